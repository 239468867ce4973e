"""Capacitive pressure-array model: a piecewise-linear pressure field integrated exactly over square sensor cells.

The input is a pressure field on the sensor plane, not an FEM object: nodal pressures [MPa] of a piecewise-linear
field on a triangulation of the plane (what the FEM gives on its base plane, or a regular grid from the reduced
contact model, or a callable p(x, y) tabulated on a grid). Each sensor node reads the force [N] on its cell, a
pitch x pitch square centred on the node: the field is clipped against the cell squares exactly (Sutherland-Hodgman
on convex polygons), so a field inside the array footprint keeps its total force to round-off. Offset, Gaussian noise
and quantization follow, in that order (paper sec. IV-B: 11 x 13 nodes at 3 mm pitch, sampled at 100 Hz).

A capacitive array (``capacitive_array``, ``controller.sensing.capacitive``) reads pads smaller than the cells,
``fill_factor`` of the cell area, through a node model with a saturating pressure-capacitance curve, crosstalk, a noise
floor and a converter. ``SensorArray()`` keeps the ideal cell integrator: fill 1 and no node model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
import scipy.sparse as sp

from fem.validation import check_finite_array, check_positive, check_range

from .capacitive import CapacitiveNode

__all__ = [
    "Interpolation",
    "PressureField",
    "SensorArray",
    "capacitive_array",
    "cell_force_operator",
    "resample_time_series",
    "sample",
]


def _frozen_array(values, dtype=float) -> np.ndarray:
    array = np.array(values, dtype=dtype)
    array.setflags(write=False)
    return array


def _check_axis(name: str, values) -> np.ndarray:
    """A strictly increasing 1D grid axis [mm] with at least two points."""
    axis = check_finite_array(name, values)
    if axis.ndim != 1 or axis.size < 2 or np.any(np.diff(axis) <= 0.0):
        raise ValueError(f"{name} must be a strictly increasing 1D array of at least 2 points, got shape {axis.shape}")
    return axis


@dataclass(frozen=True, eq=False)
class PressureField:
    """Piecewise-linear pressure field on a triangulation of the sensor plane, one frame or a time stack.

    Parameters
    ----------
    positions : (n, 2) float -- node coordinates (x, y) on the sensor plane [mm].
    triangles : (m, 3) int -- node indices of each triangle (either orientation; zero-area triangles carry nothing).
    pressure : (n,) or (t, n) float -- nodal pressure [MPa], positive in compression; the field is linear on each
        triangle. A 1D array is one frame; ``frames`` always has shape (t, n).
    """

    positions: np.ndarray
    triangles: np.ndarray
    pressure: np.ndarray

    def __post_init__(self):
        positions = check_finite_array("positions", self.positions)
        if positions.ndim != 2 or positions.shape[1] != 2:
            raise ValueError(f"positions must have shape (n, 2), got {positions.shape}")
        triangles = np.asarray(self.triangles)
        if triangles.ndim != 2 or triangles.shape[1] != 3 or not np.issubdtype(triangles.dtype, np.integer):
            raise ValueError(f"triangles must be an integer array of shape (m, 3), "
                             f"got {triangles.dtype} {triangles.shape}")
        if triangles.size and (triangles.min() < 0 or triangles.max() >= len(positions)):
            raise ValueError(f"triangles index nodes outside [0, {len(positions) - 1}]")
        pressure = check_finite_array("pressure", self.pressure)
        if pressure.ndim not in (1, 2) or pressure.shape[-1] != len(positions):
            raise ValueError(f"pressure must have shape (n,) or (t, n) with n = {len(positions)}, got {pressure.shape}")
        object.__setattr__(self, "positions", _frozen_array(positions))
        object.__setattr__(self, "triangles", _frozen_array(triangles, np.int64))
        object.__setattr__(self, "pressure", _frozen_array(pressure))

    @property
    def frames(self) -> np.ndarray:
        """Nodal pressure as a time stack (t, n) [MPa]."""
        return self.pressure.reshape(-1, len(self.positions))

    def total_force(self) -> np.ndarray:
        """Exact integral of the field over the whole triangulation, F = sum_e A_e mean(p_e) [N], shape (t,)."""
        corners = self.positions[self.triangles]                                            # (m, 3, 2)
        edges = corners[:, 1:] - corners[:, :1]                                              # (m, 2, 2)
        area = 0.5 * np.abs(edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0])   # (m,)
        return self.frames[:, self.triangles].mean(axis=2) @ area

    @classmethod
    def from_grid(cls, x, y, pressure) -> "PressureField":
        """Field from nodal values on a regular (rectilinear) grid, each grid cell split into two triangles.

        Parameters
        ----------
        x : (nx,) float -- strictly increasing node abscissae [mm].
        y : (ny,) float -- strictly increasing node ordinates [mm].
        pressure : (ny, nx) or (t, ny, nx) float -- nodal pressure [MPa], ``pressure[..., j, i]`` at (x[i], y[j]).
        """
        x, y = _check_axis("x", x), _check_axis("y", y)
        pressure = np.asarray(pressure, dtype=float)
        if pressure.ndim not in (2, 3) or pressure.shape[-2:] != (len(y), len(x)):
            raise ValueError(f"grid pressure must have shape (ny, nx) or (t, ny, nx) = (..., {len(y)}, {len(x)}), "
                             f"got {pressure.shape}")
        grid_x, grid_y = np.meshgrid(x, y)                                                   # (ny, nx)
        node = np.arange(len(x) * len(y)).reshape(len(y), len(x))
        lower_left, lower_right = node[:-1, :-1].ravel(), node[:-1, 1:].ravel()
        upper_left, upper_right = node[1:, :-1].ravel(), node[1:, 1:].ravel()
        triangles = np.concatenate([np.stack([lower_left, lower_right, upper_right], axis=1),
                                    np.stack([lower_left, upper_right, upper_left], axis=1)])
        positions = np.stack([grid_x.ravel(), grid_y.ravel()], axis=1)
        return cls(positions, triangles, pressure.reshape(pressure.shape[:-2] + (-1,)))

    @classmethod
    def from_function(cls, pressure_function, x, y) -> "PressureField":
        """Field interpolating ``pressure_function(X, Y)`` [MPa] linearly between the nodes of the grid x, y [mm].

        ``pressure_function`` is called once with the (ny, nx) node coordinate arrays and returns (ny, nx) or
        (t, ny, nx). The interpolant's integral differs from the function's by O(h^2 |grad^2 p|) per unit area
        (h the grid spacing): refine the grid until it is below the sensor noise.
        """
        x, y = _check_axis("x", x), _check_axis("y", y)
        grid_x, grid_y = np.meshgrid(x, y)
        return cls.from_grid(x, y, pressure_function(grid_x, grid_y))


@dataclass(frozen=True)
class SensorArray:
    """Capacitive pressure-array geometry and read-out chain; defaults are the paper's sensor (sec. IV-B).

    Node (i, j) sits at x_i = centre_x + (i - (nx - 1)/2) pitch, y_j = centre_y + (j - (ny - 1)/2) pitch and reads the
    force on its cell, the pitch x pitch square around it; readings have shape (t, ny, nx).

    Parameters
    ----------
    pitch : float -- node spacing and cell side [mm], > 0.
    node_counts : (int, int) -- nodes (nx, ny) along x and y, each >= 1.
    centre : (float, float) -- centre of the node grid on the sensor plane [mm].
    noise_std : float -- standard deviation of the additive Gaussian noise per node and frame [N], >= 0.
    offset : float -- constant offset added to every reading [N].
    quantization_step : float -- reading resolution [N]; 0 means no quantization.
    sample_rate_hz : float -- frame rate of the array [Hz], > 0.
    fill_factor : float -- pad area / cell area [-], in (0, 1]: each node reads a centred square pad of side
        pitch sqrt(fill_factor); 1 (default) reads the whole cell.
    node : CapacitiveNode or None -- the capacitive node model the pad force goes through before offset, noise and
        quantization above (``controller.sensing.capacitive``); None (default): the pad force itself.
    """

    pitch: float = 3.0
    node_counts: tuple[int, int] = (11, 13)
    centre: tuple[float, float] = (0.0, 0.0)
    noise_std: float = 0.0
    offset: float = 0.0
    quantization_step: float = 0.0
    sample_rate_hz: float = 100.0
    fill_factor: float = 1.0
    node: CapacitiveNode | None = None

    def __post_init__(self):
        check_positive("pitch", self.pitch, "mm")
        if len(self.node_counts) != 2 or any(int(c) != c or c < 1 for c in self.node_counts):
            raise ValueError(f"node_counts={self.node_counts!r} must be two integers >= 1 (nx, ny)")
        object.__setattr__(self, "node_counts", tuple(int(c) for c in self.node_counts))
        if len(self.centre) != 2:
            raise ValueError(f"centre={self.centre!r} must be a pair (x, y) [mm]")
        object.__setattr__(self, "centre", tuple(check_range(f"centre[{k}]", c, -math.inf, math.inf, "mm")
                                                  for k, c in enumerate(self.centre)))
        check_range("noise_std", self.noise_std, 0.0, math.inf, "N")
        check_range("offset", self.offset, -math.inf, math.inf, "N")
        check_range("quantization_step", self.quantization_step, 0.0, math.inf, "N")
        check_positive("sample_rate_hz", self.sample_rate_hz, "Hz")
        check_range("fill_factor", self.fill_factor, 0.0, 1.0, "", low_open=True)
        if self.node is not None and not isinstance(self.node, CapacitiveNode):
            raise ValueError(f"node={self.node!r} must be a CapacitiveNode or None")

    @property
    def shape(self) -> tuple[int, int]:
        """Shape (ny, nx) of one reading frame."""
        return self.node_counts[1], self.node_counts[0]

    @property
    def cell_area(self) -> float:
        """Area of one cell, pitch^2 [mm^2]; reading / cell_area is the mean pressure on the cell [MPa]."""
        return self.pitch**2

    @property
    def pad_side(self) -> float:
        """Side of a node's square pad, pitch sqrt(fill_factor) [mm]."""
        return self.pitch * math.sqrt(self.fill_factor)

    @property
    def pad_area(self) -> float:
        """Area of a node's pad, fill_factor pitch^2 [mm^2]."""
        return self.fill_factor * self.pitch**2

    @property
    def pad_gap(self) -> float:
        """Gap between neighbouring pads, pitch - pad_side [mm]."""
        return self.pitch - self.pad_side

    @property
    def node_x(self) -> np.ndarray:
        """Node abscissae (nx,) [mm]."""
        return self.centre[0] + (np.arange(self.node_counts[0]) - 0.5 * (self.node_counts[0] - 1)) * self.pitch

    @property
    def node_y(self) -> np.ndarray:
        """Node ordinates (ny,) [mm]."""
        return self.centre[1] + (np.arange(self.node_counts[1]) - 0.5 * (self.node_counts[1] - 1)) * self.pitch

    @property
    def node_positions(self) -> np.ndarray:
        """Node coordinates (ny, nx, 2) [mm], ``node_positions[j, i] = (x_i, y_j)``."""
        grid_x, grid_y = np.meshgrid(self.node_x, self.node_y)
        return np.stack([grid_x, grid_y], axis=-1)


