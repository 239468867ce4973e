"""The CoP noise gate decided on pooled readings (``EstimatorSettings.gate_pool``): sizes, refusals, the fraction
of a bump's force it keeps against a closed form, and the compiled gate equal to the library's."""

import numpy as np
import pytest

from controller.closed_loop._sensing import pool_nodes
from controller.closed_loop._sensing_kernel import bump_forces_and_cops
from controller.estimation import BumpLayout, EstimatorSettings, bump_positions, gate_pool_for, gated_weights
from controller.sensing import SensorArray

NOISE = 0.001            # N per node and frame: the closed loop's nominal array
GATE = 3.0 * NOISE       # the closed loop's node floor (NOISE_GATE sigmas)


@pytest.mark.parametrize("pitch, pool", [(3.0, 1), (2.5, 1), (1.5, 3), (1.0, 3), (0.75, 5)])
def test_pool_spans_about_three_millimetres(pitch, pool):
    assert gate_pool_for(pitch) == pool


@pytest.mark.parametrize("pitch", [0.0, -1.0, float("nan")])
def test_bad_pitch_is_refused_by_name(pitch):
    with pytest.raises(ValueError, match="pitch"):
        gate_pool_for(pitch)


@pytest.mark.parametrize("pool", [0, 2, -1, True, 1.0])
def test_bad_gate_pool_is_refused_by_name(pool):
    with pytest.raises(ValueError, match="gate_pool"):
        EstimatorSettings(gate_pool=pool)


def _gaussian_bumps(array, layout, force, width, shift=0.0):
    """Noise-free node readings (ny, nx) [N] of a Gaussian pressure of ``force`` [N] and std ``width`` [mm] under
    each bump, moved by ``shift`` [mm] along x: the node reads its cell's pressure times the cell area."""
    nodes = array.node_positions                                                            # (ny, nx, 2)
    readings = np.zeros(array.shape)
    for centre in layout.centre_array:
        r2 = ((nodes - centre - (shift, 0.0)) ** 2).sum(axis=-1)
        readings += force / (2 * np.pi * width ** 2) * np.exp(-r2 / (2 * width ** 2)) * array.pitch ** 2
    return readings


def test_pooled_gate_keeps_what_a_gaussian_bump_has_above_the_pools_floor():
    """A 2D Gaussian of width s keeps 1 - g / p_peak of its force inside the level where it reads g. The node gate
    reads the bump itself at g = 3 sigma; the pool of 3 x 3 nodes reads its mean, the Gaussian smoothed by the
    pool's box (width^2 s^2 + (m^2 - 1) pitch^2 / 12), at g = 3 sigma / 3, and keeps 1 - (g / p_peak')^(s'^2 / s^2)
    of the bump. 0.5 N per bump, width 2.5 mm, a 1 mm array: 0.76 and 0.93. Tolerance: the ~2 pi r_g / pitch nodes
    along the level r_g carry about g each and fall in or out with where the grid lies, pi r_g g / (pitch F)
    (0.08 and 0.04)."""
    array = SensorArray(pitch=1.0, node_counts=(40, 40), fill_factor=1.0)
    layout = BumpLayout.grid((3, 3), 40.0 / 3.0)
    force, width = 0.5, 2.5
    readings = _gaussian_bumps(array, layout, force, width)
    whole = bump_positions(readings, array, layout, EstimatorSettings())[0][0]
    kept = {}
    for pool in (1, 3):
        floor = GATE / pool
        smoothed = width ** 2 + (pool ** 2 - 1) * array.pitch ** 2 / 12                    # s'^2 [mm^2]
        peak = force / (2 * np.pi * smoothed) * array.pitch ** 2                             # p_peak' [N per node]
        level = np.sqrt(2 * smoothed * np.log(peak / floor))                                 # r_g [mm]
        kept[pool] = bump_positions(readings, array, layout, EstimatorSettings(node_floor=GATE, gate_pool=pool))[0][0]
        np.testing.assert_allclose(kept[pool] / whole, 1 - (floor / peak) ** (smoothed / width ** 2),
                                   atol=np.pi * level * floor / (array.pitch * force))
    assert np.all(kept[3] > kept[1])


