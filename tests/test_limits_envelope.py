"""The small-strain envelope measured against a finite-strain gel (contact.envelope) as the limits use it: before a
run (check_scene_limits), on each increment (check_increment_limits) and for the reduced model's bump forces."""

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from contact import BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, PhysicalLimitWarning, Scene
from contact.envelope import SMALL_STRAIN_ENVELOPE, SMALL_STRAIN_TOLERANCE, outside_envelope
from contact.limits import check_increment_limits, check_scene_limits, estimated_contact

LAYER = GelSpec("block", (("width", 60.0), ("depth", 60.0), ("thickness", 30.0)))
SPHERE_RADIUS = 10.0          # mm
E_STAR = 1.0 / (1.0 - 0.45**2)


def _scene(loads):
    return Scene(name="envelope", gel=LAYER, material=Material(1.0, 0.45), body=BodySpec("sphere", SPHERE_RADIUS),
                 contact=ContactSpec(friction_coefficient=0.5, frictionless_press=True),
                 mesh=MeshSettings(size_contact=0.4, size_far=3.0), loads=loads)


def _force_for_width(width: float) -> float:
    """Hertz force [N] whose contact radius is width * R: a^3 = 3 P R / (4 E*)."""
    return 4.0 * E_STAR * (width * SPHERE_RADIUS) ** 3 / (3.0 * SPHERE_RADIUS)


def _press_bounds():
    return [bound for bound in SMALL_STRAIN_ENVELOPE if bound.load == "press"]


def test_every_bound_is_a_toleranced_quantity_under_a_known_load():
    assert _press_bounds() and {"shear", "twist"} <= {bound.load for bound in SMALL_STRAIN_ENVELOPE}
    for bound in SMALL_STRAIN_ENVELOPE:
        assert bound.quantity in SMALL_STRAIN_TOLERANCE and bound.load in ("press", "shear", "twist")
        # a load ratio of 0: outside at every ratio measured (the base pressure's centre under shear)
        assert 0.0 < bound.contact_width < 1.0 and bound.load_ratio >= 0.0 and bound.measured
        # a press bound has no load ratio; an assumed shear or twist bound (not measured) only a contact width
        assert (bound.load == "press" or bound.assumed) == math.isinf(bound.load_ratio)


@pytest.mark.parametrize("bound", SMALL_STRAIN_ENVELOPE, ids=lambda b: f"{b.load}:{b.quantity}")
def test_a_state_just_past_a_bound_leaves_it_and_one_just_inside_does_not(bound):
    # 1 % either side of the bound's contact width and load ratio: the comparison is strict, no tolerance needed
    ratio = 0.0 if bound.load == "press" else bound.load_ratio
    shear, twist = (ratio, 0.0) if bound.load == "shear" else (0.0, ratio)
    assert bound not in outside_envelope(0.99 * bound.contact_width, 0.99 * shear, 0.99 * twist)
    assert bound in outside_envelope(1.01 * bound.contact_width, 0.99 * shear, 0.99 * twist)   # wider: untested
    if math.isfinite(bound.load_ratio):
        assert bound in outside_envelope(0.99 * bound.contact_width, 1.01 * shear + 0.01 * (bound.load == "shear"),
                                         1.01 * twist + 0.01 * (bound.load == "twist"))


def test_a_path_is_judged_only_by_the_loads_it_has():
    past = outside_envelope(0.99, 0.99, 0.99, loads=("press",))
    assert past and {bound.load for bound in past} == {"press"}


def test_a_press_past_the_envelope_warns_before_meshing_naming_the_quantity_and_the_note():
    tightest = min(_press_bounds(), key=lambda bound: bound.contact_width)
    force = _force_for_width(1.05 * tightest.contact_width)
    scene = _scene((Load(LoadKind.PRESS, "force", (force,)),))
    assert estimated_contact(scene)[0] / SPHERE_RADIUS == pytest.approx(1.05 * tightest.contact_width, rel=1e-9)
    with pytest.warns(PhysicalLimitWarning, match="docs/finite_strain.md"):
        notes = check_scene_limits(scene)
    envelope_notes = [note for note in notes if "small-strain envelope" in note]
    assert len(envelope_notes) == 1 and tightest.quantity.replace("_", " ") in envelope_notes[0]
    inside = _scene((Load(LoadKind.PRESS, "force", (_force_for_width(0.95 * tightest.contact_width),)),))
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        assert not any("small-strain envelope" in note for note in check_scene_limits(inside))