# --- exact integration of a piecewise-linear field over the cells -------------------------------------------------

def _clip_half_plane(polygons: np.ndarray, counts: np.ndarray, axis: int, bound: np.ndarray, keep_below: bool):
    """Clip convex polygons (K, V, 2) with ``counts`` (K,) vertices to x_axis <= bound (or >=), Sutherland-Hodgman.

    Returns polygons (K, V + 1, 2) and counts (K,); crossing points get the clip coordinate exactly ``bound``, so the
    pieces on either side of a cell edge share it bit for bit.
    """
    size, vertices = counts.shape[0], polygons.shape[1]
    index = np.arange(vertices)[None, :]                                                     # (1, V)
    valid = index < counts[:, None]                                                          # (K, V)
    following = np.where(index + 1 < counts[:, None], index + 1, 0)                          # (K, V)
    ahead = np.take_along_axis(polygons, following[..., None], axis=1)                       # (K, V, 2)
    sign = 1.0 if keep_below else -1.0
    distance = sign * (polygons[..., axis] - bound[:, None])                                 # (K, V)
    distance_ahead = sign * (ahead[..., axis] - bound[:, None])
    inside, inside_ahead = distance <= 0.0, distance_ahead <= 0.0
    crossing = valid & (inside != inside_ahead)
    denominator = np.where(crossing, distance - distance_ahead, 1.0)
    fraction = np.where(crossing, distance / denominator, 0.0)                               # (K, V)
    crossing_point = polygons + fraction[..., None] * (ahead - polygons)                     # (K, V, 2)
    crossing_point[..., axis] = bound[:, None]
    candidates = np.stack([polygons, crossing_point], axis=2).reshape(size, 2 * vertices, 2)
    keep = np.stack([valid & inside, crossing], axis=2).reshape(size, 2 * vertices)
    order = np.argsort(~keep, axis=1, kind="stable")[:, : vertices + 1]                      # kept ones first
    return np.take_along_axis(candidates, order[..., None], axis=1), keep.sum(axis=1)


