"""The compiled frame loop of the closed loop (controller.closed_loop._fused) against the Python frame loop on recorded
trials, and the incipient-slip controller replayed from a trial's recorded sensor frames: the law is one set of
compiled kernels (controller.control._slip_law), called by the fused loop and by the IncipientSlipController
wrapper alike."""

import ast
import inspect

from dataclasses import replace

import numpy as np
import pytest

from controller import GraspPhase
from controller.closed_loop import TABLE_I_OBJECTS, GraspWorld, TrialSettings
from controller.closed_loop import _fused
from controller.control.incipient_slip import IncipientSlipController

# the fused loop and the Python loop run the same kernels through other plumbing (the Python loop senses with the
# library chain): they agree to round-off; 1e-9 leaves room for a summation order and catches any difference
SAME = 1e-9
# eclair at mu = 0.6: the probe finds a slip at 4.78 s (hold from 3.2 s), then place and release
SETTINGS = TrialSettings(friction_coefficient=0.6, hold_time=2.0, seed=3)


class _Recorder:
    """The controller in the Python frame loop, recording what it was given and what it answered."""

    def __init__(self, controller: IncipientSlipController):
        self.controller, self.parameters = controller, controller.parameters
        self.frames, self.phases, self.commands = [], [], []

    @property
    def minimum_force(self):
        return self.controller.minimum_force

    @property
    def friction_estimate(self):
        return self.controller.friction_estimate

    @property
    def slip_events(self):
        return self.controller.slip_events

    def observe(self, frame) -> None:
        self.frames.append((frame.normal_force.copy(), frame.load_ratio.copy(), frame.loaded.copy(),
                            frame.ratio_noise.copy()))
        self.controller.observe(frame.normal_force, frame.load_ratio, frame.loaded, frame.ratio_noise)

    def step(self, phase) -> float:
        self.phases.append(phase)
        self.commands.append(self.controller.step(phase))
        return self.commands[-1]


def _python_trial(settings):
    """A trial through the Python frame loop (any controller that is not the bare IncipientSlipController runs
    there), the controller's inputs and commands recorded."""
    world = GraspWorld(TABLE_I_OBJECTS["eclair"], settings)
    reference = _Recorder(IncipientSlipController(world.grasp.parameters, world.tip.centres))
    world.grasp = reference
    return world.run(), reference


@pytest.fixture(scope="module")
def recorded():
    return _python_trial(SETTINGS)


def test_controller_replayed_from_recorded_frames_gives_the_same_commands(recorded):
    """A new controller driven by nothing but the recorded sensor frames and phases answers with the recorded
    commands, estimate and events: what it decides depends on the sensor's reports alone."""
    _, reference = recorded
    parameters = reference.parameters
    phases = set(reference.phases)
    # the recording exercises the whole law: every phase, the minimum-force latch, the watch and a detection
    assert phases == set(GraspPhase) and reference.minimum_force is not None and reference.slip_events
    replayed = IncipientSlipController(parameters, reference.controller.centres)
    controls = len(reference.phases) // len(reference.frames)
    commands = []
    for index, frame in enumerate(reference.frames):
        replayed.observe(*frame)
        commands.extend(replayed.step(phase) for phase in reference.phases[index * controls:(index + 1) * controls])
    np.testing.assert_array_equal(commands, reference.commands)
    assert replayed.minimum_force == reference.minimum_force
    assert replayed.friction_estimate == reference.friction_estimate
    assert replayed.slip_events == reference.slip_events


def test_the_fused_loop_gives_the_controller_only_the_sensors_reports():
    """In the fused loop the law's kernels receive the frame's per-bump loads (from the readings) and the controller's
    own arrays: no physics array (bump states, MuJoCo data, the contact configuration) reaches them."""
    tree = ast.parse(inspect.getsource(_fused.run_frames))
    state = {"parameters", "centres", "second_frame", "scalars", "contact", "filtered", "ratios", "plateau",
             "history_force", "history_ratios", "history_use", "streak", "slip_centre"}   # the controller's arrays
    reports = {"load_force", "load_ratio", "loaded", "ratio_noise", "phase"}
    calls = [node for node in ast.walk(tree) if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
             and node.func.id in ("observe_frame", "control_step")]
    assert {call.func.id for call in calls} == {"observe_frame", "control_step"}
    for call in calls:
        names = {arg.id for arg in call.args if isinstance(arg, ast.Name)}
        assert len(names) == len(call.args), f"{call.func.id} takes an expression: every argument must be named"
        assert names <= state | reports, f"{call.func.id} is given {sorted(names - state - reports)}"


@pytest.mark.parametrize("constant_force", [None, 2.5])
def test_fused_loop_is_the_python_loop(recorded, constant_force):
    """Sensing, controller and physics in one compiled call: the same trace as the Python loop on the same seed
    (the node noise drawn for the whole trial at once is the same stream as frame by frame)."""
    python = recorded[0] if constant_force is None else _python_trial(replace(SETTINGS,
                                                                              constant_force=constant_force))[0]
    compiled = GraspWorld(TABLE_I_OBJECTS["eclair"], replace(SETTINGS, constant_force=constant_force)).run()
    for key in ("force_command", "grip_force", "shear_displacement", "twist_angle", "slip_x_mm", "rotation",
                "friction_estimate", "object_height_m"):
        scale = np.abs(python.trace[key]).max()
        np.testing.assert_allclose(compiled.trace[key], python.trace[key], rtol=SAME, atol=SAME * scale, err_msg=key)
    assert compiled.trace["phase"] == python.trace["phase"]
    assert (compiled.success, compiled.dropped, compiled.crushed) == (python.success, python.dropped, python.crushed)
    assert [kind for *_, kind in compiled.slip_events] == [kind for *_, kind in python.slip_events]
    assert np.allclose([event[:2] for event in compiled.slip_events], [event[:2] for event in python.slip_events],
                       rtol=SAME)
    assert compiled.minimum_force == pytest.approx(python.minimum_force, rel=SAME)


def test_table_contact_sensor_is_the_contact_list():
    """The hold's drop check reads MuJoCo's contact sensor (object-table contacts found in the last step): the same
    verdict as scanning data.contact, with the object resting, lifted off by an applied force and landing again."""
    import mujoco

    world = GraspWorld(TABLE_I_OBJECTS["eclair"], SETTINGS)
    model, data = world.model, world.data
    pair = {world.model.geom("table").id, world.model.geom("object").id}
    weight = TABLE_I_OBJECTS["eclair"].mass * 9.81
    seen = set()
    for step in range(1500):
        data.xfrc_applied[world.object_body, 2] = 1.5 * weight if step < 500 else 0.0
        mujoco.mj_step(model, data)
        scanned = any({contact.geom1, contact.geom2} == pair for contact in data.contact)
        assert world._touches_table() == scanned
        seen.add(scanned)
    assert seen == {True, False}


def test_the_trials_swing_margin_reaches_the_law():
    """``TrialSettings.swing_margin`` is the law's, as rotational detection is: in its parameters and in the parameter
    vector the compiled kernels read (0 by default: the tests' margins are the sensor's noise alone)."""
    from controller.control._slip_state import P_SWING_MARGIN

    for margin in (0.0, 3.0):
        grasp = GraspWorld(TABLE_I_OBJECTS["eclair"], replace(SETTINGS, swing_margin=margin)).grasp
        assert isinstance(grasp, IncipientSlipController)
        assert grasp.parameters.swing_margin == margin and grasp.law[P_SWING_MARGIN] == margin
    assert TrialSettings().swing_margin == 0.0
