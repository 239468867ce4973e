"""Least-squares planar rigid transform (paper eq. 9) from per-bump positions, closed form, vectorised over time."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

__all__ = ["FrameStatus", "RigidTransformTrace", "fit_rigid_transform"]


class FrameStatus(Enum):
    """Why a frame's rigid transform is (not) valid."""

    OK = "ok"
    NOT_FINITE = "readings or positions not finite"
    NO_CONTACT = "no bump in contact"
    ONE_BUMP = "one bump in contact: rotation undetermined (eq. 9 needs two)"


@dataclass(frozen=True, eq=False)
class RigidTransformTrace:
    """Rigid transform per frame, x' = R(theta) x + t (paper eq. 9).

    Frames whose status is not OK carry theta = 0 and translation = 0 as placeholders, never NaN: check ``valid``.

    Attributes
    ----------
    rotation : (t,) float -- rotational shear displacement theta [rad], counter-clockwise about +z.
    translation : (t, 2) float -- (t_x, t_y) [mm], the image of the origin of the sensor frame.
    residual_rms : (t,) float -- RMS of |R r_i + t - r_i'| over the bumps used [mm] (0 for invalid frames).
    bump_count : (t,) int -- bumps used in each frame.
    status : (t,) object array of FrameStatus.
    """

    rotation: np.ndarray
    translation: np.ndarray
    residual_rms: np.ndarray
    bump_count: np.ndarray
    status: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        """(t,) bool: frames with at least two bumps in contact and finite data."""
        return self.status == FrameStatus.OK


def _rotate(points: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """R(theta) x for points (..., 2) [mm] and angles [rad] broadcasting against points[..., 0]."""
    cos, sin = np.cos(rotation), np.sin(rotation)
    return np.stack([cos * points[..., 0] - sin * points[..., 1], sin * points[..., 0] + cos * points[..., 1]], axis=-1)


def fit_rigid_transform(reference, current, used=None) -> RigidTransformTrace:
    """Rotation and translation best mapping ``reference`` onto ``current`` in least squares (2D Procrustes/Kabsch).

    With centroids r_m, q_m of the used bumps, a_i = r_i - r_m, b_i = q_i - q_m:

        theta = atan2( sum a_i x b_i, sum a_i . b_i ),   t = q_m - R(theta) r_m,

    the exact minimiser of sum |R r_i + t - q_i|^2 (no iteration). With i.i.d. noise sigma per coordinate on q
    and small theta, std(theta) = sigma / sqrt(sum |a_i|^2) and std(t) = sigma / sqrt(N) when r_m = 0.

    Parameters
    ----------
    reference : (k, 2) float -- bump positions in the reference frame r_i [mm].
    current : (t, k, 2) float -- bump positions per frame q_i [mm].
    used : (t, k) bool, optional -- bumps to fit in each frame (those in contact); default all.

    Frames with a non-finite used position get NOT_FINITE; fewer than two used bumps NO_CONTACT / ONE_BUMP.
    """
    reference = np.asarray(reference, dtype=float)
    current = np.asarray(current, dtype=float)
    if reference.ndim != 2 or reference.shape[1] != 2 or not np.all(np.isfinite(reference)):
        raise ValueError(f"reference must be a finite (k, 2) array, got shape {reference.shape}")
    if current.ndim != 3 or current.shape[1:] != reference.shape:
        raise ValueError(f"current must have shape (t, {reference.shape[0]}, 2), got {current.shape}")
    used = np.ones(current.shape[:2], dtype=bool) if used is None else np.asarray(used, dtype=bool)
    if used.shape != current.shape[:2]:
        raise ValueError(f"used must have shape {current.shape[:2]}, got {used.shape}")
    finite = np.all(np.isfinite(current) | ~used[..., None], axis=(1, 2))                 # (t,)
    weight = (used & finite[:, None]).astype(float)                                      # (t, k)
    count = weight.sum(axis=1)                                                           # (t,)
    safe_count = np.maximum(count, 1.0)[:, None]
    positions = np.where(weight[..., None] > 0.0, current, 0.0)                          # (t, k, 2), NaN-free
    reference_mean = weight @ reference / safe_count                                     # (t, 2)
    current_mean = np.einsum("tk,tkd->td", weight, positions) / safe_count               # (t, 2)
    a = reference[None] - reference_mean[:, None]                                        # (t, k, 2)
    b = positions - current_mean[:, None]
    cross = np.sum(weight * (a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]), axis=1)     # (t,)
    dot = np.sum(weight * np.sum(a * b, axis=-1), axis=1)
    status = np.full(len(current), FrameStatus.OK, dtype=object)
    status[count == 1] = FrameStatus.ONE_BUMP
    status[count == 0] = FrameStatus.NO_CONTACT
    status[~finite] = FrameStatus.NOT_FINITE
    valid = status == FrameStatus.OK
    rotation = np.where(valid, np.arctan2(cross, dot), 0.0)
    translation = np.where(valid[:, None], current_mean - _rotate(reference_mean, rotation), 0.0)        # (t, 2)
    mapped = _rotate(reference[None], rotation[:, None]) + translation[:, None]          # (t, k, 2)
    misfit = np.sum((mapped - positions) ** 2, axis=-1)                                  # (t, k) [mm^2]
    residual_rms = np.where(valid, np.sqrt(np.sum(weight * misfit, axis=1) / safe_count[:, 0]), 0.0)
    return RigidTransformTrace(rotation, translation, residual_rms, count.astype(int), status)
