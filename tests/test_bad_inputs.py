"""A catalogue of bad scene and sweep files: each is refused before any solve with a message naming the key, its
value and what is allowed, and on the command line with exit code 2 and no traceback. Strict types: a string or a
bool where a number belongs, a number where a bool belongs, a float where an integer belongs are all errors."""

import math
import subprocess
import sys
from pathlib import Path

import pytest

from contact.scene import load_scene
from studies._sweep_spec import load_sweep
from toml_files import DELETE, edited, to_toml

ROOT = Path(__file__).parents[1]

BASE_SCENE = {
    "name": "catalogue",
    "gel": {"shape": "block", "width": 20.0, "depth": 20.0, "thickness": 10.0},
    "material": {"E": 1.0, "nu": 0.45},
    "body": {"shape": "sphere", "radius": 10.0},
    "contact": {"friction_coefficient": 0.5},
    "mesh": {"size_contact": 0.3, "size_far": 4.0},
    "load": [{"kind": "press", "force": 0.2}, {"kind": "shear", "force": [0.02, 0.04]}],
}
CAP = {"shape": "cap", "width": 24.0, "depth": 24.0, "base_thickness": 8.0, "cap_radius": 6.0, "sphere_radius": 20.0}
ARRAY = {"shape": "array", "rows": 2, "cols": 2, "bump_radius": 2.0, "pitch": 6.0, "base_width": 20.0,
         "base_depth": 20.0, "base_thickness": 3.0}
FLAT = {"shape": "flat_cap", "width": 20.0, "depth": 20.0, "base_thickness": 4.0, "cap_radius": 3.0,
        "flat_radius": 1.0, "edge_radius": 5.0}


