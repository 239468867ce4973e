"""Closed-loop grasp in MuJoCo: a parallel-jaw gripper with two 3x3-array gel fingertips on a lifting arm.

Loop (paper Fig. 7): reduced contact model -> base pressure -> sensor (100 Hz, noise) -> estimator (eq. 9 on a 3x3
BumpLayout) -> GraspForceController (1 kHz) -> AccelerationController with DOB (8 kHz) -> finger motor force, with
MuJoCo stepping at 8 kHz. Sequence: approach, grasp on the table, lift, hold (4 s), place, release. The controller
gets no object data (mass, moment, friction).

How the contact is enforced. MuJoCo's friction is soft (a held object creeps, DESIGN.md), so the fingers and the
object do not collide in MuJoCo (contype/conaffinity 0 on the fingers): every bump tip is a contact of the reduced
model, evaluated at 4 kHz (CONTACT_RATE_HZ) and applied to the object (and, reversed, to the finger) through ``xfrc_applied``:

* normal: P_i = k_n d_i^(3/2) (1 + tau_d 1.5 d_i'/d_i), d_i the penetration of bump tip i into the object's face;
* tangential: at first touch the bump is anchored to the material point of the face it touches (object frame); the
  shear displacement delta_i is the anchor's position relative to the bump tip in the sensor plane and phi_i the
  object's rotation about the fingertip normal since the anchor was set; ``contact.reduced.bump_response`` gives
  the loads (Mindlin, Lubkin, elliptic combined limit), plus a viscous term tau_d k_t delta_i';
* slip: a bump on its friction limit moves its anchor so that its elastic displacement is the one that carries the
  limit load (an elasto-plastic "bristle", one per bump): stick is exact (the anchor does not move, so a held
  object does not creep), partial slip is Mindlin's inside each bump, incipient slip of the array is some bumps
  sliding, gross slip (translation or rotation) all of them.
The world is SI; the reduced model is mm, N, N mm: ``_ContactBridge`` converts at one place (names carry the unit).
Object-table contact stays MuJoCo's (elliptic cone): it only decides when the object leaves or touches the table.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from contact.reduced import ReducedFingertip, bump_response, full_stick_stiffness
from controller import (AccelerationControlParameters, AccelerationController, BumpLayout, BumpReference,
                        EstimatorCalibration, EstimatorSettings, GraspForceController, GraspForceParameters,
                        GraspPhase, ReferenceGenerator, ReferenceParameters, SensorArray, bump_positions, calibrate_gain, cell_force_operator,
                        estimate_slip, sample)
from controller.sensor import PressureField
from fem.validation import check_range

__all__ = ["GraspObject", "TABLE_I_OBJECTS", "TargetDesign", "TrialSettings", "TrialResult", "GraspWorld", "SensingChain",
           "run_trial", "random_settings", "required_grip_force", "DESIGN_FRICTION"]

GRAVITY = 9.81                      # m/s^2
MM_PER_M = 1000.0
PHYSICS_RATE_HZ = 8000.0            # MuJoCo step = acceleration-control rate (paper: 8 kHz)
# reduced-model contact update (explicit): omega dt <= 0.35 and damping c dt / m <= 0.9 must hold at the stiffest
# contact. At 2 kHz the light eclair between two FEM-calibrated fingertips (k_n 14 % above Hertz) broke the first
# above ~2 N per bump: it rattled between the fingers, one losing contact each step, and turned out (the two Table I
# failures of an earlier run); 4 kHz and 8 kHz give the same trial to 0.1 mrad and 0.01 N.
CONTACT_RATE_HZ = 4000.0
DESIGN_FRICTION = 0.4               # lowest friction the controller targets are designed for (mu range 0.4-1.0)
APPROACH_GAP_M = 0.001              # initial gap between each bump tip and the object face
LIFT_HEIGHT_M = 0.05
GRID_SPACING = 1.0                  # mm, base-pressure grid (kernel radius >= 4.7 mm; sensor cells 3 mm)
TORQUE_LIMIT = 1500.0               # N mm, finger actuator (30 N per finger at the 50 mm arm radius)
ARM_RADIUS = AccelerationControlParameters().arm_radius      # mm per rad of the finger drive
TABLE_CLEARANCE_M = 0.001           # object lower than this above the table during the hold = touches the ground
# rad (8.6 deg): an object turned further in the grasp has rotated out of it. With rotational detection the
# moment-loaded objects turn 30-105 mrad while the weight comes off the table in the lift (the grip builds from
# F_min at the loop's rate) and then hold still; the eclair without it turns 180-190 mrad (fig10).
ROTATION_LIMIT = 0.15
# Grasp-force loop rate [rad/s]. The FEM-calibrated fingertip's sensor reads the load ratio (CoP shift = moment arm
# x Q_i / P_i, contact.reduced calibration), not the slip-amplified shear displacement the default 30 rad/s was
# designed on: at 30 rad/s the bottle's grip oscillated between 7 and 29 N at ~2.5 Hz and it turned 115 mrad;
# at 10 rad/s the hold force ripples by 0.09 N (5 rad/s: 0.7 N, slower to follow the lift).
LOOP_RATE = 10.0


@functools.lru_cache(maxsize=1)
def default_tip() -> ReducedFingertip:
    """Both fingertips of the closed loop: the FEM-calibrated 3x3 design shipped with contact.reduced."""
    return ReducedFingertip.calibrated()


@dataclass(frozen=True)
class GraspObject:
    """A box object: mass [kg], size (x, y, z) [m] (y is the grasp width), lever [m]: the CoM's distance from the
    grasp point along x (the moment about the fingertip normal is m g lever), grasp_height [m] of the fingertip
    centre above the table, crush_force [N]: largest normal force per finger it tolerates."""

    name: str
    mass: float
    size: tuple[float, float, float]
    lever: float
    grasp_height: float
    crush_force: float = math.inf

    @property
    def moment_nm(self) -> float:
        return self.mass * GRAVITY * self.lever


# Table I. Levers from the moments: 0.120 N m / (0.251 kg g) = 48.7 mm, 0.039 / (0.104 g) = 38.2 mm.
# Eclair crush force: a filled choux shell is taken to yield at about 10 kPa nominal pressure (soft bakery
# products: 5-20 kPa); over the gel footprint it touches (the 40 mm array across the 30 mm high eclair,
# about 30 x 36 mm = 1000 mm^2) that is 10 N per finger.
TABLE_I_OBJECTS = {
    "bottle_upright": GraspObject("bottle_upright", 0.600, (0.070, 0.060, 0.200), 0.0, 0.060),
    "bottle_horizontal": GraspObject("bottle_horizontal", 0.251, (0.200, 0.070, 0.070), 0.120 / (0.251 * GRAVITY),
                                     0.035),
    "eclair": GraspObject("eclair", 0.104, (0.140, 0.030, 0.030), 0.039 / (0.104 * GRAVITY), 0.015, crush_force=10.0),
}


@dataclass(frozen=True)
class TargetDesign:
    """What the controller's targets are designed for: the lowest friction expected and the load ratios
    Q / (mu P) and T / T_slip at which the bench sets u_x,ref and theta_ref. At a friction mu in full stick the
    controller then holds about mu / (friction load_ratio) times the least force (the displacement hardly depends
    on mu below gross slip), which is its safety factor against an unknown surface."""

    friction: float = DESIGN_FRICTION
    load_ratio: float = 0.6
    torque_ratio: float = 0.6

    def __post_init__(self):
        check_range("targets.friction", self.friction, 0.0, math.inf, low_open=True, high_open=True)
        check_range("targets.load_ratio", self.load_ratio, 0.0, 1.0, low_open=True, high_open=True)
        check_range("targets.torque_ratio", self.torque_ratio, 0.0, 1.0, low_open=True, high_open=True)


@dataclass(frozen=True)
class TrialSettings:
    """One trial: friction fingertip-object, grasp-position jitter (along x, z) [m], object yaw misalignment [rad]
    (the bumps touch one after the other), sensor noise [N per node], constant_force [N] (None: the grasp
    controller; a number: that force throughout, for tau_min), phase durations [s], seed, and what the
    controller's targets are designed for (TargetDesign)."""

    friction: float = 0.8
    grasp_offset: tuple[float, float] = (0.0, 0.0)
    misalignment: float = 0.0
    sensor_noise: float = 0.001
    rotational_slip_detection: bool = True
    constant_force: float | None = None
    hold_time: float = 4.0
    place: bool = True
    seed: int = 0
    targets: TargetDesign = TargetDesign()


