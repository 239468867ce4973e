"""The MuJoCo world of one closed-loop trial (gripper, arm, table, object) and its multi-rate loop."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from contact.reduced import ReducedFingertip
from controller.acceleration_control import AccelerationControlParameters, AccelerationController
from controller.grasp_force_control import GraspForceController, GraspForceParameters
from controller.references import GraspPhase

from ._bridge import ContactBridge
from ._sensing import SensingChain
from ._trial import (APPROACH_GAP_M, ARM_RADIUS, CONTACT_RATE_HZ, GRAVITY, LIFT_HEIGHT_M, LOOP_RATE, MM_PER_M,
                     PHYSICS_RATE_HZ, TABLE_CLEARANCE_M, TORQUE_LIMIT, GraspObject, TrialResult, TrialSettings,
                     default_tip)


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
        self.bridge = ContactBridge(self.model, self.data, self.tip, obj, settings.friction)
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



def run_trial(obj: GraspObject, settings: TrialSettings = TrialSettings(), **options) -> TrialResult:
    """Build the world for one trial and run it."""
    return GraspWorld(obj, settings, **options).run()