# (edits, expected message): one bad input each, unless the entry says otherwise
SCENES = [
    ([(("gel", "shape"), "sponge")], r"gel.shape='sponge' is not one of \['block', 'cap', 'flat_cap', 'array'\]"),
    ([(("gel", "shape"), 3)], r"gel.shape=3 is not one of"),
    ([(("gel", "width"), -1.0)], r"gel.width=-1.0 outside allowed range \(0.0, inf\) mm"),
    ([(("gel", "width"), 0.0)], r"gel.width=0.0 outside allowed range"),
    ([(("gel", "width"), True)], r"gel.width=True \(a bool\) is not a number \[mm\]"),
    ([(("gel", "width"), "20")], r"gel.width='20' \(a string\) is not a number"),
    ([(("gel", "width"), math.nan)], r"gel.width=nan outside allowed range"),
    ([(("gel", "depth"), math.inf)], r"gel.depth=inf outside allowed range"),
    ([(("gel", "thickness"), [1.0, 2.0])], r"gel.thickness=\[1.0, 2.0\] \(a list\) is not a number"),
    ([(("gel", "colour"), 1.0)], r"gel: unknown key\(s\) \['colour'\] for shape 'block'"),
    ([(("gel",), "block")], r"\[gel\] must be a table, got 'block' \(a string\)"),
    ([(("gel",), DELETE)], r"scene is missing \[gel\]"),
    ([(("gel",), dict(CAP, cap_radius=25.0, sphere_radius=20.0, width=60.0, depth=60.0))],
     r"gel.cap_radius=25.0 outside allowed range \(0.0, 20.0\] mm \(a spherical cap is at most a hemisphere"),
    ([(("gel",), dict(CAP, exponent=4.0))], r"gel.power_law_height=None: a power-law cap"),
    ([(("gel",), dict(CAP, exponent=0.5, power_law_height=1.0))], r"gel.exponent=0.5 outside allowed range"),
    ([(("gel",), dict(CAP, cap_radius=13.0))], r"gel.cap_radius=13.0 outside allowed range .*fit inside the base"),
    ([(("gel",), dict(ARRAY, rows=1.5))], r"gel.rows=1.5 is not an integer \(allowed: 1 to 12\)"),
    ([(("gel",), dict(ARRAY, rows=0))], r"gel.rows=0 outside allowed range \[1, 12\]"),
    ([(("gel",), dict(ARRAY, cols=True))], r"gel.cols=True \(a bool\) is not an integer"),
    ([(("gel",), dict(ARRAY, pitch=3.0))], r"gel.pitch=3.0 outside allowed range .*bumps overlap"),
    ([(("gel",), dict(ARRAY, base_width=9.0))], r"gel.base_width=9.0 outside allowed range .*overhang the base"),
    ([(("gel",), dict(ARRAY, fillet=-0.5))], r"gel.fillet=-0.5 outside allowed range"),
    ([(("gel",), dict(FLAT, flat_radius=4.0))], r"gel.flat_radius=4.0 outside allowed range .*below cap_radius"),
    ([(("gel",), dict(FLAT, edge_radius="round"))], r"gel.edge_radius='round' \(a string\) is not a number"),
    ([(("material", "E"), -1.0)], r"material.E=-1.0 outside allowed range \(0.0, inf\) MPa"),
    ([(("material", "E"), 0)], r"material.E=0 outside allowed range"),
    ([(("material", "E"), "1.0")], r"material.E='1.0' \(a string\) is not a number \[MPa\]"),
    ([(("material", "E"), True)], r"material.E=True \(a bool\) is not a number"),
    ([(("material", "E"), math.inf)], r"material.E=inf outside allowed range"),
    ([(("material", "nu"), 0.5)], r"material.nu=0.5 outside allowed range \(-1.0, 0.5\)"),
    ([(("material", "nu"), -1.0)], r"material.nu=-1.0 outside allowed range"),
    ([(("material", "nu"), "0.45")], r"material.nu='0.45' \(a string\) is not a number"),
    ([(("material", "nu"), math.nan)], r"material.nu=nan outside allowed range"),
    ([(("material", "G"), 1.0)], r"material.G: unknown key; allowed: \['E', 'law', 'nu'\]"),
    ([(("material", "law"), "rubber")], r"material.law='rubber'"),
    ([(("material",), DELETE)], r"scene is missing \[material\]"),
    ([(("material",), 1.0)], r"\[material\] must be a table, got 1.0"),
    ([(("body", "shape"), "cube")], r"body.shape='cube' is not one of \['sphere', 'plane'\]"),
    ([(("body", "radius"), 0.0)], r"body.radius=0.0 outside allowed range"),
    ([(("body", "radius"), "big")], r"body.radius='big' \(a string\) is not a number"),
    ([(("body", "center"), [0.0])], r"body.center=\(0.0,\) \(a list\) must be two numbers \[x, y\] in mm"),
    ([(("body", "center"), [0.0, "a"])], r"body.center\[1\]='a' \(a string\) is not a number"),
    ([(("body", "center"), "origin")], r"body.center='origin' \(a string\) must be two numbers"),
    ([(("body",), DELETE)], r"scene is missing \[body\]"),
    ([(("body", "colour"), "red")], r"body.colour: unknown key"),
    ([(("contact", "mu"), 0.5), (("contact", "friction_coefficient"), DELETE)],
     r"contact.mu was renamed contact.friction_coefficient: write friction_coefficient = 0.5"),
    ([(("contact", "friction_coefficient"), -0.1)], r"contact.friction_coefficient=-0.1 outside allowed range"),
    ([(("contact", "friction_coefficient"), 6.0)], r"contact.friction_coefficient=6.0 outside allowed range \[0.0, 5.0\]"),
    ([(("contact", "friction_coefficient"), "0.5")], r"contact.friction_coefficient='0.5' \(a string\) is not a number"),
    ([(("contact", "friction_coefficient"), True)], r"contact.friction_coefficient=True \(a bool\) is not a number"),
    ([(("contact", "frictionless_press"), "no")], r"contact.frictionless_press='no' \(a string\) is not a bool: write "
                                                  r"true or false"),
    ([(("contact", "frictionless_press"), 0)], r"contact.frictionless_press=0 is not a bool"),
    ([(("contact", "frictionless_press"), 1.0)], r"contact.frictionless_press=1.0 is not a bool"),
    ([(("contact", "tolerance"), 0.0)], r"contact.tolerance=0.0 outside allowed range \[1e-13, 0.001\]"),
    ([(("contact", "tolerance"), 1.0)], r"contact.tolerance=1.0 outside allowed range"),
    ([(("contact", "max_iterations"), 1.5)], r"contact.max_iterations=1.5 is not an integer \(allowed: 1 to 10000\)"),
    ([(("contact", "max_iterations"), 0)], r"contact.max_iterations=0 outside allowed range \[1, 10000\]"),
    ([(("contact", "max_iterations"), True)], r"contact.max_iterations=True \(a bool\) is not an integer"),
    ([(("contact", "symmetry"), "on")], r"contact.symmetry='on' is not one of \['auto', 'off'\]"),
    ([(("contact", "friction"), 0.5)], r"contact.friction: unknown key; allowed"),
    ([(("mesh", "size_contact"), 0.0)], r"mesh.size_contact=0.0 outside allowed range"),
    ([(("mesh", "size_contact"), -0.1)], r"mesh.size_contact=-0.1 outside allowed range"),
    ([(("mesh", "size_contact"), "fine")], r"mesh.size_contact='fine' \(a string\) is not a number \[mm\]"),
    ([(("mesh", "size_contact"), True)], r"mesh.size_contact=True \(a bool\) is not a number"),
    ([(("mesh", "size_far"), 0.1)], r"mesh.size_contact=0.3 mm must not exceed mesh.size_far=0.1 mm"),
    ([(("mesh", "order"), 3)], r"mesh.order=3 outside allowed range \[1, 2\]"),
    ([(("mesh", "order"), True)], r"mesh.order=True \(a bool\) is not an integer"),
    ([(("mesh", "order"), 1.0)], r"mesh.order=1.0 is not an integer"),
    ([(("mesh", "order"), "2")], r"mesh.order='2' \(a string\) is not an integer"),
    ([(("mesh", "volumetric"), "mixed")], r"mesh.volumetric='mixed' is not one of \['standard', 'nodal_average'\]"),
    ([(("mesh", "volumetric"), "nodal_average"), (("mesh", "order"), 2)],
     r"mesh.volumetric='nodal_average' needs mesh.order=1"),
    ([(("mesh", "fine_radius"), -1.0)], r"mesh.fine_radius=-1.0 outside allowed range"),
    ([(("mesh", "grading"), 0.0)], r"mesh.grading=0.0 outside allowed range"),
    ([(("mesh", "size_base"), 0.0)], r"mesh.size_base=0.0 outside allowed range"),
    ([(("mesh", "h"), 0.1)], r"mesh.h: unknown key"),
    ([(("load",), DELETE)], r"scene is missing \[\[load\]\]"),
    ([(("load",), {"kind": "press"})], r"load must be an array of tables: write \[\[load\]\]"),
    ([(("load", 0, "kind"), DELETE)], r"load.0.kind is missing: give kind = one of \['press', 'shear', 'twist'\]"),
    ([(("load", 0, "kind"), "poke")], r"load.0.kind='poke' is not one of \['press', 'shear', 'twist'\]"),
    ([(("load", 0, "kind"), 1)], r"load.0.kind=1 is not one of"),
    ([(("load", 0, "depth"), 0.1)], r"load.0 \(press\) needs exactly one of \['depth', 'force'\], got"),
    ([(("load", 0, "torque"), 1.0)], r"load.0 \(press\): unknown key\(s\) \['torque'\]"),
    ([(("load", 0, "force"), [])], r"load.0.press load has an empty list of values: force = \[\]"),
    ([(("load", 0, "force"), -0.2)], r"load.0.force=-0.2 outside allowed range \(0.0, inf\) N"),
    ([(("load", 0, "force"), "a lot")], r"load.0.force='a lot' \(a string\) is not a number \[N\]"),
    ([(("load", 0, "force"), True)], r"load.0.force=True \(a bool\) is not a number"),
    ([(("load", 0, "force"), math.nan)], r"load.0.force=nan outside allowed range"),
    ([(("load", 0, "force"), [0.1, "x"])], r"load.0.force='x' \(a string\) is not a number"),
    ([(("load", 1, "direction"), [1.0, 0.0, 0.0])], r"load.1.direction=\[1.0, 0.0, 0.0\] \(a list\) must be two numbers"),
    ([(("load", 1, "direction"), "x")], r"load.1.direction='x' \(a string\) must be two numbers"),
    ([(("load", 1, "direction"), [0.0, 0.0])], r"load.1.direction=\[0.0, 0.0\] must be a non-zero \[x, y\]"),
    ([(("load", 1, "direction"), [1.0, True])], r"load.1.direction\[1\]=True \(a bool\) is not a number"),
    ([(("load", 1, "force"), [0.02, math.inf])], r"load.1.force=inf outside allowed range"),
    ([(("load", 1, "shift"), 0.01)], r"load.1 \(shear\) needs exactly one of \['force', 'shift'\]"),
    ([(("load", 1), {"kind": "twist", "depth": 0.1})], r"load.1 \(twist\): unknown key\(s\) \['depth'\]"),
    ([(("load", 0), 3)], r"load.0 must be a table \(\[\[load\]\]\), got 3"),
    ([(("load",), [{"kind": "shear", "force": 0.1}])], r"load.0.kind='shear': the first load must be a press"),
    ([(("colour",), "red")], r"colour: unknown top-level key"),
    ([(("name",), 3)], r"name=3 must be a non-empty string"),
    ([(("name",), "")], r"name='' \(a string\) must be a non-empty string"),
]
# refused when the solve starts, before meshing: past the physical limits, or more than the machine holds
LIMITS = [
    ([(("load", 0, "force"), 1e30)], r"indent the gel about .* mm into its 10 mm .*past d/H = 0.5"),
    ([(("load", 0), {"kind": "press", "depth": 20.0})], r"indent the gel about 20 mm into its 10 mm"),
    ([(("body", "radius"), 0.5), (("load", 0, "force"), 5.0)], r"a/R = .* >= 1.0\): not a small contact"),
    ([(("mesh", "size_contact"), 1e-4)], r"mesh.size_contact=0.0001 mm .* would make about .* GB; this machine has 16 GB in all"),
]
MANY = ([(("material", "E"), "1.0"), (("contact", "frictionless_press"), "no"), (("gel", "width"), True),
         (("contact", "mu"), 0.5), (("load", 0, "force"), -1.0)],
        [r"material.E='1.0'", r"contact.frictionless_press='no'", r"gel.width=True", r"contact.mu was renamed",
         r"load.0.force=-1.0"])