@dataclass
class TrialResult:
    """Trace (10 ms rows: time, phase, force command, grip force, u_x, theta, object height, slip, rotation) and
    the verdicts: dropped (object touched the table during the hold), crushed (a finger's normal force exceeded
    the crush force), success, plus statistics: forces [N] per finger, creep [um/s] and rotation creep [mrad/s] of
    the grasp point relative to the gripper after the first 0.5 s of the hold, the largest rotation of the object
    in the grasp during lift and hold [mrad] and ``rotated`` (beyond ROTATION_LIMIT: it turned out of the grasp,
    which the paper's success criterion - no table contact - does not count)."""

    object_name: str
    settings: TrialSettings
    trace: dict = field(default_factory=dict)
    success: bool = False
    dropped: bool = False
    crushed: bool = False
    hold_force_mean: float = math.nan
    hold_force_max: float = math.nan
    max_force: float = math.nan
    minimum_force: float = math.nan
    creep_um_per_s: float = math.nan
    rotation_creep_mrad_per_s: float = math.nan
    hold_slip_mm: float = math.nan
    hold_rotation_mrad: float = math.nan
    max_rotation_mrad: float = math.nan
    wall_time: float = math.nan
    simulated_time: float = math.nan

    @property
    def rotated(self) -> bool:
        return bool(self.max_rotation_mrad > 1e3 * ROTATION_LIMIT)

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second (> 1: faster than real time)."""
        return self.simulated_time / self.wall_time


def _min_jerk(progress):
    s = min(max(progress, 0.0), 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def _mjcf(obj: GraspObject, settings: TrialSettings, tip: ReducedFingertip) -> str:
    hx, hy, hz = (0.5 * s for s in obj.size)
    centre_x = obj.lever + settings.grasp_offset[0]               # box centre (CoM) relative to the grasp point
    grasp_z = obj.grasp_height + settings.grasp_offset[1]
    finger_y = hy + APPROACH_GAP_M
    pad = tip.design.half_extent / MM_PER_M
    armature = AccelerationControlParameters().nominal_inertia / MM_PER_M / (
        ARM_RADIUS / MM_PER_M) ** 2                       # J / r^2 [kg]: 0.1 N mm s^2 -> 0.04 kg
    quat = f"{math.cos(0.5 * settings.misalignment)} 0 0 {math.sin(0.5 * settings.misalignment)}"
    finger = """
      <body name="{name}" pos="0 {y} 0" gravcomp="1">
        <joint name="{name}" type="slide" axis="0 {axis} 0" armature="{armature}" damping="0.4"/>
        <geom type="box" size="{pad} 0.004 {pad}" pos="0 {back} 0" mass="0.01" contype="0" conaffinity="0"
              rgba="0.3 0.6 0.9 0.6"/>
      </body>"""
    fingers = "".join(finger.format(name=name, y=sign * finger_y, axis=-sign, armature=armature, pad=pad,
                                    back=sign * 0.004) for name, sign in (("finger_left", -1), ("finger_right", 1)))
    return f"""
