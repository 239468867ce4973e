"""Same numbers on every run, nothing lost when a run fails, limits checked before the solve, ParaView outputs of
the whole gel, and the P2 contact pressure consistent with P1 and Hertz."""

import json
import os
import socket
import warnings

import meshio
import numpy as np
import pytest

from contact import (BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, PhysicalLimitError,
                     PhysicalLimitWarning, Scene, solve_scene)
from contact.limits import SLIDING_WARN, check_increment_limits, check_scene_limits
from contact.theory import hertz

BLOCK = GelSpec("block", (("width", 20.0), ("depth", 20.0), ("thickness", 10.0)))
CAP = GelSpec("cap", (("width", 16.0), ("depth", 16.0), ("base_thickness", 5.0), ("cap_radius", 4.0),
                      ("sphere_radius", 12.0)))
SCENE_TEXT = """
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
frictionless_press = true
[mesh]
size_contact = 0.4
size_far = 4.0
[[load]]
kind = "press"
force = 0.2
[[load]]
kind = "shear"
force = {shear}
"""


def _scene(gel, loads, size_contact=0.4, order=1, body=BodySpec("sphere", 10.0)):
    return Scene(name="t", gel=gel, material=Material(1.0, 0.45), body=body,
                 contact=ContactSpec(friction_coefficient=0.5, frictionless_press=True),
                 mesh=MeshSettings(size_contact=size_contact, size_far=3.0, order=order), loads=loads)


def test_a_cap_meshed_twice_from_an_empty_cache_gives_the_same_numbers(tmp_path, monkeypatch):
    # the check: fTetWild gave 1838 / 1660 / 1765 nodes and a last stick ratio 0.730 / 0.661 / 0.682
    loads = (Load(LoadKind.PRESS, "force", (0.2,)), Load(LoadKind.TWIST, "force", (0.02, 0.04)))
    results = []
    for run in range(2):
        monkeypatch.setenv("FINGERTIP_CACHE", str(tmp_path / f"cache-{run}"))
        results.append(solve_scene(_scene(CAP, loads, body=BodySpec("plane"))))
    first, second = results
    assert first.mesh_info["nodes"] == second.mesh_info["nodes"]
    np.testing.assert_array_equal(first.model.mesh.p, second.model.mesh.p)
    assert [i.stick_ratio for i in first.increments] == [i.stick_ratio for i in second.increments]
    assert len(list((tmp_path / "cache-1").glob("mesh-*.npz"))) == 1


def test_a_truncated_mesh_cache_file_is_made_again(tmp_path):
    from fem.geometry import CapGeometry
    from fem.tetmesh import TetMeshSpec, mesh_gel

    geometry, spec = CapGeometry(16.0, 16.0, 5.0, 4.0, 12.0), TetMeshSpec(0.8, 3.0, 1.0)
    made = mesh_gel(geometry, spec, tmp_path)
    path = tmp_path / f"mesh-{made.key}.npz"
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])          # a crash mid-copy, a full disk
    with pytest.warns(UserWarning, match=f"damaged cache entry .*mesh-{made.key}.npz"):
        again = mesh_gel(geometry, spec, tmp_path)
    assert not again.from_cache and mesh_gel(geometry, spec, tmp_path).from_cache     # healed, then read
    np.testing.assert_array_equal(again.mesh.p, made.mesh.p)


def _run(tmp_path, capsys, shear, *options):
    from studies.__main__ import main

    path = tmp_path / "small.toml"
    path.write_text(SCENE_TEXT.format(shear=shear))
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", *options])
    return code, capsys.readouterr().err, tmp_path / "out"


def test_a_load_the_contact_cannot_carry_keeps_the_converged_increments(tmp_path, capsys):
    # mu P = 0.1 N: the shear of 0.12 N is past gross slip; the press and the shear of 0.05 N converged before it
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "result.json").write_text('{"stale": true}')
    code, error, out = _run(tmp_path, capsys, "[0.05, 0.12]")
    assert code == 2 and "is not below friction_coefficient x P" in error and "Traceback" not in error
    document = json.loads((out / "result.json").read_text())
    assert document["status"] == "failed" and "increment 3" in document["error"] and "stale" not in document
    assert [inc["load_kind"] for inc in document["increments"]] == ["press", "shear"]
    assert len((out / "steps.csv").read_text().splitlines()) == 3                  # header and two increments