def write_scene(folder: Path, edits) -> Path:
    path = folder / "scene.toml"
    path.write_text(to_toml(edited(BASE_SCENE, edits)))
    return path


def test_the_base_scene_is_valid(tmp_path):
    scene = load_scene(write_scene(tmp_path, []))
    assert scene.contact.friction_coefficient == 0.5 and len(scene.loads) == 2


@pytest.mark.parametrize("edits, message", SCENES, ids=[f"scene{i}" for i in range(len(SCENES))])
def test_bad_scene_is_refused_naming_file_key_and_value(tmp_path, edits, message):
    path = write_scene(tmp_path, edits)
    with pytest.raises(ValueError, match=message) as caught:
        load_scene(path)
    assert all(line.startswith(f"{path}: ") for line in str(caught.value).splitlines())


def test_every_problem_of_a_file_is_reported_at_once(tmp_path):
    edits, messages = MANY
    with pytest.raises(ValueError) as caught:
        load_scene(write_scene(tmp_path, edits))
    for message in messages:
        assert any(__import__("re").search(message, line) for line in str(caught.value).splitlines()), message


@pytest.mark.parametrize("edits, message", LIMITS, ids=[f"limit{i}" for i in range(len(LIMITS))])
def test_scene_past_the_limits_is_refused_before_meshing(tmp_path, edits, message, monkeypatch):
    from contact import PhysicalLimitError, solve_scene
    import contact.solver

    monkeypatch.setattr(contact.solver, "_gel_mesh", lambda *args: pytest.fail("meshed a refused scene"))
    with pytest.raises(PhysicalLimitError, match=message):
        solve_scene(load_scene(write_scene(tmp_path, edits)))


