"""The scene runner's outputs (result.json, steps.csv, VTU), the convergence study, and the half model's symmetry."""

import csv
import dataclasses
import json

import numpy as np
import pytest

from contact.scene import ContactSpec, Load, LoadKind, Material, MeshSettings, Scene
from contact.solver import solve_scene

SMALL_SCENE = """
name = "small"
[gel]
shape = "block"
width = 20.0
depth = 20.0
thickness = 10.0
[material]
E = 1.0
nu = 0.45
[body]
shape = "sphere"
radius = 10.0
[contact]
friction_coefficient = 0.5
{contact_extra}
[mesh]
size_contact = 0.35
size_far = 4.0
[[load]]
kind = "press"
force = 0.2
[[load]]
kind = "shear"
force = [0.05, 0.08]
[[load]]
kind = "twist"
angle = [0.01]
"""


def test_run_writes_json_csv_and_vtu(tmp_path):
    import meshio

    from studies.__main__ import main

    scene = tmp_path / "small.toml"
    scene.write_text(SMALL_SCENE.format(contact_extra=""))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--vtu", "--quiet"]) == 0
    document = json.loads((tmp_path / "out" / "result.json").read_text())
    assert set(document["mesh"]) >= {"nodes", "elements", "dofs", "order"}
    assert set(document["timings"]) >= {"mesh", "assembly", "factorization", "contact", "linear_solve"}
    increments = document["increments"]
    assert [inc["load_kind"] for inc in increments] == ["press", "shear", "shear", "twist"]
    for key in ("normal_force", "tangential_force", "torque", "depth", "shift", "angle", "contact_area",
                "stick_area", "contact_radius", "stick_radius", "stick_ratio", "max_pressure", "iterations",
                "residual", "seconds"):
        assert key in increments[0]
    assert increments[1]["tangential_force"][0] == pytest.approx(0.05, rel=1e-9)
    assert increments[3]["angle"] == pytest.approx(0.01)
    with open(tmp_path / "out" / "steps.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 4 and float(rows[2]["tangential_force_x"]) == pytest.approx(0.08, rel=1e-9)
    vtu = meshio.read(tmp_path / "out" / "increment_002.vtu")
    state = vtu.point_data["contact_state"]
    assert set(np.unique(state)) <= {-1.0, 0.0, 1.0, 2.0} and np.any(state == 2.0) and np.any(state == 1.0)


def test_failed_increment_keeps_the_converged_ones_on_disk(tmp_path, failing_after_press):
    from studies.__main__ import EXIT_FAILED, main

    scene = tmp_path / "small.toml"
    scene.write_text(SMALL_SCENE.format(contact_extra=""))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == EXIT_FAILED
    document = json.loads((tmp_path / "out" / "result.json").read_text())
    assert document["status"] == "failed" and "residual history" in document["error"]
    assert [inc["load_kind"] for inc in document["increments"]] == ["press"]


def test_half_model_matches_the_full_model():
    loads = (Load(LoadKind.PRESS, "force", (0.2,)), Load(LoadKind.SHEAR, "force", (0.05, 0.08)))
    base = Scene(name="sym", material=Material(1.0, 0.45), mesh=MeshSettings(size_contact=0.35), loads=loads)
    half = solve_scene(base)
    full = solve_scene(dataclasses.replace(base, contact=ContactSpec(symmetry="off")))
    assert half.mesh_info["half_model"] and not full.mesh_info["half_model"]
    for a, b in zip(half.increments, full.increments):
        assert a.normal_force == pytest.approx(b.normal_force, rel=1e-9)
        # the two meshes differ (the full one is not refined mirror-symmetrically): agree to the discretisation
        assert a.shift[0] == pytest.approx(b.shift[0], rel=0.02)
        assert a.stick_ratio == pytest.approx(b.stick_ratio, abs=0.05)
        assert a.contact_radius == pytest.approx(b.contact_radius, rel=0.05)


def test_convergence_study_quick(tmp_path):
    from studies import convergence

    summary = convergence.run(tmp_path, quick=True)
    with open(tmp_path / "convergence.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert {row["study"] for row in rows} == {"element size (P1)", "element order (P2)", "shear increments",
                                              "element size (P1 nodal-average, nu = 0.49)"}
    assert all(float(row["wall_time"]) > 0 and float(row["cpu_time"]) > 0 for row in rows)
    p1 = [r for r in rows if r["study"] == "element size (P1)"]
    # the recovered stick ratio beats the nodal one against the same coupled reference on every P1 mesh (measured
    # 0.018 against 0.044 at h = 0.35 mm, 0.015 against 0.037 at 0.25 mm)
    assert all(float(r["recovered_stick_ratio_error"]) < float(r["coupled_stick_ratio_error"]) for r in p1)
    # the reference offset is the coupling of the one-increment frictional press at nu = 0.45 (docs/coupled_reference.md)
    assert all(-0.03 < float(r["coupling_offset_first"]) < -0.015 for r in p1)
    assert (tmp_path / "convergence.png").exists() and (tmp_path / "convergence.pdf").exists()
    # force-controlled monotonic shear is path independent (Cattaneo-Mindlin): 1 and 5 increments agree
    by_increments = {int(r["n_shear"]): float(r["final_stick_ratio_error"]) for r in rows if r["study"] == "shear increments"}
    assert by_increments[1] == pytest.approx(by_increments[5], abs=0.02)
    assert np.isfinite(summary["max_error"])


def test_benchmark_quick_writes_medians(tmp_path):
    from studies import benchmark

    benchmark.run(tmp_path, quick=True)
    summary = json.loads((tmp_path / "benchmark.json").read_text())
    # the thread settings are stated, and one thread and the default are timed side by side
    assert set(summary["thread_settings"]["environment"]) == {"MKL_NUM_THREADS", "OMP_NUM_THREADS",
                                                              "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"}
    assert list(summary["threads"]) == ["1 thread", "default threads"]
    for medians in summary["threads"].values():
        assert medians["contact_path"] > 0 and medians["linear_solve"] > 0
        assert medians["ratio_contact_to_linear"] == pytest.approx(medians["contact_path"] / medians["linear_solve"],
                                                                   rel=1e-9)


def test_thread_limit_reaches_every_pool_and_is_lifted_after():
    from threadpoolctl import threadpool_info

    from studies._threads import limited_threads, thread_settings

    before = thread_settings()["pools"]
    with limited_threads(1):
        assert {pool["internal_api"]: pool["num_threads"] for pool in threadpool_info()} == dict.fromkeys(
            thread_settings()["pools"], 1)
    assert thread_settings()["pools"] == before or set(before) < set(thread_settings()["pools"])


def test_benchmark_substeps_quick_follows_the_same_path(tmp_path):
    import csv

    from studies import benchmark

    benchmark.run(tmp_path, quick=True, substeps=True, threads="default")
    summary = json.loads((tmp_path / "benchmark_substeps.json").read_text())
    assert list(summary["threads"]) == ["default threads"] and "environment" in summary["thread_settings"]
    with open(tmp_path / "benchmark_substeps.csv") as stream:
        rows = {row["remember_substeps"]: row for row in csv.DictReader(stream)}
    # remembered sub-steps never split more coarsely than bisection found necessary, so they take at least as many
    assert int(rows["True"]["substeps"]) >= int(rows["False"]["substeps"])
    # where bisection took a coarser later step the path differs by its discretisation: 1.5e-4 of the largest
    # torque measured on this mesh, 1e-3 allowed (a different solution would differ by the twist's own size)
    assert summary["largest_torque_difference"] <= 1e-3 * summary["largest_torque"]
    timed = summary["threads"]["default threads"]
    assert timed["ratio"] == pytest.approx(timed["wall_remembered"] / timed["wall_bisected"], rel=1e-9)


def test_benchmark_factorizations_quick_agree(tmp_path):
    from studies import benchmark

    result = benchmark.run(tmp_path, quick=True, factorizations=True, threads="1")
    stored = json.loads((tmp_path / "benchmark_factorizations.json").read_text())
    summary = result["threads"]["1 thread"]
    assert stored["threads"]["1 thread"]["nodal-average saddle point"]["factor_nonzeros"] == summary[
        "nodal-average saddle point"]["factor_nonzeros"]
    # the saddle-point and the condensed factorization solve the same K: cond(K) = 7e6 on this mesh at nu = 0.4999,
    # so two backward-stable solves differ by ~cond * eps = 2e-9 of the largest entry at most (observed 4e-13)
    assert result["saddle_point_vs_condensed_max_difference"] < 1e-8
    saddle, condensed = summary["nodal-average saddle point"], summary["nodal-average condensed K"]
    # nonzeros are deterministic, unlike times: the saddle point avoids the second-neighbour coupling of B^T B
    assert saddle["matrix_nonzeros"] < condensed["matrix_nonzeros"]
    assert saddle["free_dofs"] == condensed["free_dofs"] == summary["P1 standard"]["free_dofs"]


def test_every_study_module_imports():
    import warnings

    from studies import find_studies

    with warnings.catch_warnings():
        warnings.simplefilter("error")            # the registry warns and skips a module that does not import
        names = set(find_studies())
    assert {"fig2b", "fig3b", "torsion-theory", "fig3", "fig4", "fig6", "fig9", "convergence", "run"} <= names
