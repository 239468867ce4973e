"""Fig. 6 by grasp outcome (studies._fig6_grasp, ``fig6 --grasp``): the bench's arrays as designs, the panel's rows
from a design table, the verdict on "3x3 is best" decided only by intervals that separate, bad options refused."""

import math

import pytest

from controller.design import FingertipDesign, design_table, grasp_refusal, wilson_interval
from controller.design._evaluate import design_record
from studies import _fig6_grasp as panel


def test_the_bench_arrays_are_the_shipped_design_and_the_closed_loop_refuses_one_bump():
    designs = panel.bench_designs((1, 2, 3, 4), (1.0, 3.0))
    assert len(designs) == 8
    # the 3x3 at 3 mm is the shipped fingertip field for field (its plant and fit are the packaged design's)
    assert designs[5] == FingertipDesign()
    for design in designs:
        assert design.pitch * design.rows == pytest.approx(40.0, rel=1e-12)     # base half a pitch beyond
        assert design.bump_radius == pytest.approx(0.35 * design.pitch, rel=1e-12)
    assert "one bump" in grasp_refusal(designs[0])
    assert all(grasp_refusal(design) is None for design in designs[2:])


def _row(case: int, pitch: float, held: int, trials: int, grip=None, sd=None, status="ok", reason=""):
    low, high = wilson_interval(held, trials) if trials else (None, None)
    return dict(case=f"{case}x{case}", bumps=case * case, sensor_pitch=pitch, grasp_status=status, reason=reason,
                trials=trials, held=held if trials else None, success_rate=held / trials if trials else None,
                success_low=low, success_high=high, grip_over_slip_limit=grip, grip_over_slip_limit_sd=sd,
                translational_error_percent=10.0, bench_error_after_percent=None)


def test_the_verdict_follows_the_intervals():
    refused = _row(1, 3.0, 0, 0, status="refused", reason="one bump: no array to share the load")
    # 30/30 against 10/30: Wilson 95 % [0.886, 1] and [0.192, 0.512] do not overlap -> decided by success;
    # grip 1.20 +- 0.10 against 1.50 +- 0.10 over 30 and 10 held: Welch se sqrt(0.01/30 + 0.01/10) = 0.037,
    # the difference 0.30 is 8 se -> decided
    rows = [refused, _row(2, 3.0, 10, 30, 1.50, 0.10), _row(3, 3.0, 30, 30, 1.20, 0.10)]
    lines = panel.grasp_verdict(rows, (3.0,))
    assert lines[0].startswith("1x1 at 3 mm refused") and "one bump" in lines[0]
    assert "by success rate supported; by grip over slip limit supported" in lines[-1]
    # 29/30 against 28/30 overlap; grips 1.20 and 1.22 with sd 0.1 over ~30: 0.02 < 1.96 x 0.026 -> not decided
    rows = [_row(3, 1.0, 29, 30, 1.20, 0.10), _row(4, 1.0, 28, 30, 1.22, 0.10)]
    assert "success rate not decided; by grip over slip limit not decided" in panel.grasp_verdict(rows, (1.0,))[-1]
    # another array above the 3x3 beyond both intervals contradicts the claim; one held trial cannot decide a grip
    rows = [_row(3, 1.0, 5, 30, 1.2, None), _row(4, 1.0, 30, 30, 1.1, 0.05)]
    assert ("success rate contradicted; by grip over slip limit not decided (fewer than two held trials)"
            in panel.grasp_verdict(rows, (1.0,))[-1])


def test_the_panel_rows_come_from_the_design_table_and_keep_the_refusal():
    designs = panel.bench_designs((1, 3), (3.0,))
    low, high = wilson_interval(27, 30)
    closed = {"grasp_trials": 30, "grasp_held": 27, "grasp_success_rate": 0.9, "grasp_success_low": low,
              "grasp_success_high": high, "grasp_feasible": 30, "grasp_turned_out": 1, "grasp_dropped": 2,
              "grasp_crushed": 0, "grip_over_slip_limit": 1.25, "grip_over_slip_limit_sd": 0.08,
              "grip_over_slip_limit_max": 1.41, "translational_error": 0.12}
    records = [design_record("a", designs[0], "ok", None, {"translational_error": 0.3}, [], {}, "g",
                             {"status": "refused", "error": "one bump", "fit_key": ""}),
               design_record("b", designs[1], "ok", None, closed, [], {"trials_wall": 40.0}, "g",
                             {"status": "ok", "error": "", "fit_key": "k"})]
    bench = [dict(bumps=9, sensor_pitch=3.0, sensor="capacitive", error_after_percent=7.5),
             dict(bumps=9, sensor_pitch=3.0, sensor="cells", error_after_percent=1.0)]
    rows = panel.grasp_rows(design_table(records), bench)
    single, three = rows
    assert single["grasp_status"] == "refused" and single["reason"] == "one bump" and single["trials"] == 0
    assert single["success_rate"] is None and single["translational_error_percent"] == pytest.approx(30.0)
    assert three["held"] == 27 and three["dropped"] == 2 and three["turned_out"] == 1
    assert three["held"] + three["turned_out"] + three["dropped"] + three["crushed"] == three["trials"]
    assert three["bench_error_after_percent"] == 7.5 and three["trials_wall"] == 40.0
    figure = panel.plot_grasp(rows, [1, 3], (3.0,), 1.0)
    texts = [text.get_text() for axis in figure.axes for text in axis.texts]
    assert any(text.startswith("refused at 3 mm [1]") for text in texts)
    assert any(text.get_text() == "[1] 1x1 at 3 mm: one bump" for text in figure.texts)     # the reason, in full
    assert math.isclose(three["success_low"], low)


@pytest.mark.parametrize("argv, name", [(["--grasp", "--grasp-trials", "0"], "grasp_trials"),
                                        (["--grasp-only"], "--grasp-only"),
                                        (["--grasp", "--workers", "0"], "workers")])
def test_bad_grasp_options_are_refused_by_name(tmp_path, capsys, argv, name):
    from studies.__main__ import main

    assert main(["fig6", "--out", str(tmp_path), *argv]) == 2
    assert name in capsys.readouterr().err
    assert not list(tmp_path.iterdir())                  # refused before any solve or write