FILES = [
    (lambda folder: folder / "missing.toml", r"scene file '.*missing.toml' does not exist"),
    (lambda folder: folder, r"scene file '.*' is a folder, not a TOML file"),
    (lambda folder: _bytes(folder, to_toml(BASE_SCENE).encode("utf-16")), r"is UTF-16 text: save it as UTF-8"),
    (lambda folder: _bytes(folder, bytes(range(256))), r"is not UTF-8 text \(byte 128 is b'\\x80'\)"),
    (lambda folder: _bytes(folder, b"name = \"x\"\x00\x00"), r"holds NUL bytes: a binary file"),
    (lambda folder: _bytes(folder, b"[gel\nwidth = 1"), r"not valid TOML \(Expected ']'"),
    (lambda folder: _bytes(folder, b""), r"scene is missing \[gel\]"),
]


def _bytes(folder: Path, content: bytes) -> Path:
    path = folder / "file.toml"
    path.write_bytes(content)
    return path


@pytest.mark.parametrize("make, message", FILES, ids=[f"file{i}" for i in range(len(FILES))])
def test_unreadable_scene_file_is_named(tmp_path, make, message):
    with pytest.raises((ValueError, OSError), match=message):
        load_scene(make(tmp_path))


BASE_SWEEP = {
    "name": "catalogue-sweep",
    "outputs": ["stick_ratio@-1", "wall_time"],
    "grid": {"material.E": [0.5, 1.0]},
    "scene": BASE_SCENE,
}
SWEEPS = [
    ([(("colour",), "red")], r"colour: unknown top-level key in the sweep file"),
    ([(("scene",), DELETE)], r"scene is missing: give scene = "),
    ([(("scene",), "nowhere.toml")], r"scene='nowhere.toml': file '.*nowhere.toml' does not exist"),
    ([(("scene",), 3)], r"scene=3 must be a file path \(string\) or a \[scene\] table"),
    ([(("grid",), {})], r"the sweep has no axes"),
    ([(("grid", "material.E"), [])], r"\[grid\] axis 'material.E' is empty"),
    ([(("grid", "material.E"), 2.0)], r"\[grid\] axis 'material.E' must be a list of values"),
    ([(("grid", "material.E"), [{"a": 1}])], r"axis 'material.E': value \{'a': 1\} is not a number"),
    ([(("grid",), {"material": {"E": [1.0]}})], r"\[grid\] 'material' is a table: quote dotted keys"),
    ([(("grid",), {"material.Ex": [1.0]})], r"material.Ex: unknown key; allowed: \['E', 'law', 'nu'\]"),
    ([(("grid",), {"colour.E": [1.0]})], r"axis 'colour.E': a key is SECTION.KEY"),
    ([(("grid",), {"load.5.force": [1.0]})], r"axis 'load.5.force': 'load.5' is not an index"),
    ([(("grid",), {"material.E.x": [1.0]})], r"axis 'material.E.x': 'material.E' is a value"),
    ([(("grid", "material.E"), ["soft"])], r"material.E='soft' \(a string\) is not a number"),
    ([(("grid", "material.E"), [True, False])], r"material.E=True \(a bool\) is not a number"),
    ([(("grid",), {"material.nu": [0.45, 0.5]})], r"case \{'material.nu': 0.5\}: material.nu=0.5 outside allowed"),
    ([(("grid", "material.E"), [1.0, 1])], r"are the same scene: an axis repeats a value"),
    ([(("list",), {"material.E": [1.0]})], r"axis 'material.E' is in both \[grid\] and \[list\]"),
    ([(("list",), {"contact.friction_coefficient": [0.3, 0.5], "load.0.force": [0.2]})],
     r"\[list\] axes are zipped and need equal lengths"),
    ([(("outputs",), "stick_ratio@-1")], r"outputs must be a non-empty list"),
    ([(("outputs",), [])], r"outputs must be a non-empty list"),
    ([(("outputs",), ["stickiness@-1"])], r"'stickiness' is not a per-increment quantity"),
    ([(("outputs",), ["stick_ratio"])], r"'stick_ratio' is per increment: say which"),
    ([(("outputs",), ["stick_ratio@last"])], r"the increment after @ must be an integer"),
    ([(("outputs",), ["stick_ratio@6"])], r"increment 6 does not exist in every case"),
    ([(("outputs",), ["wall_time", "wall_time"])], r"'wall_time' is listed twice"),
    ([(("outputs",), ["colour"])], r"'colour' is not a known quantity"),
    ([(("outputs",), [3])], r"outputs: 3 is not a string"),
    ([(("grid",), {"contact.mu": [0.3, 0.5]})], r"axis 'contact.mu' was renamed contact.friction_coefficient"),
    ([(("grid",), {"contact.frictionless_press": ["no", "yes"]})],
     r"contact.frictionless_press='no' \(a string\) is not a bool"),
    ([(("grid",), {"mesh.order": [1, True]})], r"mesh.order=True \(a bool\) is not an integer"),
    ([(("grid",), {"load.1.direction": [[1.0, 0.0, 0.0]]})], r"load.1.direction=.* must be two numbers"),
    ([(("name",), 3)], r"name=3 must be a non-empty string"),
    ([(("scene", "material", "E"), -1.0)], r"scene: material.E=-1.0 outside allowed range"),
    ([(("scene", "contact", "mu"), 0.5)], r"scene: contact.mu was renamed contact.friction_coefficient"),
]


