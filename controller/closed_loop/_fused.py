"""The closed loop's sensor frames in compiled code: sensing, the incipient-slip controller and the physics block.

One call of ``run_frames`` advances frames [first, stop) of a trial: per frame (100 Hz) the plant's arrays read the
bump states the last physics step left (``controller.plant._sensor_kernel.plant_readings``, with the frame's
pre-drawn node noise), the estimators read those readings alone (``_sensing_kernel.sense_frame``), the compiled
incipient-slip controller observes the per-bump loads (``controller.control._slip_law.observe_frame``) and runs the
frame's control steps (``control_step``), and the frame's physics steps follow (``_kernel.run_block``). The same
arithmetic as the Python loop of ``GraspWorld.run`` (which drives the displacement-target law) in the same order:
both call ``frame_loads`` for a frame's sensing and the kernels below for the command a physics step applies and
for the drop check.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from controller.control._slip_law import control_step, observe_frame
from controller.control._slip_state import APPROACH, RELEASE, X_FRICTION, X_TIME
from controller.plant._sensor_kernel import plant_readings

from . import _kernel as K
from ._sensing_kernel import load_ratio_noise, sense_frame

# --- columns of the per-frame signals: command [N], u_x [mm], theta [rad], mu_hat, and a slip event's time [s],
# estimate and kind (``_slip_law.SLIP_KINDS``; NaN: none in the frame)
F_COMMAND, F_SHEAR, F_TWIST, F_FRICTION, F_EVENT, F_EVENT_FRICTION, F_EVENT_KIND, F_SIZE = range(8)


def frame_buffers(count: int, shape: tuple[int, int]) -> tuple:
    """Work arrays of ``frame_loads`` for k bumps and an (ny, nx) array per fingertip: bump states (2, k, 4),
    readings (2, ny, nx), pads and node work (ny, nx), tared readings (2, n), per-bump loads (force, ratio) and the
    paper's estimator (force, shift, fit)."""
    nodes = shape[0] * shape[1]
    return (np.zeros((2, count, 4)), np.zeros((2,) + shape), np.zeros(shape), np.zeros(shape), np.zeros((2, nodes)),
            np.zeros((2, count)), np.zeros((2, count, 2)), np.zeros((2, count)), np.zeros((2, count, 2)),
            np.zeros((2, 4)))


@njit_cached
def bump_states(out, states):
    """The plant's bump states (2, k, 4) of the contact kernel's outputs ``out`` (2 k, O_SIZE): normal force,
    tangential force (sensor frame) and the bump's own torque."""
    count = states.shape[1]
    for f in range(2):
        for i in range(count):
            row = f * count + i
            states[f, i, 0] = out[row, K.O_NORMAL]
            states[f, i, 1], states[f, i, 2] = out[row, K.O_TANGENTIAL_X], out[row, K.O_TANGENTIAL_Y]
            states[f, i, 3] = out[row, K.O_TORQUE]


@njit_cached
def frame_loads(plant, estimator, buffers, noise, out, time, ratio_noise):
    """One sensor frame: the plant's readings of the bumps' states in ``out`` at ``time`` [s] with standard-normal
    node ``noise`` (2, ny, nx) (``plant_readings``, the truth side), then the estimators on those readings alone
    (``sense_frame``, the belief side): per-bump loads into ``buffers`` and each load ratio's noise (2, k) [-];
    returns (u_x, theta)."""
    (normal_levels, normal, shear_levels, shear, spin, pad_area, law, gain, offset, drift, noise_floor) = plant
    (tare, couple_law, inverse, threshold, couple_force, couple_table, region, node_x, node_y, node_floor, pool,
     centres, table_force, table_cop, cop_gain, node_noise, couple_noise) = estimator
    states, readings, pads, change, corrected, load_force, load_ratio, force, shift, fit = buffers
    bump_states(out, states)
    plant_readings(states, normal_levels, normal, shear_levels, shear, spin, pad_area, law, gain, offset, drift,
                   noise_floor, time, noise, pads, change, readings)
    u_x, theta, _ = sense_frame(readings.reshape(2, corrected.shape[1]), tare, couple_law, inverse, threshold,
                                couple_force, couple_table, region, node_x, node_y, node_floor, pool, centres,
                                table_force, table_cop, cop_gain, corrected, load_force, load_ratio, force, shift, fit)
    load_ratio_noise(load_force, threshold, couple_law, node_noise, couple_noise, ratio_noise)
    return u_x, theta