<mujoco model="gel_gripper">
  <option timestep="{1.0 / PHYSICS_RATE_HZ}" gravity="0 0 {-GRAVITY}" cone="elliptic" impratio="10"/>
  <worldbody>
    <geom name="table" type="plane" size="0.5 0.5 0.01" friction="0.5 0.005 0.0001"/>
    <body name="arm" pos="0 0 {grasp_z}" gravcomp="1">
      <joint name="lift" type="slide" axis="0 0 1" damping="300"/>
      <geom type="box" size="0.02 {finger_y + 0.02} 0.01" pos="0 0 {pad + 0.02}" mass="0.5" contype="0"
            conaffinity="0"/>{fingers}
    </body>
    <body name="object" pos="{centre_x} 0 {hz + 1e-4}" quat="{quat}">
      <freejoint/>
      <geom name="object" type="box" size="{hx} {hy} {hz}" mass="{obj.mass}" friction="0.5 0.005 0.0001"
            rgba="0.9 0.6 0.2 1"/>
    </body>
  </worldbody>
  <equality><joint joint1="finger_right" joint2="finger_left" polycoef="0 1 0 0 0"/></equality>
  <actuator>
    <position name="lift" joint="lift" kp="20000"/>
    <motor name="grip_left" joint="finger_left"/>
    <motor name="grip_right" joint="finger_right"/>
  </actuator>