def test_an_unwritable_out_is_refused_before_the_solve(tmp_path, capsys, monkeypatch):
    import contact.solver

    monkeypatch.setattr(contact.solver, "_gel_mesh", lambda *args: pytest.fail("solved before checking --out"))
    (tmp_path / "out").write_text("a file where the folder should go")
    code, error, _ = _run(tmp_path, capsys, "[0.05]")
    assert code == 2 and "--out" in error and "is a file, not a folder" in error


def test_a_run_refused_before_any_increment_leaves_no_stale_result(tmp_path, capsys):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "result.json").write_text('{"stale": true}')
    (tmp_path / "out" / "increment_001.vtu").write_text("old")
    code, error, out = _run(tmp_path, capsys, "[0.05]".replace("0.05", "0.05]\n[[load]]\nkind = \"press\"\nforce = [1e30"))
    assert code == 2 and "past d/H = 0.5" in error
    document = json.loads((out / "result.json").read_text())
    assert document["status"] == "failed" and document["increments"] == [] and "PhysicalLimitError" in document["error"]
    assert not (out / "increment_001.vtu").exists()


def test_vtu_time_series_mirrors_the_half_model_and_names_the_states(tmp_path, capsys):
    code, _, out = _run(tmp_path, capsys, "[0.03, 0.06]", "--vtu")
    assert code == 0
    pvd = (out / "increments.pvd").read_text()
    assert [f"increment_00{n}.vtu" in pvd for n in (1, 2, 3)] == [True] * 3
    text = (out / "increment_003.vtu").read_text()
    for code_value, name in ((-1, "not_a_candidate"), (0, "open"), (1, "stick"), (2, "slip")):
        assert f'Name="contact_state_{name}" NumberOfTuples="1" format="ascii">{code_value}<' in text
    assert 'Name="mirrored_from_half_model" NumberOfTuples="1" format="ascii">1<' in text
    grid = meshio.read(out / "increment_003.vtu")
    points, tets = grid.points, grid.cells_dict["tetra"]
    assert points[:, 1].min() == -points[:, 1].max() == -10.0                    # the whole 20 mm gel
    corners = points[tets]
    assert np.all(np.linalg.det(corners[:, 1:] - corners[:, :1]) > 0.0)          # mirrored tets kept positive
    volume = np.abs(np.linalg.det(corners[:, 1:] - corners[:, :1])).sum() / 6.0
    assert volume == pytest.approx(20.0 * 20.0 * 10.0, rel=1e-12)
    # mirror images: u_y flips sign, the other components and the state are equal
    order = np.lexsort(points.T)
    mirrored = np.lexsort((points * [1.0, -1.0, 1.0]).T)
    u = grid.point_data["displacement"]
    np.testing.assert_allclose(u[mirrored] * [1.0, -1.0, 1.0], u[order], atol=1e-12)
    state = grid.point_data["contact_state"]
    np.testing.assert_array_equal(state[mirrored], state[order])
    assert {1, 2} <= set(np.unique(state))


def test_small_strain_warns_past_its_threshold_and_a_wide_contact_inside_the_envelope_does_not():
    thin = GelSpec("block", (("width", 20.0), ("depth", 20.0), ("thickness", 5.0)))
    with pytest.warns(PhysicalLimitWarning, match=r"d/H = 0.49 > 0.1"):
        notes = check_scene_limits(_scene(thin, (Load(LoadKind.PRESS, "force", (20.0,)),)))
    # a/R = 0.49 is inside the small-strain envelope measured against finite strain (a/R <= 0.52 for the press,
    # contact.envelope); tests/test_limits_envelope.py checks the note past it
    assert not any("small-strain envelope" in note for note in notes)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                                   # HCM-1's press is well inside both
        assert check_scene_limits(_scene(BLOCK, (Load(LoadKind.PRESS, "force", (0.2,)),))) == []


def test_sliding_a_sphere_past_half_its_contact_is_refused_keeping_the_increments():
    # gross slip starts at a shift of about 0.15 a here (Mindlin); 0.3 mm slides ~0.15 mm = 0.14 a, 1 mm ~0.8 a
    loads = (Load(LoadKind.PRESS, "force", (0.2,)), Load(LoadKind.SHEAR, "displacement", (0.3, 1.0)))
    with pytest.warns(PhysicalLimitWarning, match=f"> {SLIDING_WARN}\\): the small-sliding gap is approximate"):
        with pytest.raises(PhysicalLimitError, match=r"increment 3: a contact point has slid .* \(>= 0.5\)") as caught:
            solve_scene(_scene(BLOCK, loads, size_contact=0.5))
    assert [i.load_kind for i in caught.value.result.increments] == ["press", "shear", "shear"]


