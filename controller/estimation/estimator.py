"""Slip estimator on sensor readings: per-bump CoP and peak, shear displacement, rigid transform (eq. 9), stick ratio.

Paper sec. IV: each elastic hemisphere (bump) of the fingertip presses on its own patch of the pressure array. The
centre of pressure (CoP) or the maximum-pressure point of that patch moves with the bump's shear displacement; the
shift against a reference frame (pressed, not yet sheared), times a gain fitted on FEM data (``calibration``), is
the bump's shear displacement, and the least-squares rigid transform of all bumps in contact gives the rotational
and translational shear displacement (eq. 9). Readings only: the estimator knows no mesh and no true displacement.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from contact.theory import stick_ratio_from_rotation, stick_ratio_from_shear_displacement
from fem.validation import check_finite_array, check_positive, check_range

from .calibration import EstimatorCalibration, PositionSource
from .rigid_transform import FrameStatus, RigidTransformTrace, fit_rigid_transform
from controller.sensing.sensor import SensorArray

__all__ = [
    "BumpLayout",
    "BumpReference",
    "EstimatorSettings",
    "GATE_POOL_WIDTH",
    "gate_pool_for",
    "gated_weights",
    "SlipEstimate",
    "bump_positions",
    "estimate_slip",
    "rotational_stick_ratio",
    "translational_stick_ratio",
]


@dataclass(frozen=True)
class BumpLayout:
    """Bump (hemisphere) centres on the sensor plane and the sensor nodes that belong to each bump.

    Parameters
    ----------
    centres : sequence of (x, y) -- bump centres [mm], k >= 1, distinct.
    region_radius : float or None -- a node belongs to the bump whose centre is nearest (Voronoi cell, ties to the
        lower index) and, if given, lies within this distance of it [mm].
    """

    centres: tuple[tuple[float, float], ...]
    region_radius: float | None = None

    def __post_init__(self):
        centres = check_finite_array("centres", self.centres)
        if centres.ndim != 2 or centres.shape[1] != 2 or len(centres) < 1:
            raise ValueError(f"centres must have shape (k, 2) with k >= 1, got {centres.shape}")
        if len(np.unique(centres, axis=0)) != len(centres):
            raise ValueError("centres must be distinct")
        object.__setattr__(self, "centres", tuple(map(tuple, centres.tolist())))
        if self.region_radius is not None:
            object.__setattr__(self, "region_radius", check_positive("region_radius", self.region_radius, "mm"))

    @classmethod
    def grid(cls, counts: tuple[int, int] = (3, 3), spacing: float = 13.0, centre=(0.0, 0.0),
             region_radius: float | None = None) -> "BumpLayout":
        """Regular (nx, ny) bump grid at ``spacing`` [mm] centred on ``centre`` [mm] (paper: 3 x 3 on 40 x 40 mm)."""
        spacing = check_positive("spacing", spacing, "mm")
        offsets = [(np.arange(c) - 0.5 * (c - 1)) * spacing for c in counts]
        grid_x, grid_y = np.meshgrid(offsets[0] + centre[0], offsets[1] + centre[1])
        return cls(np.stack([grid_x.ravel(), grid_y.ravel()], axis=1), region_radius)

    @property
    def centre_array(self) -> np.ndarray:
        """Bump centres (k, 2) [mm]."""
        return np.array(self.centres, dtype=float)

    def regions(self, array: SensorArray) -> np.ndarray:
        """(k, ny, nx) bool: the nodes of each bump; raises ValueError if a bump gets no node."""
        offset = array.node_positions[None] - self.centre_array[:, None, None, :]           # (k, ny, nx, 2)
        distance = np.linalg.norm(offset, axis=-1)                                          # (k, ny, nx)
        regions = np.arange(len(self.centres))[:, None, None] == np.argmin(distance, axis=0)[None]
        if self.region_radius is not None:
            regions &= distance <= self.region_radius
        empty = np.flatnonzero(~regions.any(axis=(1, 2)))
        if empty.size:
            raise ValueError(f"bump {int(empty[0])} at {self.centres[empty[0]]} mm has no sensor node in its region "
                             f"({empty.size} such bumps); move it onto the array or enlarge region_radius")
        return regions


@dataclass(frozen=True)
class EstimatorSettings:
    """Thresholds of the estimator.

    Parameters
    ----------
    contact_threshold : float -- a bump is in contact when its summed reading exceeds this [N], >= 0.
    node_floor : float -- node readings at or below this count as zero in forces and CoP [N] (noise gate), >= 0.
    gate_pool : int -- odd side, in nodes, of the square around each node whose readings decide its gate: a node
        counts when the sum over the pool's nodes on the array exceeds ``node_floor`` x sqrt(their number) (the
        same sigmas of the sum's noise); 1: the node alone (``gate_pool_for`` sizes it for an array). A node of an
        open pool counts with its own reading, negative noise included (zero-mean noise then averages out).
    """

    contact_threshold: float = 0.01
    node_floor: float = 0.0
    gate_pool: int = 1

    def __post_init__(self):
        check_range("contact_threshold", self.contact_threshold, 0.0, math.inf, "N")
        check_range("node_floor", self.node_floor, 0.0, math.inf, "N")
        if isinstance(self.gate_pool, bool) or not isinstance(self.gate_pool, (int, np.integer)) \
                or self.gate_pool < 1 or self.gate_pool % 2 == 0:
            raise ValueError(f"gate_pool={self.gate_pool!r} must be an odd positive number of nodes")


# side [mm] of the pool that decides a node's noise gate: the paper's 3 mm node. A finer array's node reads a
# fraction of a 3 mm node's force over the same converter noise (a 1 mm node a ninth: a light bump's rim at 1-3
# sigmas), and gated node by node it loses the rim - a third of a 0.5 N bump's force at 1 mm, its CoP then following
# the peak; pooled to ~3 mm the gate sees 3 sigmas of the pool, and each node still counts at its own place.
GATE_POOL_WIDTH = 3.0


def gate_pool_for(pitch: float) -> int:
    """The odd number of nodes nearest GATE_POOL_WIDTH / pitch, at least 1 (1 for the paper's 3 mm array)."""
    check_range("pitch", pitch, 0.0, math.inf, "mm", low_open=True)
    return 2 * int(math.floor(GATE_POOL_WIDTH / pitch / 2.0)) + 1


def gated_weights(readings: np.ndarray, settings: EstimatorSettings) -> np.ndarray:
    """Readings (..., ny, nx) [N] where the node's gate is open (``EstimatorSettings.gate_pool``), else 0."""
    pool = settings.gate_pool
    if pool == 1:
        return np.where(readings > settings.node_floor, readings, 0.0)
    from scipy.ndimage import uniform_filter

    size = (1,) * (readings.ndim - 2) + (pool, pool)
    pooled = uniform_filter(readings, size=size, mode="constant", cval=0.0) * (pool * pool)   # sum over the pool
    # nodes of each pool on the array (fewer at its edges): the sum's noise is sqrt(members) node sigmas
    members = uniform_filter(np.ones(readings.shape[-2:]), size=(pool, pool), mode="constant") * (pool * pool)
    return np.where(pooled > settings.node_floor * np.sqrt(np.rint(members)), readings, 0.0)


def _check_readings(readings, array: SensorArray) -> np.ndarray:
    readings = np.asarray(readings, dtype=float)
    if readings.ndim not in (2, 3) or readings.shape[-2:] != array.shape:
        raise ValueError(f"readings must have shape (ny, nx) or (t, ny, nx) = (..., {array.shape[0]}, "
                         f"{array.shape[1]}), got {readings.shape}")
    return readings.reshape((-1,) + array.shape)


def _parabolic_offset(before: np.ndarray, centre: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Vertex of the parabola through (-1, before), (0, centre), (1, after) [node spacings], clipped to +-1/2.

    delta = (before - after) / (2 (before - 2 centre + after)); 0 where a neighbour is missing (NaN, array edge) or
    the three values are not concave.
    """
    curvature = before - 2.0 * centre + after
    usable = np.isfinite(curvature) & (curvature < 0.0)
    delta = np.where(usable, 0.5 * (before - after) / np.where(usable, curvature, -1.0), 0.0)
    return np.clip(delta, -0.5, 0.5)


def bump_positions(readings, array: SensorArray, layout: BumpLayout, settings: EstimatorSettings = EstimatorSettings()):
    """Per-bump force, centre of pressure and maximum-pressure point of finite readings.

    force_i = sum_{n in region i} w_n,  CoP_i = sum w_n x_n / force_i,  w_n = reading_n where the node's gate is
    open (its reading, or its pool's sum, above the floor: ``EstimatorSettings``), else 0.
    The peak is the largest reading of the region, refined by a 3-point parabola along x through its row and
    along y through its column (exact for a quadratic peak; neighbours may lie in the next bump's region; no
    refinement across the array edge). Where a bump's force is 0 both positions are its layout centre.

    Parameters
    ----------
    readings : (ny, nx) or (t, ny, nx) float -- finite node readings [N].

    Returns
    -------
    force : (t, k) [N], cop : (t, k, 2) [mm], peak : (t, k, 2) [mm].
    """
    readings = _check_readings(readings, array)
    if not np.all(np.isfinite(readings)):
        raise ValueError("readings must be finite here; estimate_slip flags non-finite frames instead")
    regions = layout.regions(array)                                                         # (k, ny, nx)
    weights = gated_weights(readings, settings)                                             # (t, ny, nx)
    force = np.einsum("tyx,kyx->tk", weights, regions)                                      # (t, k)
    moment = np.einsum("tyx,kyx,yxd->tkd", weights, regions, array.node_positions)          # (t, k, 2) [N mm]
    defined = force > 0.0
    centres = layout.centre_array[None]                                                     # (1, k, 2)
    cop = np.where(defined[..., None], moment / np.where(defined, force, 1.0)[..., None], centres)
    masked = np.where(regions[None], readings[:, None], -np.inf)                            # (t, k, ny, nx)
    flat_peak = np.argmax(masked.reshape(masked.shape[:2] + (regions[0].size,)), axis=2)   # (t, k)
    row, column = np.unravel_index(flat_peak, array.shape)
    padded = np.pad(readings, ((0, 0), (1, 1), (1, 1)), constant_values=np.nan)             # (t, ny+2, nx+2)
    frame = np.arange(len(readings))[:, None]
    value = lambda dj, di: padded[frame, row + 1 + dj, column + 1 + di]                      # noqa: E731  (t, k)
    offset_x = _parabolic_offset(value(0, -1), value(0, 0), value(0, 1))
    offset_y = _parabolic_offset(value(-1, 0), value(0, 0), value(1, 0))
    peak = np.stack([array.node_x[column] + offset_x * array.pitch, array.node_y[row] + offset_y * array.pitch], -1)
    return force, cop, np.where(defined[..., None], peak, centres)


@dataclass(frozen=True, eq=False)
class BumpReference:
    """Per-bump reference positions: the unsheared frame the shifts are measured from.

    Attributes
    ----------
    cop : (k, 2) float -- reference centres of pressure [mm].
    peak : (k, 2) float -- reference maximum-pressure points [mm].
    in_contact : (k,) bool -- bumps measured in contact in the reference frame; the others use the layout centre.
    """

    cop: np.ndarray
    peak: np.ndarray
    in_contact: np.ndarray

    @classmethod
    def from_layout(cls, layout: BumpLayout) -> "BumpReference":
        """Geometric reference: every position is the bump centre (no bump measured)."""
        centres = layout.centre_array
        return cls(centres, centres.copy(), np.zeros(len(centres), dtype=bool))

    @classmethod
    def from_readings(cls, readings, array: SensorArray, layout: BumpLayout,
                      settings: EstimatorSettings = EstimatorSettings()) -> "BumpReference":
        """Reference from the pressed but unsheared readings (ny, nx), or the mean of (t, ny, nx) frames to cut noise.

        A bump whose reference force is at most ``contact_threshold`` keeps its layout centre.
        """
        readings = _check_readings(readings, array).mean(axis=0)
        force, cop, peak = bump_positions(readings, array, layout, settings)
        in_contact = force[0] > settings.contact_threshold
        centres = layout.centre_array
        return cls(np.where(in_contact[:, None], cop[0], centres), np.where(in_contact[:, None], peak[0], centres),
                   in_contact)

    def positions(self, source: PositionSource) -> np.ndarray:
        """Reference positions (k, 2) [mm] of the chosen source."""
        return self.cop if PositionSource(source) is PositionSource.COP else self.peak


@dataclass(frozen=True, eq=False)
class SlipEstimate:
    """Estimator output for a trace of t frames and k bumps; NaN-free (invalid entries are zeros, see flags).

    Attributes
    ----------
    bump_force : (t, k) float -- summed readings per bump [N] (0 in non-finite frames).
    in_contact : (t, k) bool -- bump_force > contact_threshold in a finite frame.
    cop, peak : (t, k, 2) float -- centre of pressure and maximum-pressure point [mm] (layout centre if no force).
    cop_shift, peak_shift : (t, k, 2) float -- position minus reference position [mm], 0 where not in contact.
    shear_displacement : (t, k, 2) float -- gain * shift of the calibrated source [mm], 0 where not in contact.
    transform : RigidTransformTrace -- eq. 9 fitted to reference -> reference + shear_displacement over the bumps
        in contact; ``transform.valid`` / ``transform.status`` say which frames have one.
    """

    bump_force: np.ndarray
    in_contact: np.ndarray
    cop: np.ndarray
    peak: np.ndarray
    cop_shift: np.ndarray
    peak_shift: np.ndarray
    shear_displacement: np.ndarray
    transform: RigidTransformTrace


def estimate_slip(readings, array: SensorArray, layout: BumpLayout, reference: BumpReference | None = None,
                  calibration: EstimatorCalibration = EstimatorCalibration(),
                  settings: EstimatorSettings = EstimatorSettings()) -> SlipEstimate:
    """Per-bump shear displacement and the eq. 9 rigid transform for a whole trace in one call.

    u_i = gain * (position_i - reference_i) for the bumps in contact, position the CoP or the peak as
    ``calibration.position`` says; the rigid transform maps the reference positions onto reference + u_i.
    A frame with any non-finite reading is flagged (status NOT_FINITE, no bump in contact) rather than raised,
    so one sensor dropout does not stop a closed loop; an empty frame (no bump above the threshold) gets
    NO_CONTACT, a single bump ONE_BUMP. A trace of zero frames returns zero-length arrays.

    Parameters
    ----------
    readings : (ny, nx) or (t, ny, nx) float -- sensor readings [N] (``controller.sensing.sensor.sample``).
    array, layout : the sensor and bump geometry.
    reference : BumpReference, optional -- unsheared positions; default the layout centres.
    calibration : EstimatorCalibration -- gain and position source.
    settings : EstimatorSettings -- contact threshold and node noise gate.
    """
    readings = _check_readings(readings, array)
    reference = BumpReference.from_layout(layout) if reference is None else reference
    if reference.cop.shape != (len(layout.centres), 2) or reference.peak.shape != reference.cop.shape:
        raise ValueError(f"reference positions must have shape ({len(layout.centres)}, 2), got {reference.cop.shape}")
    finite = np.all(np.isfinite(readings), axis=(1, 2))                                    # (t,)
    force, cop, peak = bump_positions(np.where(finite[:, None, None], readings, 0.0), array, layout, settings)
    in_contact = (force > settings.contact_threshold) & finite[:, None]                     # (t, k)
    cop_shift = np.where(in_contact[..., None], cop - reference.cop, 0.0)
    peak_shift = np.where(in_contact[..., None], peak - reference.peak, 0.0)
    shift = cop_shift if calibration.position is PositionSource.COP else peak_shift
    shear_displacement = calibration.gain * shift
    start = reference.positions(calibration.position)
    transform = fit_rigid_transform(start, start[None] + shear_displacement, used=in_contact)
    status = np.where(finite, transform.status, FrameStatus.NOT_FINITE)
    return SlipEstimate(force, in_contact, cop, peak, cop_shift, peak_shift, shear_displacement,
                        dataclasses.replace(transform, status=status))


def _positive_array(name: str, values, unit: str = "") -> np.ndarray:
    array = check_finite_array(name, values)
    if np.any(array <= 0.0):
        raise ValueError(f"{name} must be > 0 {unit}, got minimum {array.min()!r}".rstrip())
    return array


def translational_stick_ratio(shear_displacement, normal_force, friction_coefficient, effective_modulus,
                              tangential_modulus, profile_constant, profile_order=2.0) -> np.ndarray:
    """Stick ratio c/a [-] of a bump from its shear displacement vector (..., 2) [mm] (corrected eq. 7).

    c/a = [1 - G* |u| / (mu E* d)]^(1/n), d the indentation depth under ``normal_force`` P [N] of the profile
    C_n r^n (``contact.theory.stick_ratio_from_shear_displacement``; 0 once |u| reaches gross slip). Pass only
    bumps in contact (P > 0), e.g. ``estimate.shear_displacement[estimate.in_contact]``. Moduli E*, G* [MPa],
    C_n [mm^(1-n)]; mu the friction coefficient, which the estimate itself does not need.
    """
    displacement = check_finite_array("shear_displacement", shear_displacement)
    if displacement.shape[-1:] != (2,):
        raise ValueError(f"shear_displacement must have shape (..., 2), got {displacement.shape}")
    return stick_ratio_from_shear_displacement(np.linalg.norm(displacement, axis=-1),
                                               _positive_array("normal_force", normal_force, "N"),
                                               friction_coefficient, effective_modulus, tangential_modulus,
                                               profile_constant, profile_order)


def rotational_stick_ratio(rotation, normal_force, friction_coefficient, contact_radius, shear_modulus) -> np.ndarray:
    """Stick ratio c/a [-] from the rotational shear displacement theta [rad] (exact replacement of eq. 8).

    Lubkin's twist theta(c) = mu P / (G a^2) f(c/a) (docs/theory.md, sec. 6.3), so c/a depends only on the normalised
    twist theta G a^2 / (mu P); ``contact.theory.stick_ratio_from_rotation`` is evaluated at P = mu = a = G = 1 with
    it, which vectorises over arrays of P, a (it takes scalar P, a). |theta| is used (the sign is the direction).
    P [N], a [mm] and G [MPa] must be > 0; a is the radius of the single contact the paper's model assumes.
    """
    rotation = check_finite_array("rotation", rotation)
    scale = (_positive_array("shear_modulus", shear_modulus, "MPa") * _positive_array("contact_radius", contact_radius,
             "mm") ** 2 / (_positive_array("friction_coefficient", friction_coefficient)
                           * _positive_array("normal_force", normal_force, "N")))
    return stick_ratio_from_rotation(np.abs(rotation) * scale, 1.0, 1.0, 1.0, 1.0)