def write_sweep(folder: Path, edits) -> Path:
    path = folder / "sweep.toml"
    path.write_text(to_toml(edited(BASE_SWEEP, edits)))
    return path


def test_the_base_sweep_is_valid(tmp_path):
    assert len(load_sweep(write_sweep(tmp_path, [])).cases) == 2


@pytest.mark.parametrize("edits, message", SWEEPS, ids=[f"sweep{i}" for i in range(len(SWEEPS))])
def test_bad_sweep_is_refused_naming_file_key_and_value(tmp_path, edits, message):
    path = write_sweep(tmp_path, edits)
    with pytest.raises(ValueError, match=message) as caught:
        load_sweep(path)
    assert all(line.startswith(f"{path}: ") for line in str(caught.value).splitlines())


# --- the command line: exit code 2, the message, no traceback (in-process for speed) --------------------------------

def _cli(args, capsys):
    from studies.__main__ import main

    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out + captured.err


@pytest.mark.parametrize("edits, message", SCENES + LIMITS + [(MANY[0], MANY[1][0])],
                         ids=[f"cli-scene{i}" for i in range(len(SCENES) + len(LIMITS) + 1)])
def test_command_line_refuses_a_bad_scene_with_exit_2(tmp_path, capsys, edits, message, monkeypatch):
    import re

    import contact.solver

    monkeypatch.setattr(contact.solver, "_gel_mesh", lambda *args: pytest.fail("meshed a refused scene"))
    code, output = _cli(["run", str(write_scene(tmp_path, edits)), "--out", str(tmp_path / "out"), "--quiet"], capsys)
    assert code == 2 and re.search(message, output) and "Traceback" not in output


