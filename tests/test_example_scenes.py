"""The example scenes beside hcm1.toml load, and say what they claim to be."""

from pathlib import Path

import pytest

from contact.scene import LoadKind, load_scene

SCENES = Path(__file__).resolve().parents[1] / "studies" / "scenes"


@pytest.mark.parametrize("name, kinds", [
    ("array_shear", [LoadKind.PRESS, LoadKind.SHEAR]),
    ("array_twist", [LoadKind.PRESS, LoadKind.TWIST]),
    ("array_shear_twist", [LoadKind.PRESS, LoadKind.SHEAR, LoadKind.TWIST]),
    ("cap_twist", [LoadKind.PRESS, LoadKind.TWIST]),
])
def test_example_scene_loads(name, kinds):
    scene = load_scene(SCENES / f"{name}.toml")
    assert scene.name == name and [load.kind for load in scene.loads] == kinds
    assert scene.body.shape == "plane"
    if name.startswith("array"):
        assert scene.gel.geometry.n_bumps == 9
    press = scene.loads[0].values[0]
    for load in scene.loads[1:]:
        if load.kind == LoadKind.SHEAR:
            # force control stays below gross slip of the plate: Q < mu P
            assert max(load.values) < scene.contact.friction_coefficient * press
