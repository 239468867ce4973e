"""The same two problems as scenes of the project's linear solver (``contact.solver``): a square block of the layer's
width under the sphere, and a 1 x 1 array (the bump on its cell of the base) under a rigid plate."""

from __future__ import annotations

from contact.scene import BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, Scene

__all__ = ["sphere_press_scene", "bump_scene"]


def sphere_press_scene(setup, forces, size_contact: float = 0.3, size_far: float = 3.0) -> Scene:
    """Sphere pressed frictionless into a block 2 layer_radius wide (half model), force control at ``forces`` [N]."""
    width = 2.0 * setup.layer_radius
    return Scene(name="finite_strain_sphere_press",
                 gel=GelSpec("block", (("width", width), ("depth", width), ("thickness", setup.thickness))),
                 material=Material(setup.youngs_modulus, setup.poissons_ratio),
                 body=BodySpec("sphere", setup.sphere_radius), contact=ContactSpec(friction_coefficient=0.0),
                 mesh=MeshSettings(size_contact=size_contact, size_far=size_far),
                 loads=(Load(LoadKind.PRESS, "force", tuple(float(f) for f in forces)),))


def bump_scene(setup, path: str, values, press_forces=(), size_contact: float = 0.3, size_base: float = 1.0,
               hold: bool = True) -> Scene:
    """The bump (a 1 x 1 array on its base cell) pressed by a plate with the forces ``press_forces`` [N] (frictionless,
    as the CalculiX reference must), then to ``setup.depth`` [mm] held there, then, with friction, shifted along +x to
    the shifts [mm] or turned to
    the angles [rad] ``values`` (``hold=False``: the presses alone). The depth is reached from a force-controlled
    press (the solver's first increment must be force-controlled: by depth alone Newton stalls near 1e-3 on a fresh
    contact)."""
    gel = GelSpec("array", (("rows", 1), ("cols", 1), ("bump_radius", setup.bump_radius),
                            ("pitch", setup.base_width), ("base_width", setup.base_width),
                            ("base_depth", setup.base_width), ("base_thickness", setup.base_thickness)))
    kind = {"shear": LoadKind.SHEAR, "twist": LoadKind.TWIST}.get(path)
    if kind is None:
        raise ValueError(f"path={path!r}; allowed: 'shear', 'twist'")
    if not press_forces:
        raise ValueError("press_forces=(): give at least one force [N] to press with before the depth is held")
    loads = (Load(LoadKind.PRESS, "force", tuple(float(f) for f in press_forces)),)
    if hold:
        loads += (Load(LoadKind.PRESS, "displacement", (setup.depth,)),)
    if hold and len(values):
        loads += (Load(kind, "displacement", tuple(float(v) for v in values)),)
    return Scene(name=f"finite_strain_bump_{path}", gel=gel,
                 material=Material(setup.youngs_modulus, setup.poissons_ratio), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=setup.friction_coefficient,
                                     frictionless_press=not setup.frictional_press),
                 mesh=MeshSettings(size_contact=size_contact, size_far=3.0, size_base=size_base), loads=loads)