def test_p2_contact_pressure_is_consistent_with_p1_and_hertz():
    # before: force / four-triangle-split area read 4/3 of the pressure on edge midpoints and 0 on vertices
    loads = (Load(LoadKind.PRESS, "force", (0.2,)),)
    reference = hertz(0.2, 10.0, 1.0 / (1.0 - 0.45**2))
    a, peak = float(reference.contact_radius), 1.5 * 0.2 / (np.pi * float(reference.contact_radius) ** 2)
    results = {order: solve_scene(_scene(BLOCK, loads, size_contact=0.3, order=order)) for order in (1, 2)}
    p1, p2 = (results[order].increments[0] for order in (1, 2))
    # P1 at h = 0.3 mm = a/3.5 overshoots the centre by 20 % (a node-wise peak of a coarse patch); P2 must not do
    # worse than P1, and the recovery is exact for uniform pressure, so its peak is within h/a of Hertz's
    assert abs(p2.max_pressure / peak - 1.0) <= abs(p1.max_pressure / peak - 1.0)
    assert p2.max_pressure == pytest.approx(peak, rel=0.3 / a)
    positions = results[2].candidate_positions
    inner = np.hypot(positions[:, 0], positions[:, 1]) < 0.6 * a
    theory = peak * np.sqrt(1.0 - (np.hypot(positions[inner, 0], positions[inner, 1]) / a) ** 2)
    ratio = p2.pressure[inner] / theory
    vertex = np.isin(positions[inner].round(9).view([("", float)] * 3).ravel(),
                     results[2].model.mesh.p.T.round(9).copy().view([("", float)] * 3).ravel())
    # vertices and edge midpoints read the same pressure (they read 0 and 4/3 before), within the P1 tolerance
    assert vertex.any() and (~vertex).any()
    assert ratio[vertex].mean() == pytest.approx(ratio[~vertex].mean(), abs=0.1)
    assert ratio.mean() == pytest.approx(1.0, abs=0.1)


def test_temporary_files_of_killed_runs_are_removed(tmp_path):
    from fem.atomic import atomic_path, remove_stale_temporaries

    host = socket.gethostname().replace(".", "_")
    dead = tmp_path / f".result.json.{host}-{2**22 + 7}.abc123.tmp"        # above Linux's default pid_max
    alive = tmp_path / f".result.json.{host}-{os.getpid()}.def456.tmp"
    dead.write_text("half")
    alive.write_text("being written")
    assert remove_stale_temporaries(tmp_path) == [dead] and alive.exists()
    with atomic_path(tmp_path / "result.json") as temporary:
        assert f"{host}-{os.getpid()}" in temporary.name


def test_a_sweep_refuses_another_sweeps_out_and_reruns_an_empty_record(tmp_path):
    from studies.sweep import _read_record, run

    sweep = tmp_path / "sweep.toml"
    sweep.write_text('name = "mine"\noutputs = ["wall_time"]\nscene = "scene.toml"\n[grid]\n"material.E" = [1.0]\n')
    (tmp_path / "scene.toml").write_text(SCENE_TEXT.format(shear="[0.05]"))
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text(json.dumps({"name": "theirs", "grid": {"material.E": [1.0]}, "list": {}}))
    with pytest.raises(ValueError, match=r"holds another sweep .*'theirs'.*choose another --out"):
        run(out, sweep_file=sweep, scheduler="synchronous", quiet=True)
    record = out / "cases" / "0123456789abcdef.json"
    record.parent.mkdir()
    record.write_text("{}")
    assert _read_record(record) is None                                 # not a record: the case runs again
    record.write_text(json.dumps({"case_id": record.stem, "status": "ok", "increments": []}))
    assert _read_record(record)["status"] == "ok"


@pytest.mark.parametrize("depth, slid", [(float("nan"), 0.0), (0.1, float("inf"))])
def test_an_increment_without_a_finite_depth_or_slide_is_refused(depth, slid):
    # no number to trust is not "within the model": refused like a value past the limit, never passed on
    scene = _scene(BLOCK, (Load(LoadKind.PRESS, "force", (0.2,)),))
    with pytest.raises(PhysicalLimitError, match=r"increment 1: .*refused"):
        check_increment_limits(scene, depth, slid, 1.0, 1, None, set())
