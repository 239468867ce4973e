"""Scenes: the HCM-1 file loads as written; every malformed scene gets a clear error naming the problem."""

from pathlib import Path

import pytest

from contact.scene import LoadKind, load_scene, scene_from_dict

HCM1 = Path(__file__).parents[1] / "studies" / "scenes" / "hcm1.toml"


def hcm1_dict():
    import tomllib

    return tomllib.loads(HCM1.read_text())


def test_hcm1_loads_as_written():
    scene = load_scene(HCM1)
    assert scene.material.E == 1.0 and scene.material.nu == 0.45 and scene.contact.friction_coefficient == 0.5
    assert scene.body.shape == "sphere" and scene.body.radius == 10.0
    assert [load.kind for load in scene.loads] == [LoadKind.PRESS, LoadKind.SHEAR]
    assert scene.loads[1].values == (0.02, 0.04, 0.06, 0.08, 0.09)
    assert scene.mirror_symmetric and scene.has_tangential_load


def edit(path, value):
    data = hcm1_dict()
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is None:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


@pytest.mark.parametrize("path, value, message", [
    (("material", "E"), -1.0, r"material.E=-1.0 outside allowed range"),
    (("material", "nu"), 0.5, r"material.nu=0.5 outside allowed range"),
    (("material", "nu"), -1.0, r"material.nu=-1.0 outside allowed range"),
    (("contact", "friction_coefficient"), -0.1, r"contact.friction_coefficient=-0.1 outside allowed range"),
    (("gel", "thickness"), 0.0, r"gel.thickness=0.0 outside allowed range"),
    (("gel", "shape"), "sponge", r"gel.shape='sponge' is not one of"),
    (("body", "shape"), "cube", r"body.shape='cube' is not one of"),
    (("mesh", "order"), 3, r"mesh.order=3 outside allowed range \[1, 2\]"),
    (("mesh", "size_contact"), "fine", r"mesh.size_contact='fine' \(a string\) is not a number \[mm\]"),
    (("material", "G"), 1.0, r"material.G: unknown key; allowed: \['E', 'law', 'nu'\]"),
    (("colour",), "red", r"colour: unknown top-level key"),
    (("material",), None, r"scene is missing \[material\]"),
    (("load",), None, r"scene is missing \[\[load\]\]"),
])
def test_malformed_scene_is_refused_with_its_key(path, value, message):
    with pytest.raises(ValueError, match=message):
        scene_from_dict(edit(path, value))


@pytest.mark.parametrize("load, message", [
    ({"force": 0.2}, r"load.0.kind is missing"),
    ({"kind": "poke", "force": 0.2}, r"load.0.kind='poke' is not one of"),
    ({"kind": "press", "force": 0.2, "depth": 0.1}, r"needs exactly one of \['depth', 'force'\]"),
    ({"kind": "press", "torque": 1.0}, r"unknown key\(s\) \['torque'\]"),
    ({"kind": "press", "force": []}, r"empty list of values"),
    ({"kind": "press", "force": -0.2}, r"load.0.force=-0.2 outside allowed range"),
    ({"kind": "press", "force": "a lot"}, r"load.0.force='a lot' \(a string\) is not a number"),
    ({"kind": "shear", "force": 0.1}, r"the first load must be a press"),
])
def test_malformed_load_is_refused(load, message):
    data = hcm1_dict()
    data["load"] = [load]
    with pytest.raises(ValueError, match=message):
        scene_from_dict(data)


def test_zero_shear_direction_is_refused():
    data = hcm1_dict()
    data["load"][1]["direction"] = [0.0, 0.0]
    with pytest.raises(ValueError, match=r"load.1.direction=\[0.0, 0.0\] must be a non-zero"):
        scene_from_dict(data)


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_scene(tmp_path / "nope.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[gel\nwidth = 1")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_scene(broken)