</mujoco>"""


class _ContactBridge:
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


class SensingChain:
    """Reduced model -> base pressure -> sensor (noise) -> estimator for both fingertips (100 Hz), and its bench.

    The bench (noise-free, like the FEM bench of Fig. 9) calibrates the CoP gain on small shifts and sets the
    controller's targets: u_x,ref is what the chain reports when every bump carries Q_i / (mu_low P_i) =
    ``design.load_ratio``, theta_ref when the array carries ``design.torque_ratio`` of its slip torque, at the
    reference force, for the lowest friction expected (``design.friction``). How each target scales with the force
    (``ReferenceParameters`` force exponents) is read off the bench too: a signal that follows the shear displacement
    grows like F^(2/3) at a fixed load ratio, one dominated by the overturning moment h Q / P stays constant
    (exponent 0, a fixed target; negative growths are clipped to 0). The
    controller's inversion exponents (its loop gain) are matched to the chain's measured slopes through the slip
    factors.
    """

    REFERENCE_FORCE = 5.0              # N, bench force for calibration and targets (mid-range of the holds)

    def __init__(self, tip: ReducedFingertip, noise: float = 0.0, rng=None, design: TargetDesign = TargetDesign()):
        self.tip, self.rng, self.design = tip, rng, design
        self.grid = tip.base_grid(GRID_SPACING)
        self.array = SensorArray(noise_std=noise)
        self.layout = BumpLayout.grid((tip.design.cols, tip.design.rows), tip.design.pitch)
        # noise gate at 3 sigma: without it the noise of the empty cells in a bump's region dominates |t| and |theta|
        # at low force (a biased magnitude the controller regulates instead of the shear); the gate in turn biases
        # the CoP of a bump's rim in a force-dependent way, which the bench below sees as well
        self.settings = EstimatorSettings(contact_threshold=max(0.02, 10.0 * noise), node_floor=3.0 * noise)
        self.operator = _operator(tip, self.array)
        self.reference_table = self._reference_table()
        self.calibration = self._calibrate()

    def _readings(self, bump_force, radius, shear, tangential, noisy=True):
        pressure = self.tip.base_pressure(self.grid, bump_force, radius, shear, tangential)
        field = PressureField.from_grid(self.grid.x, self.grid.y, pressure)
        array = self.array if noisy else replace(self.array, noise_std=0.0)
        return sample(field, array, self.rng if noisy else None, self.operator)[0]

    def _bench(self, states):
        """Noise-free readings (t, ny, nx) of reduced-model states and the estimate against the first one."""
        frames = np.stack([self._readings(s.normal_force, s.contact_radius, s.shear_displacement,
                                          s.bump_tangential_force, False) for s in states])
        reference = BumpReference.from_readings(frames[:1], self.array, self.layout, self.settings)
        return estimate_slip(frames, self.array, self.layout, reference,
                             getattr(self, "calibration", EstimatorCalibration()), self.settings)

    def _calibrate(self) -> EstimatorCalibration:
        """CoP gain on small rigid shifts (0, 0.01, 0.02 mm along x, nearly full stick) at the bench force."""
        shifts = (0.0, 0.01, 0.02)
        states = [self.tip.displacement_state(self.REFERENCE_FORCE, (shift, 0.0), 0.0, 1.0) for shift in shifts]
        estimate = self._bench(states)
        truth = np.zeros_like(estimate.cop_shift)
        truth[:, :, 0] = np.asarray(shifts)[:, None]
        return calibrate_gain(estimate.cop_shift[1:], truth[1:])

    def _design_signal(self, force, load_ratio, torque_ratio):
        """(|t|, |theta|) the chain reports at a load ratio (x) or torque ratio (slip torque share) at force P."""
        friction = self.design.friction
        bump_force = np.full(len(self.tip.centres), force / len(self.tip.centres))
        radius = self.tip.parameters.radius_coefficient * np.cbrt(bump_force)
        slip_torque = self.tip.slip_margin(bump_force, radius, friction, (0.0, 0.0), 1.0)[0]
        state = self.tip.load_state(force, (load_ratio * friction * force, 0.0), torque_ratio * slip_torque, friction)
        estimate = self._bench([self.tip.displacement_state(force, (0.0, 0.0), 0.0, friction), state])
        return (float(np.linalg.norm(estimate.transform.translation[1])), abs(float(estimate.transform.rotation[1])))

    def design_references(self) -> ReferenceParameters:
        """Targets, force scaling and slip factors from the bench (class docstring)."""
        force, x, y, step = self.REFERENCE_FORCE, self.design.load_ratio, self.design.torque_ratio, 0.01
        u_ref = self._design_signal(force, x, 0.0)[0]
        theta_ref = self._design_signal(force, 0.0, y)[1]
        # how the signals grow with the force at the design ratios (a hemisphere: u ~ F^(2/3), theta ~ F^(1/3); the
        # array's twist signal ~ F^(2/3) too, its bumps translate; a load-ratio signal, as the FEM-calibrated CoP,
        # does not grow: exponent 0, a fixed target), each channel scaled with its own exponent
        growth = (math.log(self._design_signal(4.0 * force, x, 0.0)[0] / u_ref) / math.log(4.0),
                  math.log(self._design_signal(4.0 * force, 0.0, y)[1] / theta_ref) / math.log(4.0))
        references = ReferenceParameters(u_ref, theta_ref, force, scale_with_force=True,
                                         translational_force_exponent=min(max(growth[0], 0.0), 2.0),
                                         rotational_force_exponent=min(max(growth[1], 0.0), 2.0))
        # |u| / u_ref(F) ~ F^(-e) at a constant load: e from a +-1 % force change at the design load
        span = math.log((1 + step) / (1 - step))
        ratios = []
        for channel, (load, torque) in enumerate(((x, 0.0), (0.0, y))):
            generator = ReferenceGenerator(references)
            values = [self._design_signal(force * scale, load / scale, torque / scale)[channel]
                      / generator.references(GraspPhase.HOLD, force * scale)[channel] for scale in (1 - step, 1 + step)]
            ratios.append(math.log(values[0] / values[1]) / span)
        p_x, p_theta = references.inversion_exponents                  # full-stick law of a single hemisphere
        return replace(references, translational_slip_factor=max(p_x * ratios[0], 1.0),
                       rotational_slip_factor=max(p_theta * ratios[1], 1.0))

    def _reference_table(self):
        """Unsheared bench CoPs per bump against the bump's measured force: (forces (n,) [N], cop (n, k, 2) [mm]).

        The CoP of an unsheared bump is not its centre and moves with the force (the kernel widens, the rim falls
        under the noise gate, the outer kernels leave the sensor): a single reference taken at first touch turns
        every later change of grip force into a spurious shear. The bench tabulates it (a sensor calibration of the
        design, not of the object), and ``sense`` interpolates each bump's reference at its own measured force.
        """
        totals = np.geomspace(0.1, 60.0, 40)                                              # N per fingertip
        states = [self.tip.displacement_state(total, (0.0, 0.0), 0.0, 1.0) for total in totals]
        frames = np.stack([self._readings(s.normal_force, s.contact_radius, s.shear_displacement,
                                          s.bump_tangential_force, False) for s in states])
        force, cop, _ = bump_positions(frames, self.array, self.layout, self.settings)     # (n, k), (n, k, 2)
        seen = force.min(axis=1) > 0.0                                                     # every bump above the gate
        return force[seen].mean(axis=1), cop[seen]

    def _reference_at(self, bump_force):
        """BumpReference interpolated at the measured bump forces (k,) [N] (log-force, clamped at the ends)."""
        forces, cop = self.reference_table
        position = np.interp(np.log(np.maximum(bump_force, forces[0])), np.log(forces), np.arange(len(forces)))
        lower = np.minimum(position.astype(int), len(forces) - 2)
        weight = (position - lower)[:, None]
        index = np.arange(len(bump_force))
        reference = (1.0 - weight) * cop[lower, index] + weight * cop[lower + 1, index]      # (k, 2)
        return BumpReference(reference, reference.copy(), bump_force > self.settings.contact_threshold)

    def sense(self, bridge: _ContactBridge):
        """(u_x [mm], theta [rad], contact_count) seen by the controller: the larger of the two fingertips."""
        u_x, theta, count = 0.0, 0.0, 0
        for f in range(2):
            readings = self._readings(bridge.normal_force[f], bridge.contact_radius[f], bridge.shear_displacement[f],
                                      bridge.tangential_force[f])
            bump_force = bump_positions(readings, self.array, self.layout, self.settings)[0][0]
            estimate = estimate_slip(readings, self.array, self.layout, self._reference_at(bump_force),
                                     self.calibration, self.settings)
            count = max(count, int(estimate.in_contact[0].sum()))
            if estimate.transform.valid[0]:
                u_x = max(u_x, float(np.linalg.norm(estimate.transform.translation[0])))
                theta = max(theta, abs(float(estimate.transform.rotation[0])))
        return u_x, theta, count


_OPERATORS = {}


def _operator(tip: ReducedFingertip, array: SensorArray):
    """Cell-force operator of the reduced model's base grid (cached per design, parameters and array geometry)."""
    key = (repr(tip.to_dict()), array.pitch, array.node_counts, array.centre)
    if key not in _OPERATORS:
        grid = tip.base_grid(GRID_SPACING)
        field = PressureField.from_grid(grid.x, grid.y, np.zeros((len(grid.y), len(grid.x))))
        _OPERATORS[key] = cell_force_operator(field.positions, field.triangles, array)
    return _OPERATORS[key]