@njit_cached
def applied_command(command, phase, constant):
    """The force [N] a control step applies: the controller's ``command``, or in a tau_min trial the ``constant``
    force (NaN: none) in every phase after the approach, and 0 in the release."""
    if math.isnan(constant) or phase == APPROACH:
        return command
    return constant if phase != RELEASE else 0.0


@njit_cached
def hold_commands(commands, held):
    """The commands of a frame's control steps (c,) held by its physics steps (p, m): each physics step takes the
    m control steps it spans (m > 1) or the one it lies in (m = 1)."""
    controls, per_frame, spanned = commands.shape[0], held.shape[0], held.shape[1]
    for j in range(per_frame):
        for c in range(spanned):
            held[j, c] = commands[j * controls // per_frame + c]


@njit_cached
def object_dropped(table_contacts, height, clearance):
    """Whether a held object is down: MuJoCo found object-table contacts in the last step, or its bottom is below
    ``clearance`` [m] (``height`` [m])."""
    return table_contacts > 0.0 or height < clearance


@njit_cached
def run_frames(first, stop, noise, plant, estimator, buffers, ratio_noise, loaded, controller, phases, constant,
               lift, commands, held, physics, mj_step, grasp_local, records, signals, hold, sensordata, table_sensor,
               clearance, frame_period):
    """Frames [first, stop) of a trial (module docstring). ``noise`` (stop - first, 2, ny, nx): the plant's
    standard-normal node noise of these frames; ``plant`` and ``estimator`` the two sides' constants
    (``frame_loads``); ``frame_period`` [s]; ``phases`` (frames x control steps per frame,) ``PHASE_CODES``;
    ``constant`` [N] the constant
    force of a tau_min trial (NaN: the controller's); ``lift`` (frames x physics steps per frame,) [m]; ``commands``
    (control steps per frame,) and ``held`` (physics steps per frame, commands per physics step) work arrays;
    ``records`` (frames, R_SIZE) and ``signals`` (frames, F_SIZE) take each frame's row. Returns whether the
    object was dropped: in a ``hold`` (frames,) frame MuJoCo found it on the table (``sensordata[table_sensor]``,
    contacts object-table) or its bottom sank below ``clearance`` [m]."""
    (parameters, centres, second_frame, scalars, contact, filtered, ratios, plateau, history_force, history_ratios,
     history_use, streak, slip_centre) = controller
    (config, geometry, state, bumps, out, xpos, xmat, xipos, qvel, xfrc_applied, mocap_pos, ctrl, model_address,
     data_address) = physics
    threshold = estimator[3]
    load_force, load_ratio = buffers[5], buffers[6]
    controls, per_frame = commands.shape[0], held.shape[0]
    dropped = False
    for frame in range(first, stop):
        u_x, theta = frame_loads(plant, estimator, buffers, noise[frame - first], out, frame * frame_period,
                                 ratio_noise)
        for f in range(2):
            for i in range(load_force.shape[1]):
                loaded[f, i] = load_force[f, i] > threshold
        event = observe_frame(load_force, load_ratio, loaded, ratio_noise, parameters, centres, second_frame,
                              scalars, contact, filtered, ratios, plateau, history_force, history_ratios, history_use,
                              streak, slip_centre)
        if event:
            signals[frame, F_EVENT], signals[frame, F_EVENT_FRICTION] = scalars[X_TIME], scalars[X_FRICTION]
            signals[frame, F_EVENT_KIND] = event
        command = 0.0
        for step in range(controls):
            phase = phases[frame * controls + step]
            command = applied_command(control_step(parameters, scalars, plateau, streak, phase), phase, constant)
            commands[step] = command
        hold_commands(commands, held)
        K.run_block(held, lift[frame * per_frame:(frame + 1) * per_frame], config, geometry, state, bumps, out, xpos,
                    xmat, xipos, qvel, xfrc_applied, mocap_pos, ctrl, model_address, data_address, mj_step,
                    grasp_local, records[frame])
        signals[frame, F_COMMAND], signals[frame, F_SHEAR], signals[frame, F_TWIST] = command, u_x, theta
        signals[frame, F_FRICTION] = scalars[X_FRICTION]
        if hold[frame] and not dropped:
            dropped = object_dropped(sensordata[table_sensor], records[frame, K.R_HEIGHT], clearance)
    return dropped
