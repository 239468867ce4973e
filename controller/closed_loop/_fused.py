"""The closed loop's sensor frames in compiled code: sensing, the incipient-slip controller and the physics block.

One call of ``run_frames`` advances frames [first, stop) of a trial: per frame (100 Hz) the sensor reads the bump
states the last physics step left (``_sensing_kernel.sense_frame``, with the frame's pre-drawn node noise), the
compiled incipient-slip controller observes the per-bump loads (``controller.control._slip_law.observe_frame``) and
runs the frame's control steps (``control_step``), and the frame's physics steps follow (``_kernel.run_block``). The
same arithmetic as the Python loop of ``GraspWorld.run`` (which drives the displacement-target law) in the same
order: both call the kernels below for the command a physics step applies and for the drop check.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from controller.control._slip_law import APPROACH, RELEASE, X_FRICTION, X_TIME, control_step, observe_frame

from . import _kernel as K
from ._sensing_kernel import load_ratio_noise, sense_frame

# --- columns of the per-frame signals: command [N], u_x [mm], theta [rad], mu_hat, and a slip event's time [s] and
# estimate (NaN: none in the frame)
F_COMMAND, F_SHEAR, F_TWIST, F_FRICTION, F_EVENT, F_EVENT_FRICTION, F_SIZE = range(7)


def frame_buffers(count: int, nodes: int) -> tuple:
    """Work arrays of ``_frame_loads`` for k bumps and n sensor nodes per fingertip: bump states (normal, shear,
    tangential), readings, per-bump loads (force, ratio) and the paper's estimator (force, shift, fit)."""
    return (np.zeros((2, count)), np.zeros((2, count, 2)), np.zeros((2, count, 2)), np.zeros((2, nodes)),
            np.zeros((2, count)), np.zeros((2, count, 2)), np.zeros((2, count)), np.zeros((2, count, 2)),
            np.zeros((2, 4)))


@njit_cached
def _frame_loads(sensing, buffers, noise, out, ratio_noise):
    """One sensor frame of the bumps' states in ``out`` (2 k, O_SIZE): the readings' per-bump loads into
    ``buffers`` and each load ratio's noise (2, k) [-] (``SensingChain.sense``); returns (u_x, theta)."""
    (couple_law, operator, inverse, offset, quantization, threshold, region, node_x, node_y, node_floor, centres,
     table_force, table_cop, cop_gain, noise_std, couple_noise) = sensing
    normal, shear, tangential, readings, load_force, load_ratio, force, shift, fit = buffers
    count = normal.shape[1]
    for f in range(2):
        for i in range(count):
            row = f * count + i
            normal[f, i] = out[row, K.O_NORMAL]
            shear[f, i, 0], shear[f, i, 1] = out[row, K.O_ELASTIC_X], out[row, K.O_ELASTIC_Y]
            tangential[f, i, 0], tangential[f, i, 1] = out[row, K.O_TANGENTIAL_X], out[row, K.O_TANGENTIAL_Y]
    u_x, theta, _ = sense_frame(normal, shear, tangential, noise, couple_law, operator, inverse, offset, quantization,
                                threshold, region, node_x, node_y, node_floor, centres, table_force, table_cop,
                                cop_gain, readings, load_force, load_ratio, force, shift, fit)
    load_ratio_noise(load_force, threshold, couple_law, noise_std, couple_noise, ratio_noise)
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
def run_frames(first, stop, noise, sensing, buffers, ratio_noise, loaded, controller, phases, constant, lift,
               commands, held, physics, mj_step, grasp_local, records, signals, hold, sensordata, table_sensor,
               clearance):
    """Frames [first, stop) of a trial (module docstring). ``noise`` (stop - first, 2, n_nodes) [N]: the node noise
    of these frames; ``phases`` (frames x control steps per frame,) ``PHASE_CODES``; ``constant`` [N] the constant
    force of a tau_min trial (NaN: the controller's); ``lift`` (frames x physics steps per frame,) [m]; ``commands``
    (control steps per frame,) and ``held`` (physics steps per frame, commands per physics step) work arrays;
    ``records`` (frames, R_SIZE) and ``signals`` (frames, F_SIZE) take each frame's row. Returns whether the
    object was dropped: in a ``hold`` (frames,) frame MuJoCo found it on the table (``sensordata[table_sensor]``,
    contacts object-table) or its bottom sank below ``clearance`` [m]."""
    (parameters, centres, second_frame, scalars, contact, filtered, ratios, plateau, history_force, history_ratios,
     streak, slip_centre) = controller
    (config, geometry, state, bumps, out, xpos, xmat, xipos, qvel, xfrc_applied, mocap_pos, ctrl, model_address,
     data_address) = physics
    threshold = sensing[5]
    load_force, load_ratio = buffers[4], buffers[5]
    controls, per_frame = commands.shape[0], held.shape[0]
    dropped = False
    for frame in range(first, stop):
        u_x, theta = _frame_loads(sensing, buffers, noise[frame - first], out, ratio_noise)
        for f in range(2):
            for i in range(load_force.shape[1]):
                loaded[f, i] = load_force[f, i] > threshold
        event = observe_frame(load_force, load_ratio, loaded, ratio_noise, parameters, centres, second_frame,
                              scalars, contact, filtered, ratios, plateau, history_force, history_ratios, streak,
                              slip_centre)
        if event:
            signals[frame, F_EVENT], signals[frame, F_EVENT_FRICTION] = scalars[X_TIME], scalars[X_FRICTION]
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