def test_an_edge_pool_sees_the_same_sigmas_of_its_own_noise():
    """Noise alone: an edge pool holds 6 nodes, an inner one 9; each is compared with 3 sigma of its own sum, so the
    share of gates that noise opens is the one-sided 3-sigma tail, 0.00135, wherever the node sits (a threshold of
    3 sigma of a full pool would be 3.7 sigma at the edge: 1.2e-4). Tolerance 3e-4: over 2000 frames the binomial
    standard error is 7e-5 on the 152 edge nodes and 2e-5 inside."""
    array = SensorArray(pitch=1.0, node_counts=(40, 40), fill_factor=1.0)
    noise = np.random.default_rng(5).normal(0.0, NOISE, (2000,) + array.shape)
    opened = gated_weights(noise, EstimatorSettings(node_floor=GATE, gate_pool=3)) != 0.0
    share = opened.mean(axis=0)
    edges = np.concatenate([share[0, 1:-1], share[-1, 1:-1], share[1:-1, 0], share[1:-1, -1]]).mean()
    inner = share[1:-1, 1:-1].mean()
    assert edges == pytest.approx(0.00135, abs=0.0003)
    assert inner == pytest.approx(0.00135, abs=0.0003)


def test_a_fine_arrays_cop_gain_does_not_collapse_with_the_node_noise():
    """The shipped fingertip read at 1 mm: the chain's CoP gain (bench shifts of 0.01 and 0.02 mm) with the gates of
    a trial whose rest frames show 0.002 N of node noise is at least half of that at 0.0005 N. Gated node by node
    it fell to 0.12 of it (0.0085 against 0.070): the rim of a 0.6 N bump is 1-3 sigmas per 1 mm node. What is left
    of the dependence is the bench's 20-frame means gated at one frame's sigma (docs/design.md sec. 13)."""
    from controller.closed_loop import SensingChain, estimator_bench
    from controller.design import FingertipDesign, SensorModel
    from controller.plant import SensorPlane, nominal_model

    array = FingertipDesign(sensor_pitch=1.0).sensor(SensorModel.CAPACITIVE)            # 40 x 40 nodes, pads 0.7
    bench = estimator_bench(SensorPlane.FEM, nominal_model(), array)
    chain = SensingChain(bench)
    rng = np.random.default_rng(0)
    gains = []
    for sigma in (0.0005, 0.002):
        chain.tare(bench.offset[None, None] + rng.normal(0.0, sigma, (40, 2, bench.offset.size)))
        gains.append(chain.calibration.gain)
    assert gains[1] > 0.5 * gains[0] > 0.0


@pytest.mark.parametrize("pool", [1, 3, 5])
def test_compiled_gate_is_the_library_gate(pool):
    """The closed loop's compiled per-bump force and CoP equal ``bump_positions`` on noisy 1 mm frames."""
    array = SensorArray(pitch=1.0, node_counts=(40, 40), fill_factor=1.0)
    layout = BumpLayout.grid((3, 3), 40.0 / 3.0)
    settings = EstimatorSettings(node_floor=GATE, gate_pool=pool)
    regions = layout.regions(array)
    region = np.where(regions.any(axis=0), regions.argmax(axis=0), -1).ravel().astype(np.int64)
    nodes = array.node_positions.reshape(-1, 2)
    rng = np.random.default_rng(3)
    for _ in range(5):
        readings = _gaussian_bumps(array, layout, rng.uniform(0.2, 2.0), 2.5, rng.uniform(-0.3, 0.3))
        readings += rng.normal(0.0, NOISE, array.shape)
        force, cop = np.empty(9), np.empty((9, 2))
        bump_forces_and_cops(readings.ravel(), region, nodes[:, 0].copy(), nodes[:, 1].copy(), GATE,
                             pool_nodes(array.shape, pool), layout.centre_array, force, cop)
        expected_force, expected_cop, _ = bump_positions(readings, array, layout, settings)
        np.testing.assert_allclose(force, expected_force[0], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(cop, expected_cop[0], rtol=0, atol=1e-12)


def test_pools_are_the_squares_around_each_node_cut_at_the_edge():
    pools = pool_nodes((4, 5), 3)
    assert pools.shape == (20, 9)
    assert sorted(pools[0][pools[0] >= 0].tolist()) == [0, 1, 5, 6]               # corner: 2 x 2 on the array
    assert sorted(pools[7].tolist()) == [1, 2, 3, 6, 7, 8, 11, 12, 13]              # inside: node (1, 2)'s square
    assert pool_nodes((4, 5), 1).ravel().tolist() == list(range(20))
