"""ParaView outputs of a solve: one VTU per increment on the whole gel (a half model mirrored back), a ``.pvd``
time series over the increments, and the contact-state codes named in each file (VTK field data)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fem.atomic import atomic_path, write_text_atomic
from fem.mesh import positively_oriented

__all__ = ["STATE_NAMES", "write_vtu", "write_pvd", "mirrored_mesh"]

# contact_state point values: -1 for points that cannot touch the body (not contact candidates, the sides, the base)
STATE_NAMES = {-1: "not_a_candidate", 0: "open", 1: "stick", 2: "slip"}
TIME_SERIES = "increments.pvd"


def mirrored_mesh(nodes: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The whole gel from its half y >= 0: nodes (n, 3) and tets (m, 4) reflected in y = 0, the nodes on the plane
    kept once. Returns nodes, tets, the source node of every output node and a +-1 sign per output node (y mirrored).
    """
    on_plane = nodes[:, 1] == 0.0                                # half meshes are cut exactly at y = 0
    copies = np.flatnonzero(~on_plane)
    image = np.arange(len(nodes))
    image[copies] = len(nodes) + np.arange(copies.size)
    mirrored_nodes = nodes[copies] * [1.0, -1.0, 1.0]
    mirrored_tets = image[tets][:, [0, 2, 1, 3]]                  # a reflection flips orientation: swap two corners
    source = np.concatenate([np.arange(len(nodes)), copies])
    sign = np.concatenate([np.ones(len(nodes)), -np.ones(copies.size)])
    return np.vstack([nodes, mirrored_nodes]), np.vstack([tets, mirrored_tets]), source, sign


def _field_data_legend() -> str:
    """VTK XML FieldData naming each contact-state code (ParaView shows it in the Information panel)."""
    arrays = "".join(f'<DataArray type="Int8" Name="contact_state_{name}" NumberOfTuples="1" format="ascii">{code}'
                     f"</DataArray>\n" for code, name in STATE_NAMES.items())
    arrays += ('<DataArray type="Int8" Name="mirrored_from_half_model" NumberOfTuples="1" format="ascii">{half}'
               "</DataArray>\n")
    return "<FieldData>\n" + arrays + "</FieldData>\n"


def write_vtu(result, out_dir: Path) -> list[Path]:
    """One VTU per increment, ``increment_NNN.vtu``: displacement [mm], contact_state (codes in STATE_NAMES and in
    the file's field data), contact_pressure [MPa] and tangential_traction [MPa] on the top points, nodal values on
    the mesh vertices. A half model (y >= 0) is mirrored to the whole gel (u_y and t_y change sign). For an array,
    the bump of each candidate point (-1 elsewhere; a mirrored point keeps the index of its computed bump) and its
    bump's normal force [N], stick ratio and margin to gross slip painted on it (contact.bumps)."""
    import meshio

    model = result.model
    mesh = model.mesh
    n_vertices = mesh.p.shape[1]
    vertex_dofs = model.basis.nodal_dofs.T                             # (n_vertices, 3)
    top_vertex = model.top.dofs[:, 0]
    dof_to_vertex = np.full(model.n_dofs, -1)
    dof_to_vertex[vertex_dofs[:, 0]] = np.arange(n_vertices)
    candidate_vertex = dof_to_vertex[top_vertex[result.candidates]]
    on_vertex = candidate_vertex >= 0                                  # P2 midpoints are not mesh vertices
    half = bool(result.mesh_info.get("half_model"))
    nodes, tets = mesh.p.T, mesh.t.T
    source, sign = np.arange(n_vertices), np.ones(n_vertices)
    if half:
        nodes, tets, source, sign = mirrored_mesh(nodes, tets)
    tets = positively_oriented(nodes, tets)
    legend = _field_data_legend().replace("{half}", str(int(half)))
    flip_y = np.column_stack([np.ones_like(sign), sign, np.ones_like(sign)])          # (n_out, 3)
    paths = []
    for number, increment in enumerate(result.increments, start=1):
        state = np.full(n_vertices, -1, dtype=np.int8)
        pressure = np.zeros(n_vertices)
        traction = np.zeros((n_vertices, 3))
        state[candidate_vertex[on_vertex]] = increment.status[on_vertex]
        pressure[candidate_vertex[on_vertex]] = increment.pressure[on_vertex]
        traction[candidate_vertex[on_vertex], :2] = increment.traction[on_vertex]
        displacement = increment.displacement_full[vertex_dofs]
        point_data = {"displacement": displacement[source] * flip_y, "contact_state": state[source],
                      "contact_pressure": pressure[source], "tangential_traction": traction[source] * flip_y}
        if increment.bumps is not None:
            point_data.update({key: values[source] for key, values in _bump_fields(result, increment, n_vertices,
                                                                                  candidate_vertex, on_vertex).items()})
        path = Path(out_dir) / f"increment_{number:03d}.vtu"
        with atomic_path(path) as temporary:
            meshio.write(temporary, meshio.Mesh(nodes, [("tetra", tets)], point_data=point_data), file_format="vtu")
            text = temporary.read_text()
            temporary.write_text(text.replace("<UnstructuredGrid>\n", "<UnstructuredGrid>\n" + legend, 1))
        paths.append(path)
    return paths


def _bump_fields(result, increment, n_vertices, candidate_vertex, on_vertex) -> dict:
    """Per-vertex bump index and the bump's normal force, stick ratio and gross-slip margin (0 off the bumps)."""
    bump_of_candidate = result.candidate_bump[on_vertex]
    bump = np.full(n_vertices, -1.0)
    bump[candidate_vertex[on_vertex]] = bump_of_candidate
    fields = {"bump": bump}
    for name in ("normal_force", "stick_ratio", "gross_slip_margin"):
        painted = np.zeros(n_vertices)
        painted[candidate_vertex[on_vertex]] = getattr(increment.bumps, name)[bump_of_candidate]
        fields[f"bump_{name}"] = painted
    return fields


def write_pvd(vtu_paths: list[Path], out_dir: Path) -> Path:
    """``increments.pvd``: a ParaView time series over the increment files (time = increment number)."""
    entries = "".join(f'    <DataSet timestep="{number}" part="0" file="{Path(path).name}"/>\n'
                      for number, path in enumerate(vtu_paths, start=1))
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n' + entries
            + "  </Collection>\n</VTKFile>\n")
    return write_text_atomic(Path(out_dir) / TIME_SERIES, text)
