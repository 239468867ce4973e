"""Reduced-model contact of the two fingertips with the object: the kernel's arrays and their views (mm, N, N mm).

The only place where SI (MuJoCo) meets mm / N / N mm (the reduced model): ``_kernel.physics_step`` converts, this
class lays out its configuration and state and shows the per-bump results to the sensing chain. Finger f's sensor
frame has its normal z_s toward the object (+y for the left finger, -y for the right), x_s = +x, y_s = z_s x x_s.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from contact.reduced import ReducedFingertip
from controller.control.acceleration_control import AccelerationControlParameters, ForceFeedback
from controller.control.filters import FirstOrderLowPass

from . import _kernel as K
from ._trial import MM_PER_M, GraspObject

FRAMES = np.array([[[1, 0, 0], [0, 0, -1], [0, 1, 0]],
                   [[1, 0, 0], [0, 0, 1], [0, -1, 0]]], dtype=float)          # (2 fingers, rows x_s y_s z_s, 3)
FACE_SIGN = np.array([1.0, -1.0])          # depth d = half_y + sign * y_object: the left finger touches the -y face
FINGER_MASS = 0.01                          # kg, the finger body (its travel adds the actuator armature J_n / r^2)
FINGER_DAMPING = 0.4                        # N s/m, finger slide


class ContactBridge:
    """Contact state of both fingertips and the compiled step that advances it (``step``).

    Parameters
    ----------
    model : mujoco.MjModel -- the world of ``_world._mjcf`` (bodies "object", "arm"; mocap fingers).
    tip : ReducedFingertip -- both fingertips.
    obj : GraspObject -- the object (its half sizes bound the faces).
    friction_coefficient : float -- Coulomb friction coefficient fingertip-object [-].
    acceleration : AccelerationControlParameters -- the actuator loop (its rate sets the sub-steps).
    finger_offset_m : float -- distance of each finger origin from the grasp axis at zero closing [m].
    implicit : bool -- couple the contact to the object implicitly (``_kernel``); False: explicitly, for comparison.
    friction_anisotropy : float -- e: friction mu (1 + e) along the sensor's x, mu (1 - e) along y (the plant's).
    """

    def __init__(self, model, tip: ReducedFingertip, obj: GraspObject, friction_coefficient: float,
                 acceleration: AccelerationControlParameters, finger_offset_m: float, implicit: bool = True,
                 friction_anisotropy: float = 0.0):
        import mujoco

        body = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)       # noqa: E731
        joint = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)     # noqa: E731
        self.object_id, self.arm_id = body("object"), body("arm")
        substeps = acceleration.sample_rate_hz * float(model.opt.timestep)
        p = tip.parameters
        armature = acceleration.nominal_inertia / MM_PER_M / (acceleration.arm_radius / MM_PER_M) ** 2   # kg
        config = np.zeros(K.C_SIZE)
        config[[K.C_NORMAL_STIFFNESS, K.C_RADIUS_COEFFICIENT, K.C_TANGENTIAL_MODULUS, K.C_TORSIONAL_MODULUS,
                K.C_DAMPING_TIME, K.C_FRICTION]] = (p.normal_stiffness, p.radius_coefficient, p.tangential_modulus,
                                                    p.torsional_modulus, p.damping_time, friction_coefficient)
        config[K.C_OBJECT_MASS] = model.body_mass[self.object_id]
        config[[K.C_INERTIA_X, K.C_INERTIA_Y, K.C_INERTIA_Z]] = model.body_inertia[self.object_id]
        config[[K.C_FINGER_MASS, K.C_FINGER_DAMPING]] = FINGER_MASS + armature, FINGER_DAMPING
        config[K.C_FINGER_OFFSET] = finger_offset_m * MM_PER_M
        config[[K.C_ARM_RADIUS, K.C_NOMINAL_INERTIA, K.C_TARGET_INERTIA, K.C_TARGET_DAMPING, K.C_TORQUE_LIMIT]] = (
            acceleration.arm_radius, acceleration.nominal_inertia, acceleration.target_inertia,
            acceleration.target_damping, acceleration.torque_limit)
        config[K.C_DOB_GAIN] = FirstOrderLowPass(acceleration.dob_cutoff_hz, acceleration.sample_rate_hz)._gain
        config[K.C_FORCE_OBSERVER] = float(acceleration.force_feedback is ForceFeedback.OBSERVER)
        config[K.C_USE_DOB] = 1.0
        config[K.C_IMPLICIT] = 1.0 if implicit else 0.0
        config[K.C_ANISOTROPY] = friction_anisotropy
        config[K.C_MAX_DEPTH] = tip.design.bump_radius
        config[K.C_SUBSTEPS], config[K.C_STEP] = round(substeps), float(model.opt.timestep)
        config[[K.C_HALF_X, K.C_HALF_Y, K.C_HALF_Z]] = 0.5 * np.asarray(obj.size) * MM_PER_M
        config[[K.C_OBJECT_BODY, K.C_ARM_BODY]] = self.object_id, self.arm_id
        config[K.C_OBJECT_DOF] = model.jnt_dofadr[joint("object")]
        config[K.C_ARM_DOF] = model.jnt_dofadr[joint("lift")]
        self.config = config
        self.count = len(tip.centres)
        offsets = np.einsum("kc,fcd->fkd", tip.centres, FRAMES[:, :2])                     # (2, k, 3) [mm]
        geometry = np.zeros((2, self.count, K.G_SIZE))
        geometry[..., K.G_OFFSET:K.G_OFFSET + 3] = offsets
        for axis, column in enumerate((K.G_X, K.G_Y, K.G_Z)):
            geometry[..., column:column + 3] = FRAMES[:, None, axis]
        geometry[..., K.G_FACE] = FACE_SIGN[:, None]
        self.geometry = geometry.reshape(-1, K.G_SIZE)
        self.state = np.zeros(K.S_SIZE)
        self.bumps = np.zeros((2 * self.count, K.B_SIZE))
        self.out = np.zeros((2 * self.count, K.O_SIZE))

    def step(self, data, force_command: float) -> None:
        """Advance gripper and contact by one physics step; leaves the wrenches in ``data.xfrc_applied``."""
        K.physics_step(self.config, self.geometry, self.state, self.bumps, self.out, data.xpos, data.xmat,
                       data.xipos, data.qvel, data.xfrc_applied, data.mocap_pos, np.array([float(force_command)]))

    def run(self, model, data, commands: np.ndarray, lift_targets: np.ndarray, grasp_local: np.ndarray,
            record: np.ndarray) -> None:
        """``len(commands)`` physics steps (contact step, then ``mj_step``) with grasp-force commands (n, m) [N] (m
        control steps per physics step) and lift targets (n,) [m], in compiled code; the block's end into
        ``record`` (``_kernel.R_*``: grip force, object height, grasp point relative to the arm, rotation, sliding
        bumps) for the grasp point ``grasp_local`` [m] in the object's frame."""
        K.run_block(commands, lift_targets, *self.compiled_inputs(model, data), mujoco_step_function(), grasp_local,
                    record)

    def compiled_inputs(self, model, data) -> tuple:
        """The arrays and addresses ``run`` passes to the compiled block, in ``_fused.run_frames``' order."""
        return (self.config, self.geometry, self.state, self.bumps, self.out, data.xpos, data.xmat, data.xipos,
                data.qvel, data.xfrc_applied, data.mocap_pos, data.ctrl, model._address, data._address)

    def _field(self, column) -> np.ndarray:
        return self.out[:, column].reshape(2, self.count)

    @property
    def normal_force(self) -> np.ndarray:
        """Per-bump normal force (2, k) [N], mean over the last step's sub-steps."""
        return self._field(K.O_NORMAL)

    @property
    def contact_radius(self) -> np.ndarray:
        """Per-bump contact radius (2, k) [mm]."""
        return self._field(K.O_RADIUS)

    @property
    def shear_displacement(self) -> np.ndarray:
        """Per-bump elastic shear displacement (2, k, 2) [mm] in the sensor frame."""
        return self.out[:, [K.O_ELASTIC_X, K.O_ELASTIC_Y]].reshape(2, self.count, 2)

    @property
    def tangential_force(self) -> np.ndarray:
        """Per-bump tangential force (2, k, 2) [N] of the bump law (without the viscous term)."""
        return self.out[:, [K.O_TANGENTIAL_X, K.O_TANGENTIAL_Y]].reshape(2, self.count, 2)

    @property
    def bump_states(self) -> np.ndarray:
        """Per-bump states (2, k, 4) of the plant: normal force [N], tangential force (sensor frame) [N], torque
        about the bump's axis [N mm]."""
        states = np.empty((2, self.count, 4))
        states[..., 0], states[..., 1:3], states[..., 3] = self.normal_force, self.tangential_force, \
            self._field(K.O_TORQUE)
        return states

    @property
    def sliding(self) -> np.ndarray:
        """Bumps on their combined friction limit (2, k) bool."""
        return self._field(K.O_SLIDING) > 0.0

    @property
    def grip_force_n(self) -> float:
        """Normal force per finger [N], mean of the two fingers over the last step."""
        return float(self.state[K.S_GRIP_FORCE])

    @property
    def peak_force_n(self) -> float:
        """Largest normal force of one finger over every sub-step so far [N]."""
        return float(self.state[K.S_PEAK_FORCE])

    @property
    def closing_m(self) -> float:
        """Closing of each finger from its start [m]."""
        return float(self.state[K.S_CLOSING])


@functools.lru_cache(maxsize=1)
def mujoco_step_function():
    """MuJoCo's ``mj_step`` as a ctypes function of (mjModel*, mjData*), for the compiled loop (``_kernel.run_block``).

    The same shared library the ``mujoco`` bindings loaded (their ``libmujoco.so``), so both step one mjData.
    """
    import ctypes

    import mujoco

    folder = Path(mujoco.__file__).parent
    candidates = sorted(folder.glob("libmujoco.so*")) + sorted(folder.glob("libmujoco*.dylib")) + \
        sorted(folder.glob("mujoco*.dll"))
    if not candidates:
        raise RuntimeError(f"MuJoCo's shared library was not found in {folder}; the compiled loop needs it")
    function = ctypes.CDLL(str(candidates[0])).mj_step
    function.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    function.restype = None
    return function
