"""The bump's press, then shear or twist, solved by GetFEM: run as ``python3 _script.py job.npz out.npz`` by an
interpreter that has GetFEM's Python interface (Debian's python3-getfem), never imported by the project.

It needs numpy and getfem only. The gel is the tet mesh it is given (P1), bonded at its base; a rigid plate is the
plane z = apex (a signed-distance obstacle of GetFEM's large-sliding contact brick: gap in the current geometry,
Alart-Curnier augmented Lagrangian, Coulomb friction on the sliding velocity u - w of the increment). The plate's
plane stays still and the base rises by the depth; the plate's shift along +x or turn about the bump's axis enters
the friction law as the previous displacement w of each increment (the law's slip is u - w), so the gel is never
turned as a whole; the Neo-Hookean gel's points are turned exactly, the linear gel's by the turn's linear part about
their undeformed arms, as the project's linear FEM turns them. The gel is GetFEM's linearized-elasticity brick
("linear") or a compressible Neo-Hookean solid written out in GetFEM's weak-form language ("neo_hookean"). An
increment that does not converge is halved (the rest of the step tried again once the half converged), up to
``HALVINGS`` failed attempts per increment; a path that still does not converge stops there, and its converged
increments are written with the reason (``stopped``).
"""

import sys
import time

import getfem as gf
import numpy as np

HALVINGS = 16
BASE, CONTACT = 1, 2
# the first Piola-Kirchhoff stress of W = G/2 (J^-2/3 I1 - 3) + K/2 (J - 1)^2, GetFEM differentiates it for Newton
NEO_HOOKE_STRESS = ("((G*pow(Det(F),-2/3))*(F-(Norm_sqr(F)/3)*Inv(F)')+(K*(Det(F)-1)*Det(F))*Inv(F)')"
                    ":Grad_Test_u")


def build(job):
    """The GetFEM model, its mesh and the names of the base multiplier and the P1 scalar space."""
    points, tets = job["points"], job["tets"]
    mesh = gf.Mesh("ptND", points.T.copy(), tets.T.astype(np.int32).copy())
    faces = mesh.outer_faces()
    normals = mesh.normal_of_faces(faces)
    centres = np.array([mesh.pts(mesh.pid_in_faces(faces[:, [k]])).mean(axis=1)
                        for k in range(faces.shape[1])]).T
    base_z, cap_floor = float(job["base_z"]), float(job["cap_floor"])
    mesh.set_region(BASE, faces[:, (normals[2] < -0.99) & (np.abs(centres[2] - base_z) < 1e-9)])
    mesh.set_region(CONTACT, faces[:, (normals[2] > 0.05) & (centres[2] > cap_floor)])
    E, nu, h = float(job["youngs_modulus"]), float(job["poissons_ratio"]), float(job["size"])
    shear_modulus, bulk = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
    vector = gf.MeshFem(mesh, 3)
    vector.set_classical_fem(1)
    scalar = gf.MeshFem(mesh, 1)
    scalar.set_classical_fem(1)
    volume, surface = gf.MeshIm(mesh, 2), gf.MeshIm(mesh, 2)
    model = gf.Model("real")
    model.add_fem_variable("u", vector)
    model.add_fem_data("w", vector)
    model.add_filtered_fem_variable("lambda", vector, CONTACT)
    if str(job["law"]) == "linear":
        model.add_initialized_data("clambda", E * nu / ((1 + nu) * (1 - 2 * nu)))
        model.add_initialized_data("cmu", shear_modulus)
        model.add_isotropic_linearized_elasticity_brick(volume, "u", "clambda", "cmu")
    else:
        model.add_initialized_data("G", shear_modulus)
        model.add_initialized_data("K", bulk)
        model.add_macro("F", "Id(meshdim)+Grad_u")
        model.add_nonlinear_term(volume, NEO_HOOKE_STRESS)
    model.add_fem_data("base_motion", vector)
    multiplier = model.mult_varname_Dirichlet(
        model.add_Dirichlet_condition_with_multipliers(volume, "u", vector, BASE, "base_motion"))
    # augmentation ~ the stiffness E/h of an element layer [MPa/mm]; contact found within 3 elements
    model.add_initialized_data("r", E / h)
    model.add_initialized_data("alpha", 1.0)
    model.add_initialized_data("f", 0.0)
    brick = model.add_integral_large_sliding_contact_brick_raytracing("r", 3.0 * h, "f", "alpha", 0)
    model.add_slave_contact_boundary_to_large_sliding_contact_brick(brick, surface, CONTACT, "u", "lambda", "w")
    model.add_rigid_obstacle_to_large_sliding_contact_brick(brick, f"{float(job['apex_z'])!r}-z", 3)
    return model, mesh, vector, scalar, volume, surface, multiplier


