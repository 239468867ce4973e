"""Reduced-model contact of the two fingertips with the object, applied to MuJoCo through xfrc_applied."""

from __future__ import annotations

import math

import numpy as np

from contact.reduced import ReducedFingertip, bump_response, full_stick_stiffness

from ._trial import CONTACT_RATE_HZ, MM_PER_M, GraspObject


class ContactBridge:
    """Reduced-model contact of the two fingertips with the object's y faces, applied through xfrc_applied.

    The only place where SI (MuJoCo) meets mm / N / N mm (reduced model). Finger f's sensor frame has its normal z_s
    toward the object (+y for the left finger, -y for the right), x_s = +x, y_s = z_s x x_s.
    """

    def __init__(self, model, data, tip: ReducedFingertip, obj: GraspObject, friction: float):
        import mujoco

        self.mujoco, self.model, self.data, self.tip, self.friction = mujoco, model, data, tip, friction
        self.object_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")
        self.finger_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("finger_left",
                                                                                          "finger_right")]
        self.frames = np.array([[[1, 0, 0], [0, 0, -1], [0, 1, 0]],
                                [[1, 0, 0], [0, 0, 1], [0, -1, 0]]], dtype=float)      # (2, 3 axes, 3) rows x,y,z_s
        self.face_sign = np.array([1.0, -1.0])                 # d = half_y + sign * y_object (left: -y face)
        self.half_size_mm = np.array(obj.size) * 0.5 * MM_PER_M
        centres = tip.centres                                                          # (k, 2) [mm]
        self.tip_offsets_mm = np.einsum("kc,fcd->fkd", centres, self.frames[:, :2])    # (2, k, 3) world offsets
        shape = (2, len(centres))
        self.anchor_mm = np.zeros(shape + (3,))                # anchors in object coordinates
        self.anchor_angle = np.zeros(shape)                    # object rotation about z_s at the anchor [rad]
        self.touching = np.zeros(shape, dtype=bool)
        self.previous_depth_mm = np.zeros(shape)
        self.previous_elastic_mm = np.zeros(shape + (2,))
        self.period = 1.0 / CONTACT_RATE_HZ
        # public state (mm, N, N mm) for the sensor and the controller
        self.normal_force = np.zeros(shape)
        self.contact_radius = np.zeros(shape)
        self.shear_displacement = np.zeros(shape + (2,))
        self.tangential_force = np.zeros(shape + (2,))
        self.sliding = np.zeros(shape, dtype=bool)
        self.grip_force_n = 0.0

    def object_rotation(self) -> np.ndarray:
        """Object rotation about each finger's normal z_s [rad] (2,): about +y for the left, -y for the right."""
        rotation = self.data.xmat[self.object_id].reshape(3, 3)
        angle = math.atan2(rotation[0, 2], rotation[0, 0])
        return np.array([angle, -angle])

    def update(self) -> None:
        """Evaluate the reduced model at the current poses and write the wrenches to xfrc_applied."""
        data = self.data
        object_position_mm = data.xpos[self.object_id] * MM_PER_M
        object_rotation = data.xmat[self.object_id].reshape(3, 3)
        fingers_mm = data.xpos[self.finger_ids] * MM_PER_M                             # (2, 3)
        tips_mm = fingers_mm[:, None, :] + self.tip_offsets_mm                          # (2, k, 3)
        local_mm = (tips_mm - object_position_mm) @ object_rotation                     # object coordinates
        depth_mm = self.half_size_mm[1] + self.face_sign[:, None] * local_mm[..., 1]
        inside = (np.abs(local_mm[..., 0]) <= self.half_size_mm[0]) & (np.abs(local_mm[..., 2]) <= self.half_size_mm[2])
        touching = (depth_mm > 0.0) & inside
        angle = self.object_rotation()
        new = touching & ~self.touching
        if np.any(new):                                                                 # anchor at first touch
            surface = local_mm.copy()
            surface[..., 1] = -self.face_sign[:, None] * self.half_size_mm[1]
            self.anchor_mm[new] = surface[new]
            self.anchor_angle[new] = np.broadcast_to(angle[:, None], new.shape)[new]
            self.previous_elastic_mm[new] = 0.0
        self.touching = touching
        p = self.tip.parameters
        depth = np.where(touching, depth_mm, 0.0)
        rate = np.where(touching & (self.previous_depth_mm > 0.0), (depth - self.previous_depth_mm) / self.period, 0.0)
        self.previous_depth_mm = depth
        normal = p.normal_stiffness * depth**1.5 + p.damping_time * 1.5 * p.normal_stiffness * np.sqrt(depth) * rate
        normal = np.where(touching, np.maximum(normal, 0.0), 0.0)                       # (2, k) [N]
        anchors_mm = object_position_mm + self.anchor_mm @ object_rotation.T            # world (2, k, 3)
        elastic = np.einsum("fkd,fcd->fkc", anchors_mm - tips_mm, self.frames[:, :2])   # (2, k, 2) sensor plane
        twist = angle[:, None] - self.anchor_angle
        response = bump_response(normal, elastic, twist, self.friction, p)
        # slip: move the anchors so that the elastic part is the one carrying the limit load
        slid = response.sliding
        if np.any(slid):
            target_mm = tips_mm + np.einsum("fkc,fcd->fkd", response.limit_displacement, self.frames[:, :2])
            moved = (target_mm - object_position_mm) @ object_rotation
            moved[..., 1] = self.anchor_mm[..., 1]
            self.anchor_mm[slid] = moved[slid]
            self.anchor_angle[slid] = (angle[:, None] - response.limit_twist)[slid]
        elastic = response.limit_displacement
        stiffness, _ = full_stick_stiffness(normal, p)
        damping = p.damping_time * stiffness[..., None] * (elastic - self.previous_elastic_mm) / self.period
        self.previous_elastic_mm = elastic
        tangential = response.tangential_force + np.where(slid[..., None] | ~touching[..., None], 0.0, damping)
        # forces on the object (world, N): bump pushes along z_s, resists the shear (-Q), torque -T about z_s
        force = (normal[..., None] * self.frames[:, None, 2, :]
                 - np.einsum("fkc,fcd->fkd", tangential, self.frames[:, :2]))           # (2, k, 3)
        torque_nmm = -response.torque[..., None] * self.frames[:, None, 2, :]           # (2, k, 3)
        lever = (tips_mm - data.xipos[self.object_id] * MM_PER_M).reshape(-1, 3)       # (2k, 3) [mm]
        flat = force.reshape(-1, 3)
        moment_nmm = np.array([lever[:, 1] @ flat[:, 2] - lever[:, 2] @ flat[:, 1],
                               lever[:, 2] @ flat[:, 0] - lever[:, 0] @ flat[:, 2],
                               lever[:, 0] @ flat[:, 1] - lever[:, 1] @ flat[:, 0]]) + torque_nmm.sum(axis=(0, 1))
        data.xfrc_applied[self.object_id, :3] = force.sum(axis=(0, 1))
        data.xfrc_applied[self.object_id, 3:] = moment_nmm / MM_PER_M
        for f, body in enumerate(self.finger_ids):
            data.xfrc_applied[body, :3] = -force[f].sum(axis=0)
        self.normal_force, self.contact_radius = normal, response.contact_radius
        self.shear_displacement, self.sliding = elastic, slid
        self.tangential_force = response.tangential_force
        self.grip_force_n = float(normal.sum(axis=1).mean())
