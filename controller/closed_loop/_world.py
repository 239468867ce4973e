"""The MuJoCo world of one closed-loop trial (gripper, arm, table, object) and its multi-rate loop.

Rates (``TrialSettings``): MuJoCo steps the arm, the object and its table contact at ``physics_rate_hz`` (1 kHz);
each step the compiled contact step (``_kernel``) sub-steps the gripper and its Acceleration Control at
``actuator_rate_hz`` (8 kHz, the paper's), and couples the bumps' contact to the object implicitly. The grasp-force
controller runs at its own rate (1 kHz) and the sensor at 100 Hz, both integer divisions of the physics rate.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from contact.reduced import ReducedFingertip
from controller.acceleration_control import AccelerationControlParameters
from controller.grasp_force_control import GraspForceController, GraspForceParameters
from controller.multirate import rate_ratio
from controller.references import GraspPhase

from ._bridge import ContactBridge
from ._sensing import SensingChain
from ._trial import (APPROACH_GAP_M, ARM_RADIUS, GRAVITY, LIFT_HEIGHT_M, LOOP_RATE, MM_PER_M, TABLE_CLEARANCE_M,
                     TORQUE_LIMIT, GraspObject, TrialResult, TrialSettings, default_tip)


def _min_jerk(progress):
    s = min(max(progress, 0.0), 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def _mjcf(obj: GraspObject, settings: TrialSettings, tip: ReducedFingertip) -> str:
    """The world: table, lifting arm (position-controlled slide), the object on a free joint, and the two fingers as
    mocap bodies (their closing is stepped by the contact kernel; MuJoCo only shows them)."""
    hx, hy, hz = (0.5 * s for s in obj.size)
    centre_x = obj.lever + settings.grasp_offset[0]               # box centre (CoM) relative to the grasp point
    grasp_z = obj.grasp_height + settings.grasp_offset[1]
    finger_y = hy + APPROACH_GAP_M
    pad = tip.design.half_extent / MM_PER_M
    quat = f"{math.cos(0.5 * settings.misalignment)} 0 0 {math.sin(0.5 * settings.misalignment)}"
    finger = """
    <body name="{name}" mocap="true" pos="0 {y} {z}">
      <geom type="box" size="{pad} 0.004 {pad}" pos="0 {back} 0" contype="0" conaffinity="0" rgba="0.3 0.6 0.9 0.6"/>
    </body>"""
    fingers = "".join(finger.format(name=name, y=sign * finger_y, z=grasp_z, pad=pad, back=sign * 0.004)
                      for name, sign in (("finger_left", -1), ("finger_right", 1)))
    return f"""