def _polygon_area_centroid(polygons: np.ndarray, counts: np.ndarray):
    """Signed area (K,) [mm^2] and centroid (K, 2) [mm] of polygons (K, V, 2) with ``counts`` vertices (shoelace)."""
    index = np.arange(polygons.shape[1])[None, :]
    following = np.where(index + 1 < counts[:, None], index + 1, 0)
    ahead = np.take_along_axis(polygons, following[..., None], axis=1)
    cross = np.where(index < counts[:, None],
                     polygons[..., 0] * ahead[..., 1] - ahead[..., 0] * polygons[..., 1], 0.0)   # (K, V)
    area = 0.5 * cross.sum(axis=1)
    safe = np.where(area != 0.0, area, 1.0)
    centroid = np.einsum("kv,kvd->kd", cross, polygons + ahead) / (6.0 * safe[:, None])
    return area, centroid


def cell_force_operator(positions, triangles, array: SensorArray) -> sp.csr_matrix:
    """Sparse operator W (ny * nx, n) mapping nodal pressure [MPa] to pad forces [N]: F = W p, exactly.

    A node's pad is the centred square of side ``array.pad_side`` in its cell (the whole cell at fill_factor 1).

    Each triangle is clipped against every cell its bounding box touches (pairs, no loop over elements); on a
    clipped piece of area A and centroid g the linear field integrates to A p(g) = A sum_k lambda_k(g) p_k, with
    lambda the barycentric coordinates of g in the triangle, so W holds A lambda_k(g) summed over pieces. Depends
    only on the geometry: build it once and reuse it for every frame and time step (``sample(..., operator=W)``).
    Coordinates are taken relative to each cell's lower-left corner, so round-off scales with the pitch, not with
    the distance from the origin. Row j * nx + i is node (i, j).
    """
    positions = np.asarray(positions, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    nx, ny = array.node_counts
    left, bottom = array.node_x[0] - 0.5 * array.pitch, array.node_y[0] - 0.5 * array.pitch
    corners = positions[triangles]                                                           # (m, 3, 2)
    low = np.floor((corners.min(axis=1) - (left, bottom)) / array.pitch).astype(np.int64)    # (m, 2) cell index
    high = np.floor((corners.max(axis=1) - (left, bottom)) / array.pitch).astype(np.int64)
    counts_max = np.array([nx - 1, ny - 1])
    low, high = np.maximum(low, 0), np.minimum(high, counts_max)
    span = np.where(np.all(high >= low, axis=1, keepdims=True), high - low + 1, 0)           # (m, 2) cells per axis
    pairs = span[:, 0] * span[:, 1]                                                          # (m,)
    triangle = np.repeat(np.arange(len(triangles)), pairs)                                   # (P,)
    local = np.arange(pairs.sum()) - np.repeat(np.cumsum(pairs) - pairs, pairs)              # 0..pairs-1 per triangle
    cell_i = low[triangle, 0] + local % np.maximum(span[triangle, 0], 1)
    cell_j = low[triangle, 1] + local // np.maximum(span[triangle, 0], 1)
    origin = np.stack([left + cell_i * array.pitch, bottom + cell_j * array.pitch], axis=1)   # (P, 2)
    vertices = corners[triangle] - origin[:, None, :]                                        # (P, 3, 2) cell-local
    polygons, counts = vertices, np.full(len(triangle), 3)
    margin = 0.5 * array.pad_gap if array.fill_factor < 1.0 else 0.0          # pad edges in cell coordinates
    zero, pitch = np.full(len(triangle), margin), np.full(len(triangle), float(array.pitch) - margin)
    for axis, bound, keep_below in ((0, zero, False), (0, pitch, True), (1, zero, False), (1, pitch, True)):
        polygons, counts = _clip_half_plane(polygons, counts, axis, bound, keep_below)
    area, centroid = _polygon_area_centroid(polygons, counts)                                # (P,), (P, 2)
    edges = vertices[:, 1:] - vertices[:, :1]                                                # (P, 2, 2)
    doubled = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]              # 2 * signed tri area
    keep = (counts >= 3) & (doubled != 0.0)
    relative = centroid - vertices[:, 0]
    safe = np.where(keep, doubled, 1.0)
    lambda_1 = (relative[:, 0] * edges[:, 1, 1] - relative[:, 1] * edges[:, 1, 0]) / safe
    lambda_2 = (edges[:, 0, 0] * relative[:, 1] - edges[:, 0, 1] * relative[:, 0]) / safe
    barycentric = np.stack([1.0 - lambda_1 - lambda_2, lambda_1, lambda_2], axis=1)          # (P, 3)
    weights = np.where(keep, np.abs(area), 0.0)[:, None] * barycentric                       # (P, 3) [mm^2]
    rows = np.repeat(cell_j * nx + cell_i, 3)
    operator = sp.coo_matrix((weights.ravel(), (rows, triangles[triangle].ravel())), shape=(nx * ny, len(positions)))
    return operator.tocsr()                                                                  # duplicates summed


