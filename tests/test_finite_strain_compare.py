"""The finite-strain study's reading of its rows (studies._finite_strain_compare): the envelope against either
Neo-Hookean reference, and the bounds a quantity gets when only the project's own finite-strain gel measured it."""

import math

import pytest

from studies._finite_strain_compare import _row, envelope, envelope_bounds


def _rows(problem, quantity, loads, linear, neo, relative=True):
    return [_row(problem, quantity, "load_ratio", load, {"fem_linear": a, "fem_neo_hooke": b}, relative, {})
            for load, a, b in zip(loads, linear, neo)]


def test_the_envelope_against_the_fems_own_gel_ends_at_its_first_miss_and_records_a_quantity_never_within():
    loads = (0.2, 0.4, 0.6, 0.8)
    rows = (_rows("bump_shear", "tangential_compliance", loads, (1.0, 1.0, 1.0, 1.0), (1.01, 1.03, 1.06, 1.02))
            + _rows("bump_shear", "base_cop_shift", loads, (1.0,) * 4, (1.3,) * 4))
    found = envelope(rows, reference="fem_neo_hooke")
    compliance = found["bump_shear:tangential_compliance"]
    # within 5 % at 0.2 and 0.4 (-1 %, -2.9 %), -5.7 % at 0.6: the first miss ends it though 0.8 is within again
    assert compliance["holds_to"] == 0.4 and compliance["first_miss"] == 0.6
    assert compliance["first_miss_error"] == pytest.approx(1.0 / 1.06 - 1.0)
    never = found["bump_shear:base_cop_shift"]
    assert never["holds_to"] is None and never["largest_error"] == pytest.approx(1.0 / 1.3 - 1.0)
    # nothing was compared with CalculiX's gel here: that envelope is empty
    assert envelope(rows) == {}


def test_a_quantity_measured_only_against_the_fems_own_gel_is_bounded_by_its_tighter_load():
    hold = _rows("bump_shear", "stick_ratio", (0.3, 0.6), (0.9, 0.7), (0.91, 0.8), relative=False)
    peak = _rows("bump_shear_peak", "stick_ratio", (0.3, 0.6), (0.9, 0.7), (0.93, 0.72), relative=False)
    cop = _rows("bump_shear", "base_cop_shift", (0.3,), (1.0,), (1.3,))
    # off at the first ratio, within after: the held contact is resolved, so the early miss is not excused
    late = _rows("bump_shear", "tangential_compliance", (0.3, 0.6), (1.0, 1.0), (1.2, 1.01))
    own = envelope(hold + peak + cop + late, reference="fem_neo_hooke")
    assert own["bump_shear:tangential_compliance"]["holds_from"] == 0.6
    bounds = {b.quantity: b for b in envelope_bounds({}, 0.52, "test run", "not run", own, 0.63)}
    # the hold holds c/a to 0.3 (0.1 off at 0.6), the peak to 0.6: the tighter ratio, at the peak's width
    assert (bounds["stick_ratio"].contact_width, bounds["stick_ratio"].load_ratio) == (0.63, 0.3)
    assert not bounds["stick_ratio"].assumed
    # outside at every ratio measured: a bound at ratio 0 at the hold's width (no peak run)
    assert (bounds["base_cop_shift"].contact_width, bounds["base_cop_shift"].load_ratio) == (0.52, 0.0)
    assert "at any Q/(mu P) measured" in bounds["base_cop_shift"].describe()
    assert bounds["tangential_compliance"].load_ratio == 0.0
    # a quantity no Neo-Hookean gel measured stays assumed, at the press's width (none here: 0)
    assert bounds["torsional_compliance"].assumed and math.isinf(bounds["torsional_compliance"].load_ratio)