def test_a_planned_shear_past_its_bound_warns_before_meshing():
    measured = [bound for bound in SMALL_STRAIN_ENVELOPE if bound.load == "shear" and not bound.assumed]
    if not measured:
        pytest.skip("no shear bound was measured against finite strain (docs/finite_strain.md, sec. 1)")
    shear = min(measured, key=lambda b: b.load_ratio)
    force = _force_for_width(0.5 * shear.contact_width)            # a contact well inside every press bound
    tangential = min(1.0, max(1.05 * shear.load_ratio, 0.05)) * 0.5 * force   # mu = 0.5; a bound at 0: any shear
    scene = _scene((Load(LoadKind.PRESS, "force", (force,)), Load(LoadKind.SHEAR, "force", (tangential,))))
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        notes = check_scene_limits(scene)
    expected = shear.load_ratio < 1.0 / 1.05                       # a bound at gross slip cannot be passed
    assert any(shear.quantity.replace("_", " ") in note and "Q/(mu P)" in note for note in notes) == expected


def test_a_shear_or_twist_not_measured_is_bounded_by_the_press():
    press = min(bound.contact_width for bound in _press_bounds())
    for bound in SMALL_STRAIN_ENVELOPE:
        if bound.assumed:
            assert bound.load in ("shear", "twist") and bound.contact_width == press
            assert "not measured" in bound.describe() and bound in outside_envelope(1.01 * press, 0.1, 0.1)


def test_each_quantity_warns_once_along_a_path():
    press = min(_press_bounds(), key=lambda bound: bound.contact_width)
    scene = _scene((Load(LoadKind.PRESS, "force", (1.0,)),))
    radius = 1.02 * press.contact_width * SPHERE_RADIUS
    increment = SimpleNamespace(contact_radius=radius, normal_force=1.0, tangential_force=(0.0, 0.0), torque=0.0)
    result = SimpleNamespace(increments=[increment])
    warned = set()
    with pytest.warns(PhysicalLimitWarning, match=r"increment 1: a/R = .*docs/finite_strain.md") as caught:
        check_increment_limits(scene, 0.1, 0.0, radius, 1, result, warned)
    assert press.quantity in warned and sum("small-strain envelope" in str(w.message) for w in caught) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")                              # the same state again: no second warning
        check_increment_limits(scene, 0.1, 0.0, radius, 2, result, warned)


def test_reduced_model_bump_forces_are_named_against_calibration_and_envelope():
    from contact.reduced import calibrated_bump_forces, check_bump_forces, load_calibration

    stored = load_calibration()
    fitted, checked = calibrated_bump_forces(stored)
    # the shipped calibration: plate presses of 1-6 N over nine bumps fitted, 10 N held out
    assert (fitted, checked) == pytest.approx((6.0 / 9.0, 10.0 / 9.0), rel=1e-12)
    assert check_bump_forces(0.5 * fitted, stored) == []
    assert "fitted FEM paths" in check_bump_forces(0.5 * (fitted + checked), stored)[0]
    notes = check_bump_forces(2.6, stored)                           # the closed loop's peak bump force
    assert "held-out FEM paths" in notes[0]
    width = stored.parameters.radius_coefficient * 2.6 ** (1.0 / 3.0) / stored.design.bump_radius
    past = [bound for bound in _press_bounds() if width > bound.contact_width]
    assert (len(notes) == 2) == bool(past)
    if past:
        assert all(bound.quantity.replace("_", " ") in notes[1] for bound in past)


@pytest.mark.parametrize("touching", [9, 3])
@pytest.mark.parametrize("scale", [0.95, 1.05])
def test_an_array_is_judged_by_each_bumps_contact_not_by_its_whole_area(scale, touching):
    # the 3x3 bench fingertip: the increment's contact radius is that of the touching bumps' area together; each bump
    # is judged by its own (contact.bumps), so only a bump past the press bound warns, however many bumps touch
    from controller.estimation.bench import bench_scene

    scene = bench_scene(3, "shift", (0.05,), 0.7, 1.5)
    press = min(_press_bounds(), key=lambda bound: bound.contact_width)
    bump_radius = scene.gel.curvature_radius
    own = np.where(np.arange(9) < touching, scale * press.contact_width * bump_radius, 0.0)
    force = np.where(own > 0, 1.0, 0.0)
    bumps = SimpleNamespace(contact_radius=own, normal_force=force, tangential_force=np.zeros((9, 2)),
                            spin_torque=np.zeros(9))
    whole = math.sqrt(touching) * own.max()                                 # sqrt(total area / pi)
    increment = SimpleNamespace(contact_radius=whole, normal_force=force.sum(), tangential_force=(0.0, 0.0),
                                torque=0.0, bumps=bumps)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_increment_limits(scene, 0.5, 0.0, whole, 1, SimpleNamespace(increments=[increment]), set())
    envelope = [str(w.message) for w in caught if "small-strain envelope" in str(w.message)]
    assert bool(envelope) == (scale > 1.0)
    assert all(f"widest of {touching} touching bumps" in message for message in envelope)