def region_points(mesh, region):
    """The point ids of a boundary region and its triangles (rows of point ids)."""
    faces = mesh.region(region)
    triangles = np.array([mesh.pid_in_faces(faces[:, [k]]) for k in range(faces.shape[1])], dtype=np.int64)
    return np.unique(triangles), triangles


def main(job_path, out_path):
    """Run the job and write the increments' fields."""
    gf.util_trace_level(0)
    job = dict(np.load(job_path, allow_pickle=False))
    model, mesh, vector, scalar, volume, surface, multiplier = build(job)
    points = mesh.pts()                                           # (3, N), the given order
    if points.shape != job["points"].T.shape or not np.allclose(points, job["points"].T):
        raise RuntimeError("GetFEM renumbered the mesh's points")
    base_points, _ = region_points(mesh, BASE)
    contact_points, triangles = region_points(mesh, CONTACT)
    base_mass = gf.asm_mass_matrix(volume, scalar, scalar, BASE)
    contact_mass = gf.asm_mass_matrix(surface, scalar, scalar, CONTACT)
    dof_points = scalar.basic_dof_nodes()                         # P1: one dof per point, matched by position
    order = np.lexsort(points[::-1])
    dof_order = np.lexsort(dof_points[::-1])
    point_of_dof = np.empty(points.shape[1], dtype=np.int64)
    point_of_dof[dof_order] = order
    dof_of_point = np.argsort(point_of_dof)
    coordinates = vector.basic_dof_nodes()                        # (3, n_dofs): each dof's point
    n_dofs = coordinates.shape[1]
    component = np.arange(n_dofs) % 3                             # P1 vector dofs: x, y, z of a point in a row
    first_of_point = np.arange(n_dofs) - component
    if not np.array_equal(coordinates[:, ::3], scalar.basic_dof_nodes()):
        raise RuntimeError("the vector and scalar P1 spaces number their points differently")
    centre = job["centre"]
    model.set_variable("base_motion", np.zeros(n_dofs))

    linear = str(job["law"]) == "linear"

    def plate_motion(displacement, start, end):
        """What the plate's shift and turn from loads ``start`` to ``end`` do to the points [mm], per dof: the
        Neo-Hookean gel's points turned exactly about the lever arms they have where ``displacement`` put them; the
        linear gel's by the turn's linear part about their undeformed arms, as the project's linear FEM turns them
        (exact arcs would pull a linear gel's points inwards by (1 - cos) r, a finite-kinematics term it lacks)."""
        turn, shift = end[2] - start[2], end[1] - start[1]
        if linear:
            x, y = coordinates[0] - centre[0], coordinates[1] - centre[1]
            motion = np.stack([-turn * y + shift, turn * x, np.zeros(n_dofs)])
        else:
            x, y = (coordinates[k] + displacement[first_of_point + k] - centre[k] for k in (0, 1))
            c, s = np.cos(turn), np.sin(turn)
            motion = np.stack([c * x - s * y - x + shift, s * x + c * y - y, np.zeros(n_dofs)])
        return motion[component, np.arange(n_dofs)]

    def field(expression, region):
        """(n_points, 3) nodal values of a vector expression on a region (zero elsewhere), in dof order."""
        return np.stack([model.interpolation(f"({expression})({k})", scalar, region) for k in (1, 2, 3)], axis=1)

    def solve_to(target, start):
        """Reach the loads ``target`` (depth, shift, angle) from ``start``, halving the step where Newton fails:
        the base rises by the depth; the plate's shift and turn enter as the friction law's previous displacement
        w (its slip is u - w), so the gel is never turned as a whole (a linear gel is not indifferent to that)."""
        pending, reached, splits, iterations, last_error = [target], start, 0, 0, ""
        while pending:
            load = pending[-1]
            saved = model.from_variables()           # every unknown: a failed attempt leaves no trace
            displacement = model.variable("u")
            model.set_variable("w", displacement + plate_motion(displacement, reached, load))
            model.set_variable("base_motion", np.where(component == 2, load[0], 0.0))
            try:
                count, converged = model.solve("max_res", 1e-9, "max_iter", 40, "lsearch", "simplest")
            except RuntimeError as error:              # GetFEM's own complaint, kept for the stop's reason
                count, converged, last_error = 40, False, str(error).strip().splitlines()[-1][:200]
            iterations += int(count)
            if converged:
                reached = pending.pop()
                continue
            model.to_variables(saved)
            splits += 1
            if splits > HALVINGS:
                raise NotConverged(f"GetFEM did not converge towards depth, shift, angle = {tuple(load)} "
                                   f"(from {tuple(reached)}, {splits - 1} halvings)"
                                   + (f"; GetFEM said: {last_error}" if last_error else ""))
            pending.append(tuple((np.array(reached) + np.array(load)) / 2))
        return iterations

    depth = float(job["depth"])
    loads = [(depth * k / int(job["press_steps"]), 0.0, 0.0) for k in range(1, int(job["press_steps"]) + 1)]
    kinds = [0] * len(loads)
    for value in job["values"]:
        loads.append((depth, float(value), 0.0) if str(job["path"]) == "shear" else (depth, 0.0, float(value)))
        kinds.append(1)
    records = {name: [] for name in ("u", "contact_force", "base_force", "contact_slip", "iterations", "seconds")}
    contact_area = np.asarray(contact_mass.mult(np.ones(points.shape[1])))[dof_of_point][contact_points]   # [mm^2]
    reached, stopped = (0.0, 0.0, 0.0), ""
    for load, kind in zip(loads, kinds):
        if kind == 1:
            model.set_variable("f", float(job["friction_coefficient"]))
        before = model.variable("u")
        start = time.perf_counter()
        try:
            records["iterations"].append(solve_to(load, reached))
        except NotConverged as error:         # the increments before it are kept
            stopped = str(error)
            break
        records["seconds"].append(time.perf_counter() - start)
        # the increment's slip against the plate, weighted by the hat functions, per tributary area [mm]: the
        # friction law holds it at zero on every point whose neighbourhood sticks (it is the multiplier's test of
        # u - w), while the points' own slips there oscillate about zero by up to ~1e-2 mm (P1 displacement, P1
        # multiplier)
        relative = model.variable("u") - before - plate_motion(before, reached, load)
        slip = np.column_stack([contact_mass.mult(relative[component == k]) for k in (0, 1)])
        records["contact_slip"].append(slip[dof_of_point][contact_points] / contact_area[:, None])
        reached = load
        records["u"].append(field("u", -1)[dof_of_point])
        # consistent nodal forces [N] of the plate's traction on the gel (the multiplier, per undeformed area: its
        # nodal values oscillate about the contact's rim, their integrals against the hat functions do not) and of
        # the base's reaction on it
        for name, expression, mass, region, ids in (("contact_force", "lambda", contact_mass, CONTACT, contact_points),
                                                    ("base_force", f"-{multiplier}", base_mass, BASE, base_points)):
            traction = field(expression, region)
            forces = np.column_stack([mass.mult(traction[:, k]) for k in range(3)])
            records[name].append(forces[dof_of_point][ids])
    done = len(records["u"])
    np.savez(out_path, loads=np.array(loads[:done]), kinds=np.array(kinds[:done]), contact_points=contact_points,
             triangles=triangles, base_points=base_points, stopped=np.array(stopped),
             **{k: np.array(v) for k, v in records.items()})


class NotConverged(RuntimeError):
    """An increment that did not converge after ``HALVINGS`` failed attempts."""


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