class GraspWorld:
    """One trial's MuJoCo world and loop; ``run()`` -> TrialResult.

    Parameters
    ----------
    obj : GraspObject
    settings : TrialSettings
    tip : ReducedFingertip -- both fingertips (default: the FEM-calibrated 3x3 design, ``default_tip``).
    grasp_parameters : GraspForceParameters -- the controller (rotational detection is taken from ``settings``).
    """

    def __init__(self, obj: GraspObject, settings: TrialSettings = TrialSettings(),
                 tip: ReducedFingertip | None = None, grasp_parameters: GraspForceParameters | None = None):
        import mujoco

        self.mujoco = mujoco
        self.obj, self.settings = obj, settings
        self.tip = default_tip() if tip is None else tip
        self.model = mujoco.MjModel.from_xml_string(_mjcf(obj, settings, self.tip))
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.rng = np.random.default_rng(settings.seed)
        self.bridge = _ContactBridge(self.model, self.data, self.tip, obj, settings.friction)
        self.sensing = SensingChain(self.tip, settings.sensor_noise, self.rng, settings.targets)
        base = GraspForceParameters(approach_force=0.5, maximum_force=TORQUE_LIMIT / ARM_RADIUS, loop_rate=LOOP_RATE) \
            if grasp_parameters is None else grasp_parameters
        self.grasp = GraspForceController(replace(base, rotational_slip_detection=settings.rotational_slip_detection),
                                          self.sensing.design_references())
        self.acceleration_parameters = AccelerationControlParameters(torque_limit=TORQUE_LIMIT)
        self.acceleration = AccelerationController(self.acceleration_parameters)
        ids = {name: mujoco.mj_name2id(model_, kind, name) for model_, kind, name in (
            (self.model, mujoco.mjtObj.mjOBJ_JOINT, "finger_left"), (self.model, mujoco.mjtObj.mjOBJ_GEOM, "table"),
            (self.model, mujoco.mjtObj.mjOBJ_GEOM, "object"), (self.model, mujoco.mjtObj.mjOBJ_BODY, "arm"))}
        self.finger_qpos = self.model.jnt_qposadr[ids["finger_left"]]
        self.table_geom, self.object_geom, self.arm_body = ids["table"], ids["object"], ids["arm"]
        self.schedule = self._schedule()

    def _schedule(self):
        """[(end time [s], phase)] of the sequence."""
        s = self.settings
        ends = [("approach", 0.4), ("grasp", 0.3), ("lift", 2.5), ("hold", s.hold_time)]
        if s.place:
            ends += [("place", 2.0), ("release", 0.8)]
        schedule, end = [], 0.0
        for name, length in ends:
            end += length
            schedule.append((end, GraspPhase(name)))
        return schedule

    def _phase_at(self, time_s):
        for index, (end, phase) in enumerate(self.schedule):
            if time_s < end:
                start = self.schedule[index - 1][0] if index else 0.0
                return phase, (time_s - start) / (end - start)
        return None, 1.0

    def _lift_height_m(self, phase, progress) -> float:
        if phase is GraspPhase.LIFT:
            return LIFT_HEIGHT_M * _min_jerk(progress)
        if phase is GraspPhase.HOLD:
            return LIFT_HEIGHT_M
        if phase is GraspPhase.PLACE:
            return LIFT_HEIGHT_M * (1.0 - _min_jerk(progress))
        return 0.0

    def _touches_table(self) -> bool:
        data = self.data
        for i in range(data.ncon):
            geoms = {data.contact[i].geom1, data.contact[i].geom2}
            if geoms == {self.table_geom, self.object_geom}:
                return True
        return False

    def _grasp_point_mm(self):
        """Object motion relative to the gripper: position of the object's initial grasp point relative to the arm
        [mm] (3,) and object rotation about the grasp axis [rad]."""
        data = self.data
        rotation = data.xmat[self.bridge.object_id].reshape(3, 3)
        point = data.xpos[self.bridge.object_id] + rotation @ self._grasp_local_m
        return (point - data.xpos[self.arm_body]) * MM_PER_M, self.bridge.object_rotation()[0]

    def run(self) -> TrialResult:
        """Run the sequence; return the verdicts and a 100 Hz trace."""
        mujoco, model, data, s = self.mujoco, self.model, self.data, self.settings
        physics_per_contact = int(round(PHYSICS_RATE_HZ / CONTACT_RATE_HZ))
        physics_per_grasp = int(round(PHYSICS_RATE_HZ / self.grasp.parameters.sample_rate_hz))
        physics_per_sensor = int(round(PHYSICS_RATE_HZ / self.sensing.array.sample_rate_hz))
        arm_radius = self.acceleration_parameters.arm_radius
        rotation0 = data.xmat[self.bridge.object_id].reshape(3, 3)
        self._grasp_local_m = rotation0.T @ (np.array([0.0, 0.0, data.xpos[self.arm_body][2]])
                                             - data.xpos[self.bridge.object_id])
        rows, hold = [], []
        u_x = theta = 0.0
        count, command, dropped, force_peak, turned = 0, 0.0, False, 0.0, 0.0
        steps = int(round(self.schedule[-1][0] * PHYSICS_RATE_HZ))
        start = time.perf_counter()
        for step in range(steps):
            time_s = step / PHYSICS_RATE_HZ
            phase, progress = self._phase_at(time_s)
            if step % physics_per_contact == 0:
                self.bridge.update()
            if step % physics_per_sensor == 0:
                u_x, theta, count = self.sensing.sense(self.bridge)
            if step % physics_per_grasp == 0:
                command = self.grasp.step(u_x, theta, count, phase)
                if s.constant_force is not None and phase is not GraspPhase.APPROACH:
                    command = s.constant_force if phase is not GraspPhase.RELEASE else 0.0
                data.ctrl[0] = self._lift_height_m(phase, progress)
            closing_mm = data.qpos[self.finger_qpos] * MM_PER_M
            torque_nmm = self.acceleration.step(command, self.bridge.grip_force_n, closing_mm / arm_radius)
            data.ctrl[1] = data.ctrl[2] = torque_nmm / arm_radius                     # motor force [N]
            mujoco.mj_step(model, data)
            force_peak = max(force_peak, float(self.bridge.normal_force.sum(axis=1).max()))
            if step % physics_per_sensor == 0:
                relative_mm, rotation = self._grasp_point_mm()
                height_m = float(data.xpos[self.bridge.object_id][2] - 0.5 * self.obj.size[2])
                rows.append((time_s, phase.value, command, self.bridge.grip_force_n, u_x, theta, height_m,
                             *relative_mm, rotation, int(self.bridge.sliding.sum())))
                if phase in (GraspPhase.LIFT, GraspPhase.HOLD):
                    turned = max(turned, abs(rotation))
                if phase is GraspPhase.HOLD:
                    touching = self._touches_table() or height_m < TABLE_CLEARANCE_M
                    dropped |= touching
                    hold.append((time_s, self.bridge.grip_force_n, *relative_mm, rotation))
        wall = time.perf_counter() - start
        return self._result(rows, hold, dropped, force_peak, turned, wall, steps / PHYSICS_RATE_HZ)

    def _result(self, rows, hold, dropped, force_peak, turned, wall, simulated) -> TrialResult:
        names = ("time", "phase", "force_command", "grip_force", "shear_displacement", "twist_angle",
                 "object_height_m", "slip_x_mm", "slip_y_mm", "slip_z_mm", "rotation", "sliding_bumps")
        trace = {name: [row[i] for row in rows] for i, name in enumerate(names)}
        result = TrialResult(self.obj.name, self.settings, trace, wall_time=wall, simulated_time=simulated)
        result.dropped = bool(dropped)
        result.max_force = float(force_peak)
        result.max_rotation_mrad = 1e3 * float(turned)
        result.crushed = force_peak > self.obj.crush_force
        result.minimum_force = float(self.grasp.minimum_force) if self.grasp.minimum_force is not None else math.nan
        if hold:
            hold = np.array(hold)                                                      # (n, 6)
            result.hold_force_mean = float(hold[:, 1].mean())
            result.hold_force_max = float(hold[:, 1].max())
            settled = hold[hold[:, 0] >= hold[0, 0] + 0.5]                             # after the lift transient
            if len(settled) > 2:                                                       # least-squares drift rates
                rates = np.polyfit(settled[:, 0] - settled[0, 0], settled[:, 2:6], 1)[0]
                result.creep_um_per_s = float(1e3 * np.linalg.norm(rates[:3]))
                result.rotation_creep_mrad_per_s = float(1e3 * abs(rates[3]))
            result.hold_slip_mm = float(np.linalg.norm(hold[-1, 2:5] - hold[0, 2:5]))
            result.hold_rotation_mrad = float(1e3 * abs(hold[-1, 5] - hold[0, 5]))
        result.success = not result.dropped and not result.crushed and bool(hold is not None and len(hold))
        return result


