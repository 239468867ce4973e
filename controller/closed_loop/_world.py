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

from controller.control.acceleration_control import AccelerationControlParameters
from controller.control.grasp_force_control import GraspForceController, GraspForceParameters
from controller.control.incipient_slip import IncipientSlipController, IncipientSlipParameters
from controller.control.references import GraspPhase

from controller.control._slip_state import PHASE_CODES, SLIP_KINDS
from controller.plant.fingertip_plant import FingertipPlant

from . import _fused as F
from . import _kernel as K
from ._bench import estimator_bench
from ._bridge import ContactBridge, mujoco_step_function
from ._sensing import SensingChain
from ._trial import (APPROACH_GAP_M, GRAVITY, GRIP_LIMIT, LIFT_HEIGHT_M, LOOP_RATE, MM_PER_M, TABLE_CLEARANCE_M,
                     TORQUE_LIMIT, ControllerKind, GraspObject, TrialResult, TrialSettings)


def _mjcf(obj: GraspObject, settings: TrialSettings, tip) -> str:
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
  <sensor>
    <contact name="table_contact" geom1="object" geom2="table" data="found" num="1"/>
  </sensor>
</mujoco>"""


class GraspWorld:
    """One trial's MuJoCo world and loop; ``run()`` -> TrialResult.

    Parameters
    ----------
    obj : GraspObject
    settings : TrialSettings
    plant : FingertipPlant, optional -- both fingertips as built (default: ``settings.plant``'s errors on the
        FEM-calibrated 3x3 design, ``settings.sensor_plane``, the trial's noise and seed; any design: a plant of its
        ``PlantModel`` and array). The truth side: the estimator is calibrated on the bench of the plant's design
        (``_bench``: a nominal build of the same model and array type) and tared at rest, and never reads the plant.
    controller_parameters : IncipientSlipParameters or GraspForceParameters, optional -- the controller's
        parameters, of the kind ``settings.controller`` names (rotational detection and the incipient-slip law's
        swing margin are taken from ``settings``).
    """

    def __init__(self, obj: GraspObject, settings: TrialSettings | None = None, plant: FingertipPlant | None = None,
                 controller_parameters: IncipientSlipParameters | GraspForceParameters | None = None):
        import mujoco

        if not isinstance(obj, GraspObject):
            raise TypeError(f"obj={obj!r} must be a GraspObject (e.g. TABLE_I_OBJECTS['eclair'])")
        settings = TrialSettings() if settings is None else settings
        if not isinstance(settings, TrialSettings):
            raise TypeError(f"settings={settings!r} must be TrialSettings")
        self.mujoco = mujoco
        self.obj, self.settings = obj, settings
        self.plant = FingertipPlant(settings.plant, noise=settings.sensor_noise, seed=settings.seed,
                                    plane=settings.sensor_plane) if plant is None else plant
        self.tip = self.plant.mechanics                               # the plant's bump laws (truth)
        self.model = mujoco.MjModel.from_xml_string(_mjcf(obj, settings, self.tip))
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.rng = np.random.default_rng(settings.seed)
        # by default the grip as the actuator side reads it (reaction-force observer): the gripper has no force sensor
        self.acceleration_parameters = AccelerationControlParameters(sample_rate_hz=settings.actuator_rate_hz,
                                                                     torque_limit=TORQUE_LIMIT,
                                                                     force_feedback=settings.force_feedback)
        self.bridge = ContactBridge(self.model, self.tip, obj, settings.friction_coefficient,
                                    self.acceleration_parameters, 0.5 * obj.size[1] + APPROACH_GAP_M,
                                    settings.implicit_coupling, self.plant.friction_anisotropy)
        # the estimator: calibrated on a nominal build's bench, then tared on this build's arrays at rest
        self.sensing = SensingChain(estimator_bench(self.plant.plane, self.plant.model, self.plant.array_design),
                                    settings.targets)
        self.sensing.tare(self._rest_readings())
        self.grasp = _controller(settings, controller_parameters, self.sensing)
        # contacts object-table MuJoCo found in the last step (a position-stage sensor: it does not act on the world)
        self.table_sensor = int(self.model.sensor_adr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SENSOR,
                                                                        "table_contact")])
        self.object_body, self.arm_body = self.bridge.object_id, self.bridge.arm_id
        self.schedule = self._schedule()
        self._phase_ends = np.array([end for end, _ in self.schedule])        # [s]
        control, sensor = self.grasp.parameters.sample_rate_hz, self.sensing.array.sample_rate_hz
        for name, fast, slow in (("physics_rate_hz", settings.physics_rate_hz, sensor),
                                 ("the grasp-force loop rate", control, sensor)):
            whole = fast / slow
            if whole < 1.0 or abs(whole - round(whole)) > 1e-9 * whole:
                raise ValueError(f"{name}={fast!r} Hz must be an integer multiple of the sensor rate {slow!r} Hz")
        ratio = max(settings.physics_rate_hz, control) / min(settings.physics_rate_hz, control)
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            raise ValueError(f"physics_rate_hz={settings.physics_rate_hz!r} and the grasp-force loop rate {control!r} "
                             f"Hz must be integer multiples of one another")

    def _rest_readings(self) -> np.ndarray:
        """REST_FRAMES frames (frames, 2, n_nodes) [N] of both arrays with nothing touching, just before the
        approach (the baselines drift on), their noise from a stream of their own."""
        rng = np.random.default_rng([self.settings.seed, 0x52455354])                    # "REST"
        period = 1.0 / self.sensing.array.sample_rate_hz
        shape = self.plant.array.shape
        readings = np.empty((REST_FRAMES, 2) + shape)
        for frame in range(REST_FRAMES):
            readings[frame] = self.plant.frame_readings(np.zeros((2, len(self.tip.centres), 4)),
                                                        (frame - REST_FRAMES) * period,
                                                        rng.standard_normal((2,) + shape))
        return readings.reshape(REST_FRAMES, 2, -1)

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

    def _phase_index(self, times) -> np.ndarray:
        """Index into the schedule of the phase at each of ``times`` [s] (the last phase's end and beyond: the
        last)."""
        ends = self._phase_ends
        return np.minimum(np.searchsorted(ends, times, side="right"), len(ends) - 1)

    def _lift_heights_m(self, times) -> np.ndarray:
        """Lift target [m] at ``times`` [s]: a minimum-jerk rise in LIFT, held in HOLD, lowered in PLACE."""
        ends = self._phase_ends
        starts = np.concatenate([[0.0], ends[:-1]])
        index = self._phase_index(times)
        progress = np.clip((times - starts[index]) / (ends[index] - starts[index]), 0.0, 1.0)
        rise = LIFT_HEIGHT_M * progress**3 * (10.0 - 15.0 * progress + 6.0 * progress**2)
        height = np.zeros(len(times))
        scheduled = [phase for _, phase in self.schedule]
        for phase, value in ((GraspPhase.LIFT, rise), (GraspPhase.HOLD, np.full(len(times), LIFT_HEIGHT_M)),
                             (GraspPhase.PLACE, LIFT_HEIGHT_M - rise)):
            chosen = index == scheduled.index(phase) if phase in scheduled else np.zeros(len(times), dtype=bool)
            height[chosen] = value[chosen]
        return height

    def _touches_table(self) -> bool:
        return bool(self.data.sensordata[self.table_sensor] > 0.0)

    def run(self) -> TrialResult:
        """Run the sequence; return the verdicts and a 100 Hz trace.

        Between two sensor frames the controller's inputs are held, so its commands for the frame are computed
        first and the frame's physics steps then run in compiled code (``ContactBridge.run``), each physics step
        with the commands of the control steps it spans (or the one it lies in).
        """
        mujoco, data, s = self.mujoco, self.data, self.settings
        physics_rate, control_rate = s.physics_rate_hz, self.grasp.parameters.sample_rate_hz
        sensor_rate = self.sensing.array.sample_rate_hz
        per_frame = int(round(physics_rate / sensor_rate))                  # physics steps per sensor frame
        controls = int(round(control_rate / sensor_rate))                   # control steps per sensor frame
        rotation0 = data.xmat[self.object_body].reshape(3, 3)
        self._grasp_local_m = rotation0.T @ (np.array([0.0, 0.0, data.xpos[self.arm_body][2]])
                                             - data.xpos[self.object_body])
        frames = int(round(self.schedule[-1][0] * sensor_rate))
        phases = self._phase_index(np.arange(frames * controls) / control_rate)     # schedule index per control step
        lift = self._lift_heights_m(np.arange(frames * per_frame) / physics_rate)
        records = np.zeros((frames, K.R_SIZE))
        signals = np.full((frames, F.F_SIZE), math.nan)          # command, u_x, theta, mu_hat, slip events
        frame_phases = [self.schedule[i][1] for i in phases[::controls][:frames]]      # the phase of each frame
        hold_phase = np.array([phase is GraspPhase.HOLD for phase in frame_phases])
        # control steps per physics step: the commands of a frame's physics steps (one held over several steps when
        # the physics runs faster than the controller)
        held = np.zeros((per_frame, controls // per_frame if per_frame < controls else 1))
        loop = self._compiled_loop if isinstance(self.grasp, IncipientSlipController) else self._python_loop
        start = time.perf_counter()
        dropped = loop(phases, lift, held, records, signals, hold_phase)
        wall = time.perf_counter() - start
        unstable = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        if unstable:
            raise RuntimeError(f"MuJoCo reset the simulation {unstable} times (bad accelerations) in trial "
                               f"{self.obj.name!r} at physics_rate_hz={physics_rate}: the step is too large for this "
                               f"world")
        times = np.arange(frames) / sensor_rate
        return self._result(times, frame_phases, records, signals, dropped, self.bridge.peak_force_n, wall,
                            frames / sensor_rate)

    def _compiled_loop(self, phases, lift, held, records, signals, hold_phase) -> bool:
        """The incipient-slip loop in compiled code (``_fused.run_frames``), the whole trial in one call; ``phases``
        the schedule index of each control step. Returns whether the object was found dropped."""
        controls = len(phases) // len(records)
        codes = np.array([PHASE_CODES[phase] for _, phase in self.schedule], dtype=np.int64)[phases]
        constant = math.nan if self.settings.constant_force is None else float(self.settings.constant_force)
        count, sensing = len(self.tip.centres), self.sensing
        buffers = F.frame_buffers(count, self.plant.array.shape)
        dropped = F.run_frames(
            0, len(records), self.plant.frame_noise(self.rng, len(records)), self.plant.compiled_inputs(),
            sensing.compiled_inputs(), buffers, np.zeros((2, count)), np.zeros((2, count), dtype=np.bool_),
            self.grasp.arrays(), codes, constant, lift, np.zeros(controls), held,
            self.bridge.compiled_inputs(self.model, self.data), mujoco_step_function(),
            self._grasp_local_m, records, signals, hold_phase, self.data.sensordata, self.table_sensor,
            TABLE_CLEARANCE_M, 1.0 / sensing.array.sample_rate_hz)
        seen = ~np.isnan(signals[:, F.F_EVENT])         # the slip events the compiled loop marked
        self.grasp.slip_events.extend(zip(signals[seen, F.F_EVENT].tolist(), signals[seen, F.F_EVENT_FRICTION].tolist(),
                                          [SLIP_KINDS[int(kind)] for kind in signals[seen, F.F_EVENT_KIND]]))
        return dropped

    def _python_loop(self, phases, lift, held, records, signals, hold_phase) -> bool:
        """The frame loop in Python for a controller with no compiled form (the displacement-target law): sense,
        observe, the frame's control steps, then its physics steps in compiled code. Returns whether the object
        was found dropped."""
        frames, per_frame = len(records), held.shape[0]
        controls = len(phases) // frames
        codes = np.array([PHASE_CODES[phase] for _, phase in self.schedule], dtype=np.int64)[phases]
        phases = [self.schedule[i][1] for i in phases]
        constant = math.nan if self.settings.constant_force is None else float(self.settings.constant_force)
        bridge, grasp, sensing = self.bridge, self.grasp, self.sensing
        commands, command, dropped = np.zeros(controls), 0.0, False
        noise, period = self.plant.frame_noise(self.rng, frames), 1.0 / sensing.array.sample_rate_hz
        for frame_index in range(frames):
            readings = self.plant.frame_readings(bridge.bump_states, frame_index * period, noise[frame_index])
            frame = sensing.sense(readings.reshape(2, -1))
            grasp.observe(frame)
            first = frame_index * controls
            for step in range(controls):
                command = F.applied_command(grasp.step(phases[first + step]), codes[first + step], constant)
                commands[step] = command
            F.hold_commands(commands, held)
            bridge.run(self.model, self.data, held, lift[frame_index * per_frame:(frame_index + 1) * per_frame],
                       self._grasp_local_m, records[frame_index])
            signals[frame_index, :F.F_EVENT] = (command, frame.shear_displacement, frame.twist_angle,
                                                grasp.friction_estimate)
            if hold_phase[frame_index] and not dropped:
                dropped = F.object_dropped(self.data.sensordata[self.table_sensor], records[frame_index, K.R_HEIGHT],
                                           TABLE_CLEARANCE_M)
        return dropped

    def _result(self, times, phases, records, signals, dropped, force_peak, wall, simulated) -> TrialResult:
        trace = {"time": times.tolist(), "phase": [phase.value for phase in phases],
                 "force_command": signals[:, 0].tolist(), "grip_force": records[:, K.R_GRIP_FORCE].tolist(),
                 "shear_displacement": signals[:, 1].tolist(), "twist_angle": signals[:, 2].tolist(),
                 "object_height_m": records[:, K.R_HEIGHT].tolist(),
                 "slip_x_mm": records[:, K.R_RELATIVE_X].tolist(), "slip_y_mm": records[:, K.R_RELATIVE_Y].tolist(),
                 "slip_z_mm": records[:, K.R_RELATIVE_Z].tolist(), "rotation": records[:, K.R_ROTATION].tolist(),
                 "sliding_bumps": records[:, K.R_SLIDING].astype(int).tolist(),
                 "friction_estimate": signals[:, 3].tolist()}
        result = TrialResult(self.obj.name, self.settings, trace, wall_time=wall, simulated_time=simulated)
        result.dropped = bool(dropped)
        result.max_force = float(force_peak)
        lifted = np.array([phase in (GraspPhase.LIFT, GraspPhase.HOLD) for phase in phases])
        result.max_rotation_mrad = 1e3 * float(np.abs(records[lifted, K.R_ROTATION]).max(initial=0.0))
        if lifted.any():
            relative = records[lifted, K.R_RELATIVE_X:K.R_RELATIVE_Z + 1]
            result.grasp_slip_mm = float(np.linalg.norm(relative - relative[0], axis=1).max())
        result.crushed = force_peak > self.obj.crush_force
        result.minimum_force = float(self.grasp.minimum_force) if self.grasp.minimum_force is not None else math.nan
        result.friction_estimate = float(self.grasp.friction_estimate)
        result.slip_events = list(self.grasp.slip_events)
        holding = np.array([phase is GraspPhase.HOLD for phase in phases])
        if holding.any():
            hold = np.column_stack([times, records[:, K.R_GRIP_FORCE], records[:, K.R_RELATIVE_X:K.R_RELATIVE_Z + 1],
                                    records[:, K.R_ROTATION]])[holding]                 # (n, 6)
            result.hold_force_mean = float(hold[:, 1].mean())
            result.hold_force_max = float(hold[:, 1].max())
            result.hold_force_settled = float(hold[hold[:, 0] >= hold[-1, 0] - SETTLED_WINDOW, 1].mean())
            settled = hold[hold[:, 0] >= hold[0, 0] + 0.5]                             # after the lift transient
            if len(settled) > 2:                                                       # least-squares drift rates
                rates = np.polyfit(settled[:, 0] - settled[0, 0], settled[:, 2:6], 1)[0]
                result.creep_um_per_s = float(1e3 * np.linalg.norm(rates[:3]))
                result.rotation_creep_mrad_per_s = float(1e3 * abs(rates[3]))
            result.hold_slip_mm = float(np.linalg.norm(hold[-1, 2:5] - hold[0, 2:5]))
            result.hold_rotation_mrad = float(1e3 * abs(hold[-1, 5] - hold[0, 5]))
            found = max([event[0] for event in result.slip_events], default=-math.inf)
            after = hold[hold[:, 0] >= max(found + FOUND_SETTLE, hold[0, 0] + 0.5)]
            if len(after) > 2:
                rates = np.polyfit(after[:, 0] - after[0, 0], after[:, 2:5], 1)[0]
                result.creep_after_friction_um_per_s = float(1e3 * np.linalg.norm(rates))
                result.creep_window_s = float(after[-1, 0] - after[0, 0])
        result.success = result.outcome == "held" and bool(holding.any())
        return result


SETTLED_WINDOW = 1.0          # s: the end of the hold over which the settled grip force is averaged
REST_FRAMES = 20              # frames at rest before the approach: the estimator's tare (0.2 s at 100 Hz)
FOUND_SETTLE = 0.2            # s after the last slip event before the creep "after the friction is found" is measured


class _DisplacementLaw:
    """The displacement-target law behind the same two calls as the incipient-slip controller."""

    friction_estimate = math.nan                       # the law assumes its design friction; it measures none
    slip_events = ()

    def __init__(self, controller: GraspForceController):
        self.controller, self.parameters = controller, controller.parameters
        self._inputs = (0.0, 0.0, 0)

    @property
    def minimum_force(self):
        return self.controller.minimum_force

    def observe(self, frame) -> None:
        self._inputs = (frame.shear_displacement, frame.twist_angle, frame.contact_count)

    def step(self, phase) -> float:
        return self.controller.step(*self._inputs, phase)


def _controller(settings: TrialSettings, parameters, sensing: SensingChain):
    """The trial's controller, fed only what the sensor reports (``observe``) and the phase (``step``)."""
    if settings.controller is ControllerKind.DISPLACEMENT_TARGETS:
        base = GraspForceParameters(approach_force=0.5, maximum_force=GRIP_LIMIT, loop_rate=LOOP_RATE) \
            if parameters is None else parameters
        if not isinstance(base, GraspForceParameters):
            raise ValueError(f"controller_parameters must be GraspForceParameters for {settings.controller.value}, "
                             f"got {type(base).__name__}")
        law = GraspForceController(replace(base, rotational_slip_detection=settings.rotational_slip_detection),
                                   sensing.design_references())
        return _DisplacementLaw(law)
    base = IncipientSlipParameters(maximum_force=GRIP_LIMIT) if parameters is None else parameters
    if not isinstance(base, IncipientSlipParameters):
        raise ValueError(f"controller_parameters must be IncipientSlipParameters for {settings.controller.value}, "
                         f"got {type(base).__name__}")
    frame_rate = sensing.array.sample_rate_hz
    return IncipientSlipController(
        replace(base, rotational_slip_detection=settings.rotational_slip_detection, frame_rate_hz=frame_rate,
                swing_margin=settings.swing_margin),
        sensing.layout.centre_array)                     # the estimator's layout of the design


def run_trial(obj: GraspObject, settings: TrialSettings | None = None, **options) -> TrialResult:
    """Build the world for one trial and run it (``GraspWorld``'s options: ``plant``, ``controller_parameters``;
    TypeError naming the argument for anything but a GraspObject and a TrialSettings or None)."""
    if not isinstance(obj, GraspObject):
        raise TypeError(f"obj={obj!r} is a {type(obj).__name__}, not a GraspObject (e.g. TABLE_I_OBJECTS['eclair'])")
    if settings is not None and not isinstance(settings, TrialSettings):
        raise TypeError(f"settings={settings!r} is a {type(settings).__name__}, not a TrialSettings (or None)")
    return GraspWorld(obj, settings, **options).run()