def sample(field: PressureField, array: SensorArray, rng=None, operator=None) -> np.ndarray:
    """Sensor readings (t, ny, nx) [N] of ``field``: pad forces, the node model, then offset, noise and quantization.

    reading = Q(N(F_pad) + offset + noise), F_pad the force on each node's pad (its whole cell at fill_factor 1),
    N the capacitive node model (``array.node``; identity when None), noise ~ N(0, noise_std^2) independent per
    node and frame, Q rounding to the nearest multiple of ``quantization_step`` (none when 0). Force outside the
    pads is not seen. Divide by ``array.pad_area`` for the mean pad pressure [MPa].

    Parameters
    ----------
    field : PressureField -- pressure on the sensor plane, one frame or (t, n).
    array : SensorArray -- geometry and read-out chain.
    rng : numpy Generator or int seed or None -- noise source (used only when noise_std > 0 or the node model has
        a noise floor); seed it for reproducible noise, None draws fresh entropy.
    operator : sparse (ny * nx, n), optional -- ``cell_force_operator`` of this geometry, to skip rebuilding it.
    """
    if operator is None:
        operator = cell_force_operator(field.positions, field.triangles, array)
    elif operator.shape != (array.shape[0] * array.shape[1], len(field.positions)):
        raise ValueError(f"operator shape {operator.shape} does not match the array and field "
                         f"({array.shape[0] * array.shape[1]}, {len(field.positions)})")
    readings = (operator @ field.frames.T).T.reshape((-1,) + array.shape)                    # (t, ny, nx)
    rng = np.random.default_rng(rng) if (array.noise_std > 0.0 or array.node is not None) else rng
    if array.node is not None:
        readings = array.node.read(readings, array.pad_area, rng)
    readings = readings + array.offset
    if array.noise_std > 0.0:
        readings = readings + rng.normal(0.0, array.noise_std, readings.shape)
    if array.quantization_step > 0.0:
        readings = np.round(readings / array.quantization_step) * array.quantization_step
    return readings


