"""The convergence study's 3x3-fingertip part: cases, knee, plot marks and the run's bookkeeping; slow: one solve."""

import csv

import pytest

from studies import convergence
from studies._convergence_array import ARRAY_LOAD_RATIO, ARRAY_STUDIES, array_cases, array_scene, solve_array_case


def _row(study, size, error, wall, order=1, n_shear=1, peak_pressure_error=0.02):
    """A study row; the HCM-1 columns take ``error`` for the recovered c/a and ``wall`` for the CPU time too."""
    return dict(study=study, size_contact=size, order=order, n_shear=n_shear, dofs=int(1e4 / size), elements=1,
                compliance_columns=1, wall_time=wall, cpu_time=wall, mesh_time=0.0, stick_ratio_error=error,
                stick_ratio_error_signed=-error, final_stick_ratio_error=-error, recovered_stick_ratio_error_cm=error,
                coupled_stick_ratio_error=2 * error, recovered_stick_ratio_error=error, coupling_offset_first=-0.02,
                coupling_offset_last=-0.01, coupling_offset_largest=-0.02, contact_radius_error=0.01,
                recovered_contact_radius_error=0.005, peak_pressure_error=0.1,
                recovered_peak_pressure_error=peak_pressure_error, reference_peak_pressure_error=0.008,
                shift_error=float("nan"))


def test_knee_is_the_cheapest_row_within_the_factor_of_the_best():
    rows = [_row("s", 0.9, 0.050, 1.0), _row("s", 0.6, 0.030, 2.0), _row("s", 0.4, 0.027, 4.0),
            _row("s", 0.3, 0.026, 8.0)]
    # 0.030 > 1.15 * 0.026 = 0.0299 is out; 0.027 is in and cheaper than the best itself
    assert convergence.knee(rows, factor=1.15) is rows[2]
    assert convergence.knee(rows, factor=1.0) is rows[3]
    assert convergence.knee([]) is None


def test_array_scene_shears_in_equal_steps_to_the_final_load():
    from controller import bench as tip

    final = ARRAY_LOAD_RATIO * tip.FRICTION * tip.NORMAL_FORCE
    press, shear = array_scene(0.6, order=1, n_shear=5).loads
    assert press.values == (tip.NORMAL_FORCE,)
    assert shear.values == pytest.approx([final * k / 5 for k in range(1, 6)], rel=1e-12)   # rounding only
    quadratic = array_scene(0.6, order=2).mesh
    assert quadratic.order == 2 and quadratic.size_base == 2 * tip.BENCH_SIZE_BASE    # P1's node spacing
    with pytest.raises(ValueError, match="n_shear=0 must be an integer >= 1"):
        array_scene(0.6, n_shear=0)


def test_default_setting_leaves_the_fine_meshes_to_full():
    default, full = convergence._cases("default"), convergence._cases("full")
    sizes = {r["size_contact"] for r in default if r["study"] == convergence.SIZE_STUDY}
    assert sizes == {0.35, 0.25, 0.2, 0.14}               # the knee (0.2) with a size on each side for the rates
    assert {0.1, 0.07} <= {r["size_contact"] for r in full if r["study"] == convergence.SIZE_STUDY}
    assert len(full) > len(default)
    assert 0.3 not in {r["size_contact"] for r in array_cases(full=False)}
    assert 0.3 in {r["size_contact"] for r in array_cases(full=True)}
    with pytest.raises(ValueError, match="--quick and --full exclude each other"):
        convergence.setting_name(quick=True, full=True)


def test_full_run_marks_one_knee_per_part(tmp_path, monkeypatch):
    """run(full=True), the solves replaced: every array study is run and each part gets its own knee."""
    errors = {0.9: 0.05, 0.6: 0.03, 0.4: 0.027, 0.3: 0.026}        # array knee: h = 0.4 (cheaper than 0.3)

    def fake_array(size_contact, order, n_shear):
        return {k: v for k, v in _row("", size_contact, errors[size_contact] + 0.01 * (order - 1),
                                       10.0 / size_contact * order * n_shear).items()
                if k not in ("study", "size_contact", "order", "n_shear")}

    def fake_hcm1(size_contact, order, n_shear, reference_spacing, nu=None, volumetric=None):
        # HCM-1 knee: the cheapest mesh meeting c/a <= 0.01 and p_max within 3 %: 0.2 (0.25 misses the pressure)
        error = {0.35: 0.012, 0.25: 0.009, 0.2: 0.0097}.get(size_contact, 0.005)
        return {k: v for k, v in _row("", size_contact, error, 1.0 / size_contact,
                                       peak_pressure_error=0.039 if size_contact == 0.25 else 0.023).items()
                if k not in ("study", "size_contact", "order", "n_shear")}

    monkeypatch.setattr(convergence, "solve_array_case", fake_array)
    monkeypatch.setattr(convergence, "solve_case", fake_hcm1)
    summary = convergence.run(tmp_path, full=True)
    with open(tmp_path / "convergence.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert {r["study"] for r in rows} >= set(ARRAY_STUDIES)
    knees = sorted((r["study"], float(r["size_contact"])) for r in rows if r["knee"] == "True")
    assert knees == [(ARRAY_STUDIES[0], 0.4), ("element size (P1)", 0.2)]
    assert summary["array_knee_size_contact"] == 0.4 and summary["knee_size_contact"] == 0.2
    assert (tmp_path / "convergence.png").is_file()


def test_plot_stars_both_knees():
    rows = [_row("element size (P1)", h, e, t) for h, e, t in ((0.35, 0.03, 1.0), (0.25, 0.02, 3.0))]
    rows += [_row(study, h, e, t) for study, h, e, t in ((ARRAY_STUDIES[0], 0.9, 0.05, 5.0),
                                                         (ARRAY_STUDIES[0], 0.6, 0.04, 9.0),
                                                         (ARRAY_STUDIES[1], 0.9, 0.08, 90.0),
                                                         (ARRAY_STUDIES[2], 0.6, 0.04, 12.0))]
    figure = convergence._plot(rows, rows[1], rows[3])
    stars = [(line.get_xdata()[0], line.get_ydata()[0]) for axis in figure.axes for line in axis.get_lines()
             if line.get_marker() == "*"]
    assert stars == [(3.0, 0.02), (9.0, 0.04)]                      # HCM-1 top row first, then the array row


@pytest.mark.slow
def test_array_shear_in_one_or_two_increments_ends_at_the_same_stick_ratio():
    one, two = (solve_array_case(0.9, 1, n) for n in (1, 2))
    # force-controlled monotonic shear is path independent (Cattaneo-Mindlin); in the discrete problem one surface
    # node of tributary area ~h^2 = 0.8 mm^2 flipping moves c/a by ~0.01 over the 9 contacts (48 mm^2): allow two
    assert two["final_stick_ratio_error"] == pytest.approx(one["final_stick_ratio_error"], abs=0.02)
    assert one["dofs"] == two["dofs"]
