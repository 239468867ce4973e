"""controller/ in rooms that follow the data: every import of a room's modules (lazy ones inside functions too) names
only the rooms before it, and the module paths from before the rooms still import the same modules."""

import ast
import importlib
from pathlib import Path

import pytest

import controller

ROOT = Path(controller.__file__).parent
# room -> the rooms it may import (docs/design.md, sec. 2); the plant never sees estimation or control
ALLOWED = {
    "sensing": set(),
    "estimation": {"sensing"},
    "control": {"sensing", "estimation"},
    "plant": {"sensing"},
    "closed_loop": {"sensing", "estimation", "control", "plant"},
    "design": {"sensing", "estimation", "control", "plant", "closed_loop"},
}


def imported_rooms(path: Path, room: str, root: Path = ROOT) -> set[str]:
    """The controller rooms a module under ``root / room`` imports (absolute or relative, at any depth); '' for the
    bare package."""
    package = ["controller", room] + list(path.relative_to(root / room).parent.parts)
    rooms = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            names = [".".join(base + ([node.module] if node.module else []))]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "controller":
                rooms.add(parts[1] if len(parts) > 1 else "")
    return rooms - {room}


@pytest.mark.parametrize("room", sorted(ALLOWED))
def test_a_room_imports_only_the_rooms_before_it(room):
    modules = sorted((ROOT / room).rglob("*.py"))
    assert modules, f"room {room} has no modules"
    for path in modules:
        extra = imported_rooms(path, room) - ALLOWED[room]
        assert not extra, f"{path.relative_to(ROOT.parent)} imports {sorted(extra)} (allowed: {sorted(ALLOWED[room])})"


def test_every_module_of_controller_lives_in_a_room():
    loose = [p.name for p in ROOT.glob("*.py") if p.name != "__init__.py"]
    assert loose == []
    assert {p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file()} == set(ALLOWED)


def test_the_rule_checker_sees_a_forbidden_import(tmp_path):
    """The checker itself: a plant module importing the estimator is caught, relative or absolute."""
    (tmp_path / "plant" / "deep").mkdir(parents=True)
    path = tmp_path / "plant" / "deep" / "probe.py"
    for source, room in (("from controller.estimation import estimate_slip\n", "estimation"),
                         ("def f():\n    from ...control import x\n", "control"),
                         ("from .. import hertz_plant\n", None)):
        path.write_text(source)
        assert imported_rooms(path, "plant", tmp_path) == ({room} if room else set())


@pytest.mark.parametrize("former, room_module", sorted(controller.FORMER_MODULES.items()))
def test_former_module_paths_are_the_room_modules(former, room_module):
    assert importlib.import_module(f"controller.{former}") is importlib.import_module(f"controller.{room_module}")
