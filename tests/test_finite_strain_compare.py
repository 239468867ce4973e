"""The finite-strain study's reading of its rows (studies._finite_strain_compare): the envelope against each
Neo-Hookean reference, and the bounds a quantity gets from GetFEM's gel or, without it, the project's own."""

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


def test_getfems_gel_bounds_a_quantity_before_the_fems_own_but_not_the_stick_ratios():
    def rows(problem, quantity, loads, values, relative=True):
        return [_row(problem, quantity, "load_ratio", load, dict(zip(("fem_linear", "fem_neo_hooke", "getfem_linear",
                                                                       "getfem_neo_hooke"), v)), relative, {})
                for load, v in zip(loads, values)]

    # the linear FEM within 5 % of the FEM's own gel at both ratios, outside GetFEM's at 0.6 (-9 %)
    compliance = rows("bump_shear", "tangential_compliance", (0.3, 0.6),
                      ((1.0, 1.01, 1.0, 1.02), (1.0, 1.02, 1.0, 1.1)))
    # GetFEM's stick ratio reads low: it is reported, not judged, and the FEM's own gel bounds the quantity
    stick = rows("bump_shear", "stick_ratio", (0.3, 0.6), ((0.9, 0.91, 0.8, 0.81), (0.7, 0.8, 0.6, 0.62)),
                 relative=False)
    assert math.isnan(stick[0]["judged_error_getfem"])
    assert stick[0]["error_fem_neo_hooke_vs_getfem_neo_hooke"] == pytest.approx(0.1)
    own = envelope(compliance + stick, reference="fem_neo_hooke")
    independent = envelope(compliance + stick, reference="getfem_neo_hooke")
    assert "bump_shear:stick_ratio" not in independent
    bounds = {b.quantity: b for b in envelope_bounds({}, 0.52, "test run", "not run", own, None, independent)}
    assert bounds["tangential_compliance"].load_ratio == 0.3 and "GetFEM" in bounds["tangential_compliance"].measured
    assert bounds["stick_ratio"].load_ratio == 0.3 and "project's" in bounds["stick_ratio"].measured
    # without GetFEM's envelope the FEM's own gel bounds the compliance too
    fallback = {b.quantity: b for b in envelope_bounds({}, 0.52, "test run", "not run", own, None)}
    assert fallback["tangential_compliance"].load_ratio == 0.6
    assert "project's Neo-Hookean gel" in fallback["tangential_compliance"].measured


def test_a_model_that_stops_early_leaves_nan_past_its_last_ratio_not_fewer_rows():
    from studies._finite_strain_compare import shear_rows

    def path(ratios, cop_gain):       # the pressed state, then increments at the load ratios Q/(mu P), P = 1 N
        return [dict(normal_force=1.0, tangential_force=0.0, shift=0.0, stick_ratio=1.0, base_cop_x=0.0)] + [
            dict(normal_force=1.0, tangential_force=q, shift=1.8 * q, stick_ratio=1.0 - q, base_cop_x=cop_gain * q)
            for q in ratios]

    rows = shear_rows(path((0.2, 0.4, 0.6, 0.8), 5.0), {"fem_neo_hooke": path((0.2, 0.4, 0.6, 0.8), 6.0),
                                                        "getfem_neo_hooke": path((0.2, 0.4), 6.0)}, 1.0)
    cop = [r for r in rows if r["quantity"] == "base_cop_shift"]
    assert [r["load"] for r in cop] == [0.2, 0.4, 0.6, 0.8]
    assert [math.isnan(r["getfem_neo_hooke"]) for r in cop] == [False, False, True, True]
    assert cop[-1]["error_fem_vs_fem_neo_hooke"] == pytest.approx(5.0 / 6.0 - 1.0)


def test_a_model_that_starts_above_the_fems_first_ratio_leaves_nan_there_not_its_first_value():
    from studies._finite_strain_compare import shear_rows

    def path(ratios, cop_gain):       # the pressed state, then increments at the load ratios Q/(mu P), P = 1 N
        return [dict(normal_force=1.0, tangential_force=0.0, shift=0.0, stick_ratio=1.0, base_cop_x=0.0)] + [
            dict(normal_force=1.0, tangential_force=q, shift=1.8 * q, stick_ratio=1.0 - q, base_cop_x=cop_gain * q)
            for q in ratios]

    rows = shear_rows(path((0.2, 0.4, 0.6), 5.0), {"getfem_neo_hooke": path((0.3, 0.4, 0.6), 6.0)}, 1.0)
    cop = [r for r in rows if r["quantity"] == "base_cop_shift"]
    # np.interp alone would repeat the model's value at 0.3 (1.8 mm) at 0.2, a load it never reached
    assert math.isnan(cop[0]["getfem_neo_hooke"])
    assert cop[1]["getfem_neo_hooke"] == pytest.approx(6.0 * 0.4)
