"""The sweep study: a 2 x 2 grid on a LocalCluster, resume, a failing case, and the bad-sweep-file catalog."""

import json
import socket
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

import studies  # noqa: E402
from studies._sweep_spec import load_sweep, sweep_from_dict  # noqa: E402
from studies.sweep import run  # noqa: E402

# the HCM-1 scene as the base (path form), coarsened to CI size by quick=True: press 0.2 N, shear to 0.9 mu P
HCM1 = Path(studies.__file__).parent / "scenes" / "hcm1.toml"

GRID = f"""
scene = "{HCM1}"
outputs = ["stick_ratio@-1", "contact_radius@0", "iterations", "wall_time"]
[grid]
"material.E" = [1.0, 2.0]
"contact.friction_coefficient" = [0.5, 0.6]
"""

FAILING = f"""
scene = "{HCM1}"
outputs = ["stick_ratio@-1", "max_pressure@0"]
[list]
"load.1.force" = [0.05, 0.2]        # 0.2 N is beyond mu P = 0.1 N: refused by the solver
"""


def _write(tmp_path, sweep_text):
    path = tmp_path / "sweep.toml"
    path.write_text(sweep_text)
    return path


def _rows(out_dir):
    import pyarrow.parquet as pq

    return pq.read_table(out_dir / "sweep.parquet").to_pylist()


def test_grid_on_local_cluster_shares_prepare_and_resumes(tmp_path):
    sweep_file, out_dir = _write(tmp_path, GRID), tmp_path / "out"
    summary = run(out_dir, quick=True, sweep_file=sweep_file, scheduler="local", workers=2, quiet=True)
    assert summary["ran"] == 4 and summary["ok"] == 4
    rows = _rows(out_dir)
    assert sorted((r["material.E"], r["contact.friction_coefficient"]) for r in rows) == [(1.0, 0.5), (1.0, 0.6), (2.0, 0.5), (2.0, 0.6)]
    assert all(r["status"] == "ok" and r["error"] == "" and 0 < r["stick_ratio@-1"] < 1 for r in rows)
    # mu does not change mesh or factorization: one prepare per modulus, the other case of each E reuses it
    assert sum(r["prepared_here"] for r in rows) == 2
    assert len({r["worker"] for r in rows}) == 2                    # the two groups ran on the two workers
    assert (out_dir / "sweep.csv").read_text().count("\n") == 5
    assert (out_dir / "sweep.png").is_file() and (out_dir / "sweep.pdf").is_file()

    stamps = {p.name: p.stat().st_mtime_ns for p in (out_dir / "cases").iterdir()}
    again = run(out_dir, quick=True, sweep_file=sweep_file, scheduler="synchronous", quiet=True)
    assert again["ran"] == 0 and again["skipped"] == 4
    assert {p.name: p.stat().st_mtime_ns for p in (out_dir / "cases").iterdir()} == stamps   # nothing solved again
    lost = sorted(stamps)[0]
    (out_dir / "cases" / lost).unlink()                             # as if interrupted before this case finished
    resumed = run(out_dir, quick=True, sweep_file=sweep_file, scheduler="synchronous", quiet=True)
    assert resumed["ran"] == 1 and resumed["skipped"] == 3 and len(_rows(out_dir)) == 4


def test_failing_case_is_recorded_and_the_rest_complete(tmp_path):
    from studies.__main__ import main

    out_dir = tmp_path / "out"
    assert main(["sweep", str(_write(tmp_path, FAILING)), "--out", str(out_dir), "--scheduler", "synchronous",
                 "--quiet", "--quick"]) == 0
    ok, failed = sorted(_rows(out_dir), key=lambda r: r["status"] != "ok")
    assert ok["status"] == "ok" and ok["stick_ratio@-1"] > 0
    assert failed["status"] == "failed" and "not below friction_coefficient x P" in failed["error"]
    record = json.loads((out_dir / "cases" / f"{failed['case_id']}.json").read_text())
    assert record["status"] == "failed" and record["document"]["load"][1]["force"] == 0.2
    # the failed case stays recorded: a re-run skips it unless asked to retry
    assert run(out_dir, quick=True, sweep_file=tmp_path / "sweep.toml", scheduler="synchronous", quiet=True)["ran"] == 0
    retried = run(out_dir, quick=True, sweep_file=tmp_path / "sweep.toml", scheduler="local", workers=1,
                  quiet=True, retry_failed=True)
    assert retried["ran"] == 1 and retried["failed"] == 1
    assert (out_dir / "cases" / f"{failed['case_id']}.json.previous").is_file()      # the old record is kept


BASE = {"scene": str(HCM1), "outputs": ["stick_ratio@-1"], "grid": {"material.E": [1.0, 2.0]}}


def _check(tmp_path, **changes):
    data = {**BASE, **changes}
    return sweep_from_dict({k: v for k, v in data.items() if v is not None}, base_dir=tmp_path)


def test_valid_sweep_builds_every_case(tmp_path):
    spec = _check(tmp_path, list={"contact.friction_coefficient": [0.3, 0.5], "load.1.force": [[0.03], [0.05]]},
                  outputs=["stick_ratio@*", "wall_time"])
    assert len(spec.cases) == 4 and len({c.case_id for c in spec.cases}) == 4
    assert [o.text for o in spec.outputs] == ["stick_ratio@0", "stick_ratio@1", "wall_time"]
    example = Path(studies.__file__).parent / "sweeps" / "stick_ratio_E_mu.toml"
    assert len(load_sweep(example).cases) == 9
    assert spec.cases[3].scene.loads[1].values == (0.05,) and spec.cases[3].scene.material.E == 2.0


