"""Closed-form contact theory, the frictional contact solver against a rigid body, scenes and the reduced model."""

from contact import theory
from contact._newton import OPEN, SLIP, STICK, ContactNotConverged
from contact.scene import (BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, Scene, load_scene,
                           scene_from_dict)
from contact.result import ContactUnderResolved, LoadNotCarried
from contact.solver import ContactResult, Increment, PathNotCompleted, Prepared, prepare, preparation_key, solve_scene

__all__ = ["theory", "OPEN", "STICK", "SLIP", "ContactNotConverged", "BodySpec", "ContactSpec", "GelSpec", "Load",
           "LoadKind", "Material", "MeshSettings", "Scene", "load_scene", "scene_from_dict", "ContactResult",
           "Increment", "PathNotCompleted", "LoadNotCarried", "ContactUnderResolved", "Prepared", "prepare",
           "preparation_key", "solve_scene"]