<mujoco model="gel_gripper">
  <option timestep="{1.0 / settings.physics_rate_hz}" gravity="0 0 {-GRAVITY}" cone="elliptic" impratio="10"/>
  <worldbody>
    <geom name="table" type="plane" size="0.5 0.5 0.01" friction="0.5 0.005 0.0001"/>
    <body name="arm" pos="0 0 {grasp_z}" gravcomp="1">
      <joint name="lift" type="slide" axis="0 0 1" damping="300"/>
      <geom type="box" size="0.02 {finger_y + 0.02} 0.01" pos="0 0 {pad + 0.02}" mass="0.52" contype="0"
            conaffinity="0"/>
    </body>{fingers}
    <body name="object" pos="{centre_x} 0 {hz + 1e-4}" quat="{quat}">
      <freejoint name="object"/>
      <geom name="object" type="box" size="{hx} {hy} {hz}" mass="{obj.mass}" friction="0.5 0.005 0.0001"
            rgba="0.9 0.6 0.2 1"/>
    </body>
  </worldbody>
  <actuator>
    <position name="lift" joint="lift" kp="20000"/>
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

    def __init__(self, obj: GraspObject, settings: TrialSettings | None = None,
                 tip: ReducedFingertip | None = None, grasp_parameters: GraspForceParameters | None = None):
        import mujoco

        settings = TrialSettings() if settings is None else settings
        self.mujoco = mujoco
        self.obj, self.settings = obj, settings
        self.tip = default_tip() if tip is None else tip
        self.model = mujoco.MjModel.from_xml_string(_mjcf(obj, settings, self.tip))
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.rng = np.random.default_rng(settings.seed)
        self.acceleration_parameters = AccelerationControlParameters(sample_rate_hz=settings.actuator_rate_hz,
                                                                     torque_limit=TORQUE_LIMIT)
        self.bridge = ContactBridge(self.model, self.tip, obj, settings.friction_coefficient, self.acceleration_parameters,
                                    0.5 * obj.size[1] + APPROACH_GAP_M, settings.implicit_coupling)
        self.sensing = SensingChain(self.tip, settings.sensor_noise, self.rng, settings.targets)
        base = GraspForceParameters(approach_force=0.5, maximum_force=TORQUE_LIMIT / ARM_RADIUS, loop_rate=LOOP_RATE) \
            if grasp_parameters is None else grasp_parameters
        self.grasp = GraspForceController(replace(base, rotational_slip_detection=settings.rotational_slip_detection),
                                          self.sensing.design_references())
        ids = {name: mujoco.mj_name2id(self.model, kind, name) for kind, name in (
            (mujoco.mjtObj.mjOBJ_GEOM, "table"), (mujoco.mjtObj.mjOBJ_GEOM, "object"))}
        self.table_geom, self.object_geom = ids["table"], ids["object"]
        self.object_body, self.arm_body = self.bridge.object_id, self.bridge.arm_id
        self.schedule = self._schedule()
        for name, rate in (("grasp-force loop", self.grasp.parameters.sample_rate_hz),
                           ("sensor", self.sensing.array.sample_rate_hz)):
            whole = settings.physics_rate_hz / rate
            if whole < 1.0 or abs(whole - round(whole)) > 1e-9 * whole:
                raise ValueError(f"physics_rate_hz={settings.physics_rate_hz!r} must be an integer multiple of the "
                                 f"{name} rate {rate!r} Hz")

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
        pairs = np.sort(self.data.contact.geom, axis=1)
        return bool(np.any((pairs[:, 0] == min(self.table_geom, self.object_geom))
                           & (pairs[:, 1] == max(self.table_geom, self.object_geom))))

    def _object_rotation(self) -> float:
        """Object rotation about the left finger's normal (+y) [rad]."""
        rotation = self.data.xmat[self.object_body]
        return math.atan2(rotation[2], rotation[0])

    def _grasp_point_mm(self):
        """Object motion relative to the gripper: position of the object's initial grasp point relative to the arm
        [mm] (3,) and object rotation about the grasp axis [rad]."""
        data = self.data
        rotation = data.xmat[self.object_body].reshape(3, 3)
        point = data.xpos[self.object_body] + rotation @ self._grasp_local_m
        return (point - data.xpos[self.arm_body]) * MM_PER_M, self._object_rotation()

    def run(self) -> TrialResult:
        """Run the sequence; return the verdicts and a 100 Hz trace.

        Between two sensor frames the controller's inputs are held, so its commands for the frame are computed
        first and the frame's physics steps then run in compiled code (``ContactBridge.run``).
        """
        mujoco, model, data, s = self.mujoco, self.model, self.data, self.settings
        rate = s.physics_rate_hz
        per_grasp = rate_ratio(rate, self.grasp.parameters.sample_rate_hz)
        per_sensor = rate_ratio(rate, self.sensing.array.sample_rate_hz)
        rotation0 = data.xmat[self.object_body].reshape(3, 3)
        self._grasp_local_m = rotation0.T @ (np.array([0.0, 0.0, data.xpos[self.arm_body][2]])
                                             - data.xpos[self.object_body])
        steps = int(round(self.schedule[-1][0] * rate))
        phases, lift = self._plan(steps, rate)
        rows, hold = [], []
        command, dropped, turned = 0.0, False, 0.0
        constant = s.constant_force
        bridge, grasp, sensing = self.bridge, self.grasp, self.sensing
        commands = np.zeros(per_sensor)
        start = time.perf_counter()
        for first in range(0, steps, per_sensor):
            last = min(first + per_sensor, steps)
            frame = sensing.sense(bridge)
            u_x, theta, count = frame.shear_displacement, frame.twist_angle, frame.contact_count
            for step in range(first, last):
                if step % per_grasp == 0:
                    phase = phases[step]
                    command = grasp.step(u_x, theta, count, phase)
                    if constant is not None and phase is not GraspPhase.APPROACH:
                        command = constant if phase is not GraspPhase.RELEASE else 0.0
                commands[step - first] = command
            bridge.run(model, data, commands[:last - first], lift[first:last])
            phase = phases[first]
            time_s = first / rate
            relative_mm, rotation = self._grasp_point_mm()
            height_m = float(data.xpos[self.object_body][2] - 0.5 * self.obj.size[2])
            rows.append((time_s, phase.value, command, bridge.grip_force_n, u_x, theta, height_m, *relative_mm,
                         rotation, int(bridge.sliding.sum())))
            if phase is GraspPhase.LIFT or phase is GraspPhase.HOLD:
                turned = max(turned, abs(rotation))
            if phase is GraspPhase.HOLD:
                dropped |= self._touches_table() or height_m < TABLE_CLEARANCE_M
                hold.append((time_s, bridge.grip_force_n, *relative_mm, rotation))
        wall = time.perf_counter() - start
        unstable = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        if unstable:
            raise RuntimeError(f"MuJoCo reset the simulation {unstable} times (bad accelerations) in trial "
                               f"{self.obj.name!r} at physics_rate_hz={rate}: the step is too large for this world")
        return self._result(rows, hold, dropped, bridge.peak_force_n, turned, wall, steps / rate)

    def _plan(self, steps: int, rate: float):
        """Phase (list of GraspPhase) and lift target [m] (array) at every physics step."""
        phases, lift = [], np.zeros(steps)
        for step in range(steps):
            phase, progress = self._phase_at(step / rate)
            phases.append(phase)
            lift[step] = self._lift_height_m(phase, progress)
        return phases, lift

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



def run_trial(obj: GraspObject, settings: TrialSettings | None = None, **options) -> TrialResult:
    """Build the world for one trial and run it."""
    return GraspWorld(obj, settings, **options).run()