def capacitive_array(pitch: float = 3.0, node_counts: tuple[int, int] = (11, 13), centre=(0.0, 0.0),
                     pad_gap: float = 0.5, node: CapacitiveNode | None = None, **options) -> SensorArray:
    """A capacitive array: square pads with ``pad_gap`` [mm] between them (fill (1 - gap / pitch)^2) read through
    ``node`` (default ``CapacitiveNode()``, the documented node of ``controller.sensing.capacitive``); ``options`` are
    the other SensorArray fields. A 0.5 mm gap leaves 69 % of a 3 mm cell and 25 % of a 1 mm cell to the pad."""
    check_range("pad_gap", pad_gap, 0.0, pitch, "mm (at most the pitch)", high_open=True)
    return SensorArray(pitch=pitch, node_counts=node_counts, centre=centre, fill_factor=(1.0 - pad_gap / pitch) ** 2,
                       node=CapacitiveNode() if node is None else node, **options)


class Interpolation(Enum):
    """How a sensor frame is taken from a finer simulation time base."""

    LINEAR = "linear"   # linear interpolation between the two neighbouring simulation samples
    HOLD = "hold"       # the latest simulation sample at or before the sensor instant (sample and hold)


_RATE_ROUND_OFF = 1e-9   # fraction of a sensor period forgiven at the end, so t_end = k / f_s keeps sample k


