"""Caches that heal: a damaged mesh, compliance, compiled-kernel or trial-table entry is reported once with its path,
discarded and made again, and the result is the one an undamaged cache gives; an unusable FINGERTIP_CACHE gives one
warning naming the variable, and the run goes on without a cache."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

from fem import cache_dir
from fem.cache_dir import CacheWarning

SCENE = {
    "name": "healing",
    "gel": {"shape": "block", "width": 10.0, "depth": 10.0, "thickness": 5.0},
    "material": {"E": 1.0, "nu": 0.3},
    "body": {"shape": "sphere", "radius": 10.0},
    "contact": {"friction_coefficient": 0.5},
    "mesh": {"size_contact": 0.3, "size_far": 2.0},
    "load": [{"kind": "press", "force": 0.2}],
}


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    """FINGERTIP_CACHE in a new folder, and fem.cache_dir's per-process memory of probed folders and reports reset."""
    monkeypatch.setenv("FINGERTIP_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(cache_dir, "_checked", {})
    monkeypatch.setattr(cache_dir, "_reported", set())
    return tmp_path / "cache"


def _damage(path, how: str) -> None:
    data = bytearray(path.read_bytes())
    if how == "truncated":
        path.write_bytes(bytes(data[: len(data) // 2]))
    elif how == "bit flip":                     # one bit in the middle of the stored array: the zip's CRC-32 fails
        data[len(data) // 2] ^= 0x10
        path.write_bytes(bytes(data))
    else:
        path.write_bytes(b"not a cache file")


def _cache_warnings(caught) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category, CacheWarning)]


def _solve():
    from contact import scene_from_dict, solve_scene

    return solve_scene(scene_from_dict(SCENE))


@pytest.mark.parametrize("how", ["truncated", "bit flip", "garbage"])
def test_damaged_compliance_columns_are_reported_once_and_computed_again(fresh_cache, how):
    first = _solve()
    (stored,) = (fresh_cache / "compliance").glob("compliance-*.npz")
    _damage(stored, how)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again = _solve()
    messages = _cache_warnings(caught)
    assert len(messages) == 1 and str(stored) in messages[0] and "made again" in messages[0]
    assert again.timings["compliance_columns_loaded"] == 0 and again.timings["compliance_columns"] > 0
    # the same columns solved again: the same answer to round-off of the back-substitution
    assert again.increments[0].depth == pytest.approx(first.increments[0].depth, rel=1e-12)
    with warnings.catch_warnings(record=True) as caught:        # healed: the rewritten file is read back
        warnings.simplefilter("always")
        third = _solve()
    assert not _cache_warnings(caught) and third.timings["compliance_columns_loaded"] > 0


def test_a_column_set_of_another_shape_is_named_and_replaced(fresh_cache):
    from contact.compliance import ColumnCache

    _solve()
    (stored,) = (fresh_cache / "compliance").glob("compliance-*.npz")
    cache = ColumnCache(stored.parent)
    key = stored.stem.removeprefix("compliance-")
    columns, values = cache.load(key)
    cache.save(key, columns[:-1], values[:-3, :-1])         # three rows short: another compliance's columns
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = _solve()
    (message,) = _cache_warnings(caught)
    assert str(stored) in message
    assert f"{values.shape[0] - 3} rows where this compliance has {values.shape[0]}" in message
    assert result.timings["compliance_columns_loaded"] == 0


@pytest.mark.parametrize("how", ["truncated", "bit flip", "garbage"])
def test_damaged_mesh_is_reported_once_and_meshed_again(tmp_path, monkeypatch, how):
    from fem.geometry import ArrayGeometry
    from fem.tetmesh import TetMeshSpec, mesh_gel

    monkeypatch.setattr(cache_dir, "_reported", set())
    geometry = ArrayGeometry(rows=1, cols=1, bump_radius=2.0, pitch=6.0, base_width=6.0, base_depth=6.0,
                             base_thickness=1.0)
    spec = TetMeshSpec(size_contact=0.6, size_far=1.5, contact_radius=1.5)
    first = mesh_gel(geometry, spec, tmp_path)
    _damage(tmp_path / f"mesh-{first.key}.npz", how)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again = mesh_gel(geometry, spec, tmp_path)
    (message,) = _cache_warnings(caught)
    assert f"mesh-{first.key}.npz" in message and not again.from_cache
    np.testing.assert_array_equal(again.mesh.p, first.mesh.p)     # gmsh on one thread: the same mesh again
    assert mesh_gel(geometry, spec, tmp_path).from_cache          # and the healed file is read back


@pytest.mark.parametrize("how", ["index", "data"])
def test_damaged_kernel_cache_is_reported_and_compiled_again(fresh_cache, how):
    from fem import compiled

    compiled.kernel_cache_dir.cache_clear()

    def tripled(values):
        return 3.0 * values

    assert np.array_equal(compiled.njit_cached(tripled)(np.arange(3.0)), [0.0, 3.0, 6.0])
    folder = compiled.kernel_cache_dir()
    (damaged,) = folder.rglob("*tripled*.nbi" if how == "index" else "*tripled*.nbc")
    damaged.write_bytes(damaged.read_bytes()[:40])                 # a truncated write
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again = compiled.njit_cached(tripled)                      # a new dispatcher reads the disk cache
        assert np.array_equal(again(np.arange(3.0)), [0.0, 3.0, 6.0])
    (message,) = _cache_warnings(caught)
    assert "tripled" in message and str(folder) in message and "made again" in message
    healed = compiled.njit_cached(tripled)
    healed(np.arange(3.0))
    assert healed.stats.cache_hits                                 # the rewritten files load
    compiled.kernel_cache_dir.cache_clear()


@pytest.mark.parametrize("unusable", ["a file", "read-only"])
def test_unusable_cache_folder_warns_once_naming_the_variable_and_runs(tmp_path, monkeypatch, unusable):
    from fem import compiled

    target = tmp_path / "cache"
    if unusable == "a file":
        target.write_text("I am not a folder")
    else:                                   # the probe's write fails as in a read-only folder (root ignores modes)
        def refuse(*args, **kwargs):
            raise PermissionError(13, "Permission denied")

        monkeypatch.setattr(cache_dir.tempfile, "mkstemp", refuse)
    monkeypatch.setenv("FINGERTIP_CACHE", str(target))
    monkeypatch.setattr(cache_dir, "_checked", {})
    compiled.kernel_cache_dir.cache_clear()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = _solve()

        @compiled.njit_cached
        def halved(values):
            return 0.5 * values

        assert np.array_equal(halved(np.arange(3.0)), [0.0, 0.5, 1.0])
    compiled.kernel_cache_dir.cache_clear()
    messages = _cache_warnings(caught)
    assert messages and all(f"FINGERTIP_CACHE={str(target)!r} cannot hold the disk cache" in m for m in messages)
    assert len(messages) == 1                  # one for the whole cache: not per subfolder, file or kernel
    assert result.increments[0].normal_force == pytest.approx(0.2, rel=1e-8)
    assert target.is_file() if unusable == "a file" else not [p for p in target.rglob("*") if p.is_file()]


def test_command_line_runs_with_an_unusable_cache_and_says_so_once(tmp_path, monkeypatch, capsys):
    from studies.__main__ import main
    from toml_files import write_toml

    target = tmp_path / "cache-file"
    target.write_text("")
    monkeypatch.setenv("FINGERTIP_CACHE", str(target))
    monkeypatch.setattr(cache_dir, "_checked", {})
    scene = write_toml(tmp_path / "scene.toml", SCENE)
    code = main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"])
    errors = capsys.readouterr().err
    assert code == 0 and errors.count(f"FINGERTIP_CACHE={str(target)!r}") == 1 and "Traceback" not in errors


def test_damaged_trial_rows_are_skipped_with_one_warning_and_run_again(tmp_path):
    pytest.importorskip("mujoco")
    from studies._trials import TrialRowWarning, run_trial_table

    from controller.closed_loop import GraspObject, TrialSettings

    box = GraspObject("box", 0.1, (0.06, 0.05, 0.08), 0.0, 0.04)
    jobs = [(f"{k:016x}", box, TrialSettings(friction_coefficient=mu), {"mu": mu})
            for k, mu in enumerate((0.5, 0.7, 0.9))]
    path = tmp_path / "trials.csv"
    calls = []

    def row(value, info):
        calls.append(info["mu"])
        return {"mu": info["mu"], "grip": value, "required": info["required"]}

    first = run_trial_table(path, jobs, row, processes=1, function=_grip_of)
    lines = path.read_text().splitlines()
    lines[1] = lines[1].replace(",0.5,", ",0.6,")                    # an edited value
    lines[3] = lines[3][: len(lines[3]) // 2]                        # a truncated last line
    path.write_text("\n".join(lines) + "\n")
    calls.clear()
    with pytest.warns(TrialRowWarning, match=r"trials.csv': 2 of 3 row\(s\) damaged"):
        again = run_trial_table(path, jobs, row, processes=1, function=_grip_of)
    assert sorted(calls) == [0.5, 0.9] and again == first           # only the damaged trials ran, same rows
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.warns(TrialRowWarning, match="cannot be read"):
        assert run_trial_table(path, jobs, row, processes=1, function=_grip_of) == first
    calls.clear()
    assert run_trial_table(path, jobs, row, processes=1, function=_grip_of) == first and not calls   # rebuilt


def test_trial_rows_of_another_plan_are_named_before_they_are_replaced(tmp_path):
    pytest.importorskip("mujoco")
    from studies._trials import TrialRowWarning, run_trial_table

    from controller.closed_loop import GraspObject, TrialSettings

    box = GraspObject("box", 0.1, (0.06, 0.05, 0.08), 0.0, 0.04)

    def jobs(*mus):
        return [(f"{round(100 * mu):016x}", box, TrialSettings(friction_coefficient=mu), {"mu": mu}) for mu in mus]

    def row(value, info):
        return {"mu": info["mu"], "grip": value, "required": info["required"]}

    path = tmp_path / "trials.csv"
    run_trial_table(path, jobs(0.5, 0.7), row, processes=1, function=_grip_of)
    with pytest.warns(TrialRowWarning, match=r"trials.csv': 1 of its rows belong to another plan"):
        rows = run_trial_table(path, jobs(0.5, 0.9), row, processes=1, function=_grip_of)   # 0.7 is not asked for
    assert [r["mu"] for r in rows] == [0.5, 0.9] and len(path.read_text().splitlines()) == 3


def _grip_of(obj, settings):
    """A stand-in for a trial: the slip-limit grip force at twice the friction (deterministic, fast) [N]."""
    from controller.closed_loop import required_grip_force

    return required_grip_force(obj, 2.0 * settings.friction_coefficient)


@pytest.mark.parametrize("stamp", ["[]", "3", '{"outputs": 5}', '{"hash": "x", "outputs": ["fig2b.csv"]}', "{"])
def test_a_study_stamp_of_another_shape_means_run_again(tmp_path, stamp):
    from studies import all as all_studies
    from studies._registry import find_studies

    all_studies.stamp_path(tmp_path, "fig2b").parent.mkdir(parents=True)
    all_studies.stamp_path(tmp_path, "fig2b").write_text(stamp)
    (tmp_path / "fig2b.summary.json").write_text("[1, 2]")
    assert not all_studies.is_up_to_date(tmp_path, "fig2b", find_studies()["fig2b"], quick=True)
    assert all_studies.read_summary(tmp_path, "fig2b") == {}


def test_a_cache_warning_raised_while_the_studies_are_imported_is_one_line(tmp_path):
    # the cache folder is probed as the studies are imported, which came before the command line set its one-line
    # warning format: Python's own 'file:line: CacheWarning: ...' with the source line under it came out
    target = tmp_path / "cache-file"
    target.write_text("")
    done = subprocess.run([sys.executable, "-m", "studies", "fig2b", "--quick", "--out", str(tmp_path / "out")],
                          env={**os.environ, "FINGERTIP_CACHE": str(target)}, capture_output=True, text=True,
                          timeout=600)
    mentions = [line for line in done.stderr.splitlines() if "FINGERTIP_CACHE" in line]
    assert done.returncode == 0, done.stderr
    assert len(mentions) == 1 and mentions[0].startswith(f"warning: FINGERTIP_CACHE={str(target)!r}"), done.stderr
    assert "CacheWarning" not in done.stderr
