"""Resume that never loses or duplicates: one run per --out at a time, tables rebuilt from every record on disk,
cases known by their physical case, and malformed records skipped with a warning (their cases run again)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from toml_files import write_toml

pytest.importorskip("pyarrow")

ROOT = Path(__file__).parents[1]
SCENE = {
    "name": "resume",
    "gel": {"shape": "block", "width": 8.0, "depth": 8.0, "thickness": 4.0},
    "material": {"E": 1.0, "nu": 0.3},
    "body": {"shape": "sphere", "radius": 10.0},
    "contact": {"friction_coefficient": 0.5},
    "mesh": {"size_contact": 0.4, "size_far": 2.0},
    "load": [{"kind": "press", "force": 0.2}, {"kind": "shear", "force": [0.02], "direction": [1.0, 0.0]}],
}


# --- one run per --out ----------------------------------------------------------------------------------------------

def test_a_second_run_into_a_busy_out_is_refused_naming_the_owner(tmp_path):
    from fem.run_lock import LOCK_NAME, OutDirBusy, hold_out_dir

    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK_NAME).write_text(json.dumps({"host": __import__("socket").gethostname().replace(".", "_"),
                                                      "pid": sleeper.pid, "started": "now", "command": "sweep x"}))
        with pytest.raises(OutDirBusy, match=rf"is in use by another run \(sweep x, pid {sleeper.pid} on .*\): wait "
                                             rf"for it to finish or choose another --out; if that run is gone, delete"):
            with hold_out_dir(tmp_path):
                pass
    finally:
        sleeper.kill()
        sleeper.wait()
    with hold_out_dir(tmp_path, "mine") as held:             # its owner is gone: the stale lock is taken over
        assert json.loads((held / LOCK_NAME).read_text())["pid"] == os.getpid()
        with hold_out_dir(tmp_path):                         # the same process may enter again
            pass
        assert (held / LOCK_NAME).exists()
    assert not (tmp_path / LOCK_NAME).exists()               # released at the end


def test_concurrent_sweep_into_the_same_out_exits_2(tmp_path):
    from fem.run_lock import hold_out_dir

    sweep = write_toml(tmp_path / "sweep.toml", {"scene": SCENE, "outputs": ["wall_time"],
                                                 "grid": {"material.E": [1.0, 2.0]}})
    with hold_out_dir(tmp_path / "out", "the first sweep"):
        done = subprocess.run([sys.executable, "-m", "studies", "sweep", str(sweep), "--out", str(tmp_path / "out"),
                               "--scheduler", "synchronous", "--quiet"], capture_output=True, text=True, cwd=ROOT,
                              timeout=300)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"is in use by another run (the first sweep, pid {os.getpid()}" in done.stderr
    assert not (tmp_path / "out" / "cases").exists() or not any((tmp_path / "out" / "cases").iterdir())


# --- the scene sweep: identity from the physical case, malformed records ------------------------------------------

def _sweep(tmp_path, name: str, direction, extra=None, force=(0.02,)) -> Path:
    scene = json.loads(json.dumps(SCENE))
    scene["load"][1]["direction"] = direction
    scene["load"][1]["force"] = list(force) if isinstance(force, tuple) else force
    scene.update(extra or {})
    return write_toml(tmp_path / f"{name}.toml", {"name": "resume", "scene": scene, "outputs": ["stick_ratio@-1"],
                                                  "grid": {"material.E": [1.0, 2.0]}})


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    from studies.sweep import run

    folder = tmp_path_factory.mktemp("sweep")
    summary = run(folder / "out", sweep_file=_sweep(folder, "first", [1.0, 0.0]), scheduler="synchronous",
                  quiet=True)
    assert summary["ran"] == 2 and summary["ok"] == 2
    return folder


def test_the_same_physical_case_written_otherwise_is_not_solved_again(swept, monkeypatch):
    import contact.solver
    from studies.sweep import run

    monkeypatch.setattr(contact.solver, "prepare", lambda *a, **k: pytest.fail("a recorded case was solved again"))
    # the direction [2, 0] is [1, 0]; a load given as one value or a list of one, a default written out: one case
    other = _sweep(swept, "second", [2.0, 0.0], {"contact": {"friction_coefficient": 0.5, "symmetry": "auto"}},
                   force=0.02)
    summary = run(swept / "out", sweep_file=other, scheduler="synchronous", quiet=True)
    assert summary["skipped"] == 2 and summary["ran"] == 0


@pytest.mark.parametrize("damage", ["{", "shape", "increments"])
def test_a_malformed_record_is_skipped_with_a_warning_and_its_case_runs_again(swept, tmp_path, damage):
    import shutil

    from fem.task_runner import RecordWarning
    from studies.sweep import run

    out = tmp_path / "out"
    shutil.copytree(swept / "out", out)
    record = sorted((out / "cases").glob("*.json"))[0]
    document = json.loads(record.read_text())
    if damage == "shape":
        document["increments"] = "all of them"
    elif damage == "increments":
        document["increments"][0] = ["not", "a", "row"]
    text = json.dumps(document) if damage in ("shape", "increments") else damage
    record.write_text(text)
    with pytest.warns(RecordWarning, match=rf"1 case record\(s\) in .* skipped, their cases run again: {record.name}"):
        summary = run(out, sweep_file=_sweep(swept, "first", [1.0, 0.0]), scheduler="synchronous", quiet=True)
    assert summary["ran"] == 1 and summary["skipped"] == 1 and summary["ok"] == 2
    assert json.loads(record.read_text())["status"] == "ok"                        # rewritten whole


def test_an_unreadable_sweep_json_is_written_again_not_a_reason_to_delete(swept, tmp_path):
    import shutil

    from studies.sweep import run

    out = tmp_path / "out"
    shutil.copytree(swept / "out", out)
    (out / "sweep.json").write_text('{"name": "resu')                               # a killed write
    with pytest.warns(UserWarning, match="sweep.json' is unreadable .*written again"):
        summary = run(out, sweep_file=_sweep(swept, "first", [1.0, 0.0]), scheduler="synchronous", quiet=True)
    assert summary["skipped"] == 2 and json.loads((out / "sweep.json").read_text())["name"] == "resume"


# --- the design sweep: the table holds every recorded design, whichever run computed it ---------------------------

def test_a_resumed_design_run_killed_while_writing_keeps_every_recorded_design(tmp_path, monkeypatch):
    import pyarrow.parquet as pq

    from controller.design import DesignStudy, FingertipDesign, design_id
    import fem.task_runner as sweep_module
    from controller.design._evaluate import design_record
    from studies import design

    study = DesignStudy(size_contact=0.7, size_base=1.5, noise_draws=2)
    pitches = [3.0, 2.5, 2.0, 1.5]
    designs = [FingertipDesign(sensor_pitch=pitch) for pitch in pitches]
    cases = tmp_path / "out" / "cases"
    cases.mkdir(parents=True)
    metrics = {"translational_error": 0.1, "stick_ratio_drop": 5.0, "torque_capacity": 10.0,
               "rotational_error": 0.2, "combined_torque_capacity": 8.0}

    def record(design_):
        return design_record(design_id(design_, study), design_, "ok", None, dict(metrics), [], {}, "g0")

    for design_ in designs[:3]:                             # three designs computed by an earlier run
        (cases / f"{design_id(design_, study)}.json").write_text(json.dumps(record(design_)))

    def one_more(tasks, iterate, payload, crashed, cases_dir, on_record, client=None):
        (case,) = [case for task in tasks for case in task]
        on_record(case, record(case.design))                # the fourth arrives, then the run is killed

    monkeypatch.setattr(sweep_module, "run_tasks", one_more)
    real = design.write_tables

    def killed_after_writing(records, out_dir):
        real(records, out_dir)
        raise KeyboardInterrupt

    monkeypatch.setattr(design, "write_tables", killed_after_writing)
    path = write_toml(tmp_path / "designs.toml", {"name": "pitches", "study": {"size_contact": 0.7, "size_base": 1.5,
                                                                                "noise_draws": 2},
                                                  "grid": {"sensor_pitch": pitches}})
    with pytest.raises(KeyboardInterrupt):
        design.run(tmp_path / "out", design_file=path, scheduler="synchronous", quiet=True)
    table = pq.read_table(tmp_path / "out" / "design.parquet").to_pandas()
    assert sorted(table["sensor_pitch"]) == sorted(pitches)          # 4 rows: the 3 on disk and the new one
    assert not (tmp_path / "out" / ".run.lock").exists()             # released on the way out


def test_a_design_record_of_another_shape_is_skipped_and_run_again(tmp_path, monkeypatch):
    from controller.design import DesignStudy, FingertipDesign, design_id, design_sweep
    import fem.task_runner as sweep_module
    from controller.design._evaluate import design_record
    from fem.task_runner import RecordWarning

    study = DesignStudy(size_contact=0.7, size_base=1.5, noise_draws=2)
    good, other = FingertipDesign(), FingertipDesign(sensor_pitch=2.0)
    cases = tmp_path / "cases"
    cases.mkdir()
    wrong = design_record(design_id(good, study), other, "ok", None, {"torque_capacity": 1.0}, [], {}, "")
    (cases / f"{design_id(good, study)}.json").write_text(json.dumps(wrong))        # another design's fields
    ran = []

    def run_tasks(tasks, iterate, payload, crashed, cases_dir, on_record, client=None):
        for case in (case for task in tasks for case in task):
            ran.append(case.design)
            on_record(case, design_record(case.case_id, case.design, "ok", None, {"torque_capacity": 2.0}, [], {},
                                          ""))

    monkeypatch.setattr(sweep_module, "run_tasks", run_tasks)
    with pytest.warns(RecordWarning, match="the record's design is not this case's"):
        table = design_sweep([good], study, out_dir=tmp_path, scheduler="synchronous", progress=False)
    assert ran == [good] and table.loc[0, "torque_capacity"] == 2.0