def resample_time_series(times, values, sample_rate_hz: float, interpolation: Interpolation = Interpolation.LINEAR,
                         start_time: float | None = None):
    """Resample ``values`` (T, ...) given at ``times`` (T,) [s] at the sensor rate: instants t0 + k / f_s <= t_end.

    Parameters
    ----------
    times : (T,) float -- strictly increasing simulation times [s].
    values : (T, ...) float -- anything sampled at ``times`` (pressure frames, readings, forces).
    sample_rate_hz : float -- sensor rate f_s [Hz] (the paper's array: 100 Hz).
    interpolation : Interpolation -- LINEAR or HOLD.
    start_time : float, optional -- first sensor instant t0 in [times[0], times[-1]] [s]; default times[0].

    Returns
    -------
    sample_times : (K,) float [s] and samples : (K, ...) float.
    """
    times = check_finite_array("times", times)
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0.0):
        raise ValueError(f"times must be a strictly increasing 1D array, got shape {times.shape}")
    values = np.asarray(values, dtype=float)
    if values.shape[:1] != times.shape:
        raise ValueError(f"values must have {times.size} samples along axis 0, got shape {values.shape}")
    rate = check_positive("sample_rate_hz", sample_rate_hz, "Hz")
    interpolation = Interpolation(interpolation)
    start = times[0] if start_time is None else check_range("start_time", start_time, times[0], times[-1], "s")
    count = int(math.floor((times[-1] - start) * rate + _RATE_ROUND_OFF)) + 1
    sample_times = start + np.arange(count) / rate
    clamped = np.minimum(sample_times, times[-1])
    if interpolation is Interpolation.HOLD:
        index = np.searchsorted(times, clamped + _RATE_ROUND_OFF / rate, side="right") - 1
        return sample_times, values[index]
    upper = np.clip(np.searchsorted(times, clamped, side="right"), 1, max(times.size - 1, 1))
    lower = upper - 1
    if times.size == 1:
        return sample_times, values[np.zeros(count, dtype=int)]
    weight = ((clamped - times[lower]) / (times[upper] - times[lower])).reshape((-1,) + (1,) * (values.ndim - 1))
    return sample_times, (1.0 - weight) * values[lower] + weight * values[upper]
