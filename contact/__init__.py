"""Closed-form contact theory, the frictional contact solver against a rigid body, scenes and the reduced model."""

from contact import theory
from contact._newton import OPEN, SLIP, STICK, ContactNotConverged
from contact.scene import (BodyShape, BodySpec, ContactSpec, GelShape, GelSpec, Load, LoadControl, LoadKind, Material,
                           MeshSettings, Scene, Symmetry, Volumetric, load_scene, scene_from_dict)
from contact.limits import PhysicalLimitError, PhysicalLimitWarning
from contact.result import ContactUnderResolved, LoadNotCarried
from contact.recovery import RecoveredContact, recover_contact
from contact.halfspace import coupled_reference, solve_halfspace
from contact.solver import ContactResult, Increment, PathNotCompleted, Prepared, prepare, preparation_key, solve_scene

__all__ = ["theory", "OPEN", "STICK", "SLIP", "ContactNotConverged", "BodySpec", "BodyShape", "ContactSpec", "GelSpec",
           "GelShape", "Load", "LoadKind", "LoadControl", "Symmetry", "Volumetric", "Material", "MeshSettings",
           "Scene", "load_scene", "scene_from_dict", "ContactResult", "Increment", "PathNotCompleted",
           "LoadNotCarried", "ContactUnderResolved", "PhysicalLimitError", "PhysicalLimitWarning", "Prepared",
           "prepare", "preparation_key", "solve_scene", "RecoveredContact", "recover_contact",
           "coupled_reference", "solve_halfspace"]