def required_grip_force(obj: GraspObject, friction: float, tip: ReducedFingertip = None) -> float:
    """Least normal force per finger [N] that carries the object (reduced model's slip limit, two fingers sharing
    the weight m g / 2 [N] and the moment m g lever / 2 [N mm] about the fingertip normal)."""
    tip = default_tip() if tip is None else tip
    weight_n = obj.mass * GRAVITY
    return tip.minimum_normal_force((0.0, 0.5 * weight_n), 0.5 * weight_n * obj.lever * MM_PER_M, friction)


def run_trial(obj: GraspObject, settings: TrialSettings = TrialSettings(), **options) -> TrialResult:
    """Build the world for one trial and run it."""
    return GraspWorld(obj, settings, **options).run()


def random_settings(rng, **fixed) -> TrialSettings:
    """Randomised trial (Table I): mu in [0.4, 1.0], grasp jitter +-5 mm along x and +-1 mm in height (the 30 mm
    eclair leaves 1.7 mm between the outer bump rows and its edges; a row off the face flickers in and out), yaw
    misalignment +-1 deg, sensor noise 0.5-2 mN per node; ``fixed`` overrides."""
    values = dict(friction=float(rng.uniform(0.4, 1.0)),
                  grasp_offset=(float(rng.uniform(-0.005, 0.005)), float(rng.uniform(-0.001, 0.001))),
                  misalignment=float(np.radians(rng.uniform(-1.0, 1.0))),
                  sensor_noise=float(rng.uniform(0.0005, 0.002)), seed=int(rng.integers(2**31)))
    values.update(fixed)
    return TrialSettings(**values)