@pytest.mark.parametrize("make, message", FILES, ids=[f"cli-file{i}" for i in range(len(FILES))])
def test_command_line_names_an_unreadable_file_with_exit_2(tmp_path, capsys, make, message):
    import re

    code, output = _cli(["run", str(make(tmp_path)), "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and re.search(message, output) and "Traceback" not in output


@pytest.mark.parametrize("edits, message", SWEEPS, ids=[f"cli-sweep{i}" for i in range(len(SWEEPS))])
def test_command_line_refuses_a_bad_sweep_with_exit_2(tmp_path, capsys, edits, message):
    import re

    code, output = _cli(["sweep", str(write_sweep(tmp_path, edits)), "--out", str(tmp_path / "out"),
                         "--scheduler", "synchronous", "--quiet"], capsys)
    assert code == 2 and re.search(message, output) and "Traceback" not in output


def test_real_command_line_exits_2_without_traceback_and_debug_shows_it(tmp_path):
    path = write_scene(tmp_path, [(("contact", "frictionless_press"), "no")])
    command = [sys.executable, "-m", "studies", "run", str(path), "--out", str(tmp_path / "out")]
    plain = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    assert plain.returncode == 2 and "Traceback" not in plain.stderr
    assert "contact.frictionless_press='no' (a string) is not a bool" in plain.stderr
    debug = subprocess.run(command + ["--debug"], capture_output=True, text=True, cwd=ROOT)
    assert debug.returncode != 0 and "Traceback" in debug.stderr and "InputErrors" in debug.stderr