def test_case_id_changes_with_the_package_version(tmp_path, monkeypatch):
    import importlib.metadata

    before = [case.case_id for case in _check(tmp_path).cases]
    assert [case.case_id for case in _check(tmp_path).cases] == before           # stable for one version
    real_version = importlib.metadata.version
    monkeypatch.setattr(importlib.metadata, "version",
                        lambda name: "99.0" if name == "fingertip-contact" else real_version(name))
    after = [case.case_id for case in _check(tmp_path).cases]
    assert len(set(after)) == len(after) and not set(after) & set(before)      # an upgrade re-runs every case


@pytest.mark.parametrize("changes, match", [
    (dict(colour="red"), r"colour: unknown top-level key in the sweep file"),
    (dict(scene=None), "scene is missing"),
    (dict(scene="nowhere.toml"), r"scene='nowhere.toml': file '.*nowhere.toml' does not exist"),
    (dict(scene=3), r"scene=3 must be a file path"),
    (dict(grid={}), "the sweep has no axes"),
    (dict(grid={"material.E": []}), r"axis 'material.E' is empty"),
    (dict(grid={"material.E": 2.0}), r"axis 'material.E' must be a list"),
    (dict(grid={"material.E": [{"a": 1}]}), r"axis 'material.E': value .* is not a number"),
    (dict(grid={"material": {"E": [1.0]}}), r"'material' is a table: quote dotted keys"),
    (dict(grid={"material.Ex": [1.0]}), r"material.Ex: unknown key; allowed: \['E', 'law', 'nu'\]"),
    (dict(grid={"colour.E": [1.0]}), r"axis 'colour.E': a key is SECTION.KEY"),
    (dict(grid={"load.5.force": [1.0]}), r"axis 'load.5.force': 'load.5' is not an index"),
    (dict(grid={"material.E.x": [1.0]}), r"axis 'material.E.x': 'material.E' is a value"),
    (dict(grid={"material.E": ["soft"]}), r"material.E='soft' \(a string\) is not a number"),
    (dict(grid={"material.nu": [0.45, 0.5]}), r"material.nu=0.5 outside allowed range"),
    (dict(grid={"material.E": [1.0, 1]}), r"are the same scene: an axis repeats a value"),
    (dict(list={"material.E": [1.0]}), r"axis 'material.E' is in both \[grid\] and \[list\]"),
    (dict(list={"contact.friction_coefficient": [0.3, 0.5], "load.0.force": [0.2]}), r"\[list\] axes are zipped and need equal"),
    (dict(outputs="stick_ratio@-1"), "outputs must be a non-empty list"),
    (dict(outputs=[]), "outputs must be a non-empty list"),
    (dict(outputs=["stickiness@-1"]), r"'stickiness' is not a per-increment quantity"),
    (dict(outputs=["stick_ratio"]), r"'stick_ratio' is per increment: say which"),
    (dict(outputs=["stick_ratio@last"]), r"the increment after @ must be an integer"),
    (dict(outputs=["stick_ratio@6"]), r"increment 6 does not exist in every case"),
    (dict(outputs=["wall_time", "wall_time"]), r"'wall_time' is listed twice"),
    (dict(outputs=["colour"]), r"'colour' is not a known quantity"),
])
def test_bad_sweep_file_names_the_key(tmp_path, changes, match):
    with pytest.raises(ValueError, match=match):
        _check(tmp_path, **changes)


def test_unreachable_scheduler_names_the_address(tmp_path):
    with socket.socket() as probe:                                   # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{probe.getsockname()[1]}"
    with pytest.raises(ConnectionError, match=f"cannot reach the dask scheduler at '{address}' within 1 s"):
        run(tmp_path / "out", sweep_file=_write(tmp_path, GRID), scheduler=address, connect_timeout=1.0, quiet=True)
    with pytest.raises(ValueError, match="--scheduler 'my-cluster' is not one of 'local', 'synchronous' or a dask"):
        run(tmp_path / "out", sweep_file=tmp_path / "sweep.toml", scheduler="my-cluster", quiet=True)


def test_list_axes_are_exploded_into_typed_columns_and_plotted(tmp_path):
    import matplotlib
    import pandas as pd

    from studies._sweep_table import case_row, plot_sweep, write_table

    matplotlib.use("Agg")
    spec = _check(tmp_path, list={"contact.friction_coefficient": [0.3, 0.5], "load.1.force": [[0.05], [0.03, 0.04]]},
                  outputs=["stick_ratio@-1"])
    records = [dict(status="ok", increments=[dict(stick_ratio=0.9), dict(stick_ratio=0.5 + i)])
               for i in range(len(spec.cases))]
    rows = [case_row(case, record, spec.outputs) for case, record in zip(spec.cases, records)]
    write_table(rows, tmp_path, "table")
    frame = pd.read_parquet(tmp_path / "table.parquet")
    # one float column per item of the shear path; the shorter path has no second item (null), nothing is text
    assert str(frame["load.1.force[0]"].dtype) == "float64" and "load.1.force" not in frame
    by_mu = frame.set_index("contact.friction_coefficient")      # the first case's path is the shorter one
    assert list(by_mu.loc[0.5, "load.1.force[0]"].unique()) == [0.03]
    assert by_mu.loc[0.3, "load.1.force[1]"].isna().all() and (by_mu.loc[0.5, "load.1.force[1]"] == 0.04).all()
    figure = plot_sweep(rows, spec.axes, spec.zipped_axes, spec.outputs, "t")
    labels = {tick.get_text() for panel in figure.axes for tick in panel.get_xticklabels()}
    assert {"(0.03, 0.04)", "(0.05,)"} <= labels                      # the list axis is a labelled category
