"""Compiled physics step of the closed loop: gripper sub-steps at the actuator rate, bump contact, implicit coupling.

One call advances everything that is not MuJoCo's by one physics step h (1 ms by default) and leaves the contact
wrench on the object and the arm in ``xfrc_applied`` for the ``mj_step`` that follows:

1. Gripper, n = actuator rate / physics rate sub-steps of dt = h / n (8 kHz, as the paper's actuator loop): the
   closing s of the two mirrored fingers (m_f s'' = F_motor - c_f s' - P, P the per-finger normal force, damping
   implicit as MuJoCo's Euler integrator treats joint damping), the Acceleration Control block with its disturbance
   observer (the equations of ``controller.control.acceleration_control``, checked step for step against that class in
   the tests), and the normal force of every bump tip against the object face, P_i = k_n d_i^(3/2)
   (1 + 1.5 tau_d d_i' / d_i), d_i' from the relative velocity (not a finite difference). The object is held at its
   pose and twist at the start of the step.
2. Tangential contact once per step (``contact.reduced.bump_law``: Mindlin, Lubkin, elliptic combined limit) at the
   mean normal forces of the sub-steps, with the friction along each bump's shear direction (an anisotropic surface
   of the plant: ``_friction_along``): each bump is anchored to the material point of the face it first touched;
   the anchor's offset from the tip in the sensor plane is the elastic shear, and a bump on its friction limit
   moves its anchor so that the elastic part carries the limit load (stick is exact: a held object does not creep).
   Viscous term tau_d k_t delta' on stuck bumps, again from the relative velocity.
3. Implicit coupling. The contact is stiff for a 0.1 kg object (omega ~ 600 rad/s) and its damping more so
   (c h / m ~ 2 at 1 ms: explicit damping diverges), so the wrench is taken at the end of the step, linearised:
   with K and C the contact stiffness and damping on the object twist xi (6,) and f the other forces (gravity,
   table, gyroscopic; estimated from the last step's observed acceleration, f = M (xi_n - xi_{n-1}) / h - W_{n-1}),
   (M + h C + h^2 K) dxi = h (f + W - h K xi_n) and W_applied = W - h K (xi_n + dxi) - C dxi, so that MuJoCo's
   semi-implicit Euler step reproduces the implicit (backward Euler) update of the contact terms. This is the
   implicit-spring coupling of co-simulation; it is exact for a linear contact and removes the step-size limit of
   the explicit one.

Units: mm, N, N mm, s inside the contact law (as contact.reduced); the MuJoCo arrays are SI and are converted here.
Hand-written because no library steps a custom contact law between MuJoCo steps at this rate; numba compiles it.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from contact.reduced import bump_law

MM = 1000.0                        # mm per m

# --- layout of the configuration vector (floats) ---------------------------------------------------------------
(C_NORMAL_STIFFNESS, C_RADIUS_COEFFICIENT, C_TANGENTIAL_MODULUS, C_TORSIONAL_MODULUS, C_DAMPING_TIME, C_FRICTION,
 C_OBJECT_MASS, C_INERTIA_X, C_INERTIA_Y, C_INERTIA_Z, C_FINGER_MASS, C_FINGER_DAMPING, C_FINGER_OFFSET,
 C_ARM_RADIUS, C_NOMINAL_INERTIA, C_TARGET_INERTIA, C_TARGET_DAMPING, C_TORQUE_LIMIT, C_DOB_GAIN, C_USE_DOB,
 C_SUBSTEPS, C_STEP, C_HALF_X, C_HALF_Y, C_HALF_Z, C_OBJECT_BODY, C_ARM_BODY, C_OBJECT_DOF, C_ARM_DOF,
 C_IMPLICIT, C_ANISOTROPY, C_FORCE_OBSERVER, C_MAX_DEPTH, C_SIZE) = range(34)
# --- per-bump geometry rows (2 k, 15): tip offset from the finger origin (world, mm), x_s, y_s, z_s, face sign, -----
G_OFFSET, G_X, G_Y, G_Z, G_FACE, G_SIZE = 0, 3, 6, 9, 12, 13
# --- per-bump state rows (2 k, 6): anchor (object frame, mm), anchor angle [rad], touching at the last step (0/1),
# depth at the last sub-step [mm] -------------------------------------------------------------------------------
B_ANCHOR, B_ANGLE, B_TOUCHING, B_DEPTH, B_SIZE = 0, 3, 4, 5, 6
# --- per-bump outputs (2 k, 12) -----------------------------------------------------------------------------------
(O_NORMAL, O_RADIUS, O_ELASTIC_X, O_ELASTIC_Y, O_TANGENTIAL_X, O_TANGENTIAL_Y, O_TORQUE, O_SLIDING, O_TWIST,
 O_LOAD_RATIO, O_TORQUE_RATIO, O_STICK_RATIO, O_SIZE) = range(13)
# --- loop state vector: gripper, acceleration control + DOB, implicit coupling, outputs ---------------------------
(S_CLOSING, S_CLOSING_RATE, S_ANGLE_1, S_ANGLE_2, S_TORQUE_1, S_TORQUE_2, S_DOB_INPUT, S_DOB_OUTPUT, S_VELOCITY,
 S_TORQUE, S_GRIP_FORCE, S_PEAK_FORCE, S_HAVE_PREVIOUS) = range(13)
S_TWIST, S_APPLIED, S_SIZE = 13, 19, 25                        # previous object twist (6), applied wrench (6)


@njit_cached
def acceleration_step(state, config, force_command, measured_force, angle, period):
    """Acceleration Control with DOB (``control.acceleration_control``) on the state vector; torque [N mm]. The
    force loop reads ``measured_force`` [N] (a force sensor) or, with C_FORCE_OBSERVER, the DOB's estimate / r."""
    velocity = (angle - state[S_ANGLE_1]) / period
    raw = 0.5 * (state[S_TORQUE_1] + state[S_TORQUE_2]) - config[C_NOMINAL_INERTIA] * (
        angle - 2.0 * state[S_ANGLE_1] + state[S_ANGLE_2]) / (period * period)
    gain = config[C_DOB_GAIN]
    disturbance = gain * (raw + state[S_DOB_INPUT]) + (1.0 - 2.0 * gain) * state[S_DOB_OUTPUT]
    state[S_DOB_INPUT], state[S_DOB_OUTPUT] = raw, disturbance
    state[S_ANGLE_2], state[S_ANGLE_1] = state[S_ANGLE_1], angle
    force = disturbance / config[C_ARM_RADIUS] if config[C_FORCE_OBSERVER] > 0.0 else measured_force
    acceleration = (config[C_ARM_RADIUS] * (force_command - force)
                    - config[C_TARGET_DAMPING] * velocity) / config[C_TARGET_INERTIA]
    torque = config[C_NOMINAL_INERTIA] * acceleration + (disturbance if config[C_USE_DOB] > 0.0 else 0.0)
    limit = config[C_TORQUE_LIMIT]
    torque = min(max(torque, -limit), limit)
    state[S_TORQUE_2], state[S_TORQUE_1] = state[S_TORQUE_1], torque
    state[S_VELOCITY], state[S_TORQUE] = velocity, torque
    return torque


@njit_cached(inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit_cached(inline="always")
def _to_local(rotation, x, y, z):
    """R^T (x, y, z): world vector in object coordinates."""
    return (rotation[0, 0] * x + rotation[1, 0] * y + rotation[2, 0] * z,
            rotation[0, 1] * x + rotation[1, 1] * y + rotation[2, 1] * z,
            rotation[0, 2] * x + rotation[1, 2] * y + rotation[2, 2] * z)


@njit_cached(inline="always")
def _to_world(rotation, x, y, z):
    """R (x, y, z): object vector in world coordinates."""
    return (rotation[0, 0] * x + rotation[0, 1] * y + rotation[0, 2] * z,
            rotation[1, 0] * x + rotation[1, 1] * y + rotation[1, 2] * z,
            rotation[2, 0] * x + rotation[2, 1] * y + rotation[2, 2] * z)


@njit_cached
def _fixed_offsets(geometry, arm, position, rotation, fixed):
    """What the sub-steps of one physics step share (the fingers close along y only, the object is held): each bump
    tip's offset from the object along x and z [mm] and their products with R's rows, into ``fixed`` (2 k, 8), so
    that ``_normal_forces`` forms R^T offset with the same operations in the same order as ``_to_local``."""
    for i in range(geometry.shape[0]):
        offset_x = arm[0] + geometry[i, G_OFFSET] - position[0]
        offset_z = arm[2] + geometry[i, G_OFFSET + 2] - position[2]
        fixed[i, 0], fixed[i, 1] = offset_x, offset_z
        for axis in range(3):
            fixed[i, 2 + 2 * axis] = rotation[0, axis] * offset_x
            fixed[i, 3 + 2 * axis] = rotation[2, axis] * offset_z


@njit_cached
def _normal_forces(config, geometry, bumps, arm, closing_mm, closing_rate_mm, position, rotation, velocity, spin,
                   forces, fixed):
    """Normal force of every bump tip [N] into ``forces`` (2 k,) and its depth [mm] into ``bumps``; ``fixed`` from
    ``_fixed_offsets``."""
    count = geometry.shape[0] // 2
    k_n, damping = config[C_NORMAL_STIFFNESS], config[C_DAMPING_TIME]
    half_x, half_y, half_z = config[C_HALF_X], config[C_HALF_Y], config[C_HALF_Z]
    for i in range(geometry.shape[0]):
        side = 2 * (i // count) - 1                                            # -1 left, +1 right
        offset_x, offset_z = fixed[i, 0], fixed[i, 1]
        offset_y = arm[1] + side * (config[C_FINGER_OFFSET] - closing_mm) + geometry[i, G_OFFSET + 1] - position[1]
        face = geometry[i, G_FACE]
        depth = half_y + face * (fixed[i, 4] + rotation[1, 1] * offset_y + fixed[i, 5])       # R^T offset, y
        # a bump not touching at the last step whose tip is found deeper than the bump's own radius did not press
        # into the face: the object met the fingertip edge-on (it slid or turned out of the grasp), a contact the
        # bump law does not describe. A contact that deepened while touching keeps its law (and its force)
        entering_too_deep = depth > config[C_MAX_DEPTH] and bumps[i, B_TOUCHING] == 0.0
        if not (depth > 0.0 and not entering_too_deep
                and abs(fixed[i, 2] + rotation[1, 0] * offset_y + fixed[i, 3]) <= half_x
                and abs(fixed[i, 6] + rotation[1, 2] * offset_y + fixed[i, 7]) <= half_z):
            bumps[i, B_DEPTH] = 0.0
            forces[i] = 0.0
            continue
        bumps[i, B_DEPTH] = depth
        turn_x, turn_y, turn_z = _cross(spin[0], spin[1], spin[2], offset_x, offset_y, offset_z)
        rate = face * _to_local(rotation, -velocity[0] - turn_x, -side * closing_rate_mm - velocity[1] - turn_y,
                                -velocity[2] - turn_z)[1]                         # d' [mm/s]
        root = math.sqrt(depth)
        forces[i] = max(k_n * depth * root + damping * 1.5 * k_n * root * rate, 0.0)


@njit_cached(inline="always")
def _friction_along(friction, anisotropy, shear_x, shear_y):
    """Friction coefficient along the bump's shear (x, y) of an anisotropic surface: the radius of the ellipse with
    semi-axes mu (1 + e) along the sensor's x and mu (1 - e) along y in the shear's direction (mu when e = 0 or
    without shear)."""
    length = math.hypot(shear_x, shear_y)
    if anisotropy == 0.0 or length == 0.0:
        return friction
    along_x, along_y = shear_x / (length * (1.0 + anisotropy)), shear_y / (length * (1.0 - anisotropy))
    return friction / math.sqrt(along_x * along_x + along_y * along_y)


@njit_cached
def physics_step(config, geometry, state, bumps, out, xpos, xmat, xipos, qvel, xfrc_applied, mocap_pos,
                 force_commands):
    """Advance the gripper and the contact by one physics step (module docstring); write xfrc_applied, mocap_pos.

    ``force_commands`` (m,) [N]: the grasp-force commands over the step, each held for 1 / m of it (m = 1 when the
    controller runs at the physics rate or slower; m > 1 when the physics step spans several control steps).
    """
    obj, arm_body = int(config[C_OBJECT_BODY]), int(config[C_ARM_BODY])
    dof = int(config[C_OBJECT_DOF])
    rotation = xmat[obj].reshape(3, 3)
    position = xpos[obj] * MM
    com = xipos[obj] * MM
    velocity = qvel[dof:dof + 3] * MM                                          # mm/s
    spin_world = _to_world(rotation, qvel[dof + 3], qvel[dof + 4], qvel[dof + 5])   # rad/s
    spin = np.array(spin_world)
    arm = xpos[arm_body] * MM
    count = geometry.shape[0]
    half_count = count // 2
    substeps = int(config[C_SUBSTEPS])
    step = config[C_STEP]
    period = step / substeps
    mass, damping = config[C_FINGER_MASS], config[C_FINGER_DAMPING]
    radius = config[C_ARM_RADIUS]
    forces = np.zeros(count)
    mean = np.zeros(count)
    fixed = np.empty((count, 8))
    _fixed_offsets(geometry, arm, position, rotation, fixed)
    for substep in range(substeps):                                            # 1. gripper at the actuator rate
        force_command = force_commands[substep * force_commands.size // substeps]
        closing_mm = state[S_CLOSING] * MM
        _normal_forces(config, geometry, bumps, arm, closing_mm, state[S_CLOSING_RATE] * MM, position, rotation,
                       velocity, spin, forces, fixed)
        left, right = forces[:half_count].sum(), forces[half_count:].sum()
        grip = 0.5 * (left + right)                                            # N per finger
        torque = acceleration_step(state, config, force_command, grip, closing_mm / radius, period)
        rate = (state[S_CLOSING_RATE] + period / mass * (torque / radius - grip)) / (1.0 + period * damping / mass)
        state[S_CLOSING_RATE] = rate
        state[S_CLOSING] += period * rate
        state[S_PEAK_FORCE] = max(state[S_PEAK_FORCE], left, right)
        for i in range(count):
            mean[i] += forces[i] / substeps
    state[S_GRIP_FORCE] = 0.5 * mean.sum()
    finger = config[C_FINGER_OFFSET] - state[S_CLOSING] * MM
    for f in range(2):
        mocap_pos[f, 0], mocap_pos[f, 1], mocap_pos[f, 2] = arm[0] / MM, (arm[1] + (2 * f - 1) * finger) / MM, \
            arm[2] / MM

    # 2. tangential contact at the mean normal forces; 3. wrench and its stiffness and damping on the object twist
    angle = math.atan2(rotation[0, 2], rotation[0, 0])                       # object rotation about +y
    stiffness = np.zeros((6, 6))
    viscosity = np.zeros((6, 6))
    wrench = np.zeros(6)
    row = np.zeros(6)
    k_n, tau = config[C_NORMAL_STIFFNESS], config[C_DAMPING_TIME]
    arm_velocity_mm = qvel[int(config[C_ARM_DOF])] * MM
    for i in range(count):
        f = i // half_count
        x_s, y_s, z_s = geometry[i, G_X:G_X + 3], geometry[i, G_Y:G_Y + 3], geometry[i, G_Z:G_Z + 3]
        tip_x = mocap_pos[f, 0] * MM + geometry[i, G_OFFSET]
        tip_y = mocap_pos[f, 1] * MM + geometry[i, G_OFFSET + 1]
        tip_z = mocap_pos[f, 2] * MM + geometry[i, G_OFFSET + 2]
        touching = mean[i] > 0.0
        finger_angle = angle if f == 0 else -angle
        if touching and bumps[i, B_TOUCHING] == 0.0:                          # first touch: anchor on the face
            local = _to_local(rotation, tip_x - position[0], tip_y - position[1], tip_z - position[2])
            bumps[i, B_ANCHOR], bumps[i, B_ANCHOR + 2] = local[0], local[2]
            bumps[i, B_ANCHOR + 1] = -geometry[i, G_FACE] * config[C_HALF_Y]
            bumps[i, B_ANGLE] = finger_angle
        bumps[i, B_TOUCHING] = 1.0 if touching else 0.0
        if not touching:
            for j in range(O_SIZE):
                out[i, j] = 0.0
            continue
        anchor_x, anchor_y, anchor_z = _to_world(rotation, bumps[i, B_ANCHOR], bumps[i, B_ANCHOR + 1],
                                                 bumps[i, B_ANCHOR + 2])                  # relative to the origin
        gap_x = position[0] + anchor_x - tip_x
        gap_y = position[1] + anchor_y - tip_y
        gap_z = position[2] + anchor_z - tip_z
        twist = finger_angle - bumps[i, B_ANGLE]
        shear_x = gap_x * x_s[0] + gap_y * x_s[1] + gap_z * x_s[2]
        shear_y = gap_x * y_s[0] + gap_y * y_s[1] + gap_z * y_s[2]
        law = bump_law(mean[i], shear_x, shear_y, twist,
                       _friction_along(config[C_FRICTION], config[C_ANISOTROPY], shear_x, shear_y),
                       config[C_RADIUS_COEFFICIENT], config[C_TANGENTIAL_MODULUS], config[C_TORSIONAL_MODULUS])
        (contact_radius, q_x, q_y, torque, load_ratio, torque_ratio, stick_ratio, sliding, elastic_x, elastic_y,
         _, elastic_twist) = law
        if sliding > 0.0:                                                      # the anchor slides to the limit
            moved = _to_local(rotation, tip_x + elastic_x * x_s[0] + elastic_y * y_s[0] - position[0],
                              tip_y + elastic_x * x_s[1] + elastic_y * y_s[1] - position[1],
                              tip_z + elastic_x * x_s[2] + elastic_y * y_s[2] - position[2])
            bumps[i, B_ANCHOR], bumps[i, B_ANCHOR + 2] = moved[0], moved[2]
            bumps[i, B_ANGLE] = finger_angle - elastic_twist
        full_stick = 2.0 * config[C_TANGENTIAL_MODULUS] * contact_radius      # N/mm
        damping_x = damping_y = 0.0
        if sliding == 0.0:                                                     # viscous term on a stuck bump
            turn = _cross(spin[0], spin[1], spin[2], anchor_x, anchor_y, anchor_z)
            relative_x = velocity[0] + turn[0]
            relative_y = velocity[1] + turn[1]
            relative_z = velocity[2] + turn[2] - arm_velocity_mm
            damping_x = tau * full_stick * (relative_x * x_s[0] + relative_y * x_s[1] + relative_z * x_s[2])
            damping_y = tau * full_stick * (relative_x * y_s[0] + relative_y * y_s[1] + relative_z * y_s[2])
        shear_x, shear_y = q_x + damping_x, q_y + damping_y
        force_x = mean[i] * z_s[0] - shear_x * x_s[0] - shear_y * y_s[0]         # on the object [N]
        force_y = mean[i] * z_s[1] - shear_x * x_s[1] - shear_y * y_s[1]
        force_z = mean[i] * z_s[2] - shear_x * x_s[2] - shear_y * y_s[2]
        lever_x, lever_y, lever_z = (tip_x - com[0]) / MM, (tip_y - com[1]) / MM, (tip_z - com[2]) / MM   # m
        moment = _cross(lever_x, lever_y, lever_z, force_x, force_y, force_z)
        wrench[0] += force_x
        wrench[1] += force_y
        wrench[2] += force_z
        for a in range(3):
            wrench[3 + a] += moment[a] - torque / MM * z_s[a]                     # N m
        # stiffness rows (SI): normal, and for a stuck bump both shears and the twist
        normal_stiffness = 1.5 * k_n * math.sqrt(bumps[i, B_DEPTH]) * MM        # N/m
        _add_row(stiffness, viscosity, row, z_s, lever_x, lever_y, lever_z, normal_stiffness,
                 tau * normal_stiffness)
        if sliding == 0.0:
            shear_stiffness = full_stick * stick_ratio * MM
            _add_row(stiffness, viscosity, row, x_s, lever_x, lever_y, lever_z, shear_stiffness, tau * full_stick * MM)
            _add_row(stiffness, viscosity, row, y_s, lever_x, lever_y, lever_z, shear_stiffness, tau * full_stick * MM)
            torsional = 16.0 * config[C_TORSIONAL_MODULUS] * contact_radius**3 / 3.0 / MM     # N m/rad
            for a in range(3):
                for b in range(3):
                    stiffness[3 + a, 3 + b] += torsional * z_s[a] * z_s[b]
        out[i, O_NORMAL], out[i, O_RADIUS] = mean[i], contact_radius
        out[i, O_ELASTIC_X], out[i, O_ELASTIC_Y] = elastic_x, elastic_y
        out[i, O_TANGENTIAL_X], out[i, O_TANGENTIAL_Y], out[i, O_TORQUE] = q_x, q_y, torque
        out[i, O_SLIDING], out[i, O_TWIST] = sliding, twist
        out[i, O_LOAD_RATIO], out[i, O_TORQUE_RATIO], out[i, O_STICK_RATIO] = load_ratio, torque_ratio, stick_ratio

    if config[C_IMPLICIT] > 0.0:
        _implicit_wrench(config, state, rotation, qvel[dof:dof + 3], spin, wrench, stiffness, viscosity, step,
                         arm_velocity_mm / MM)
    for a in range(6):
        xfrc_applied[obj, a] = wrench[a]
        xfrc_applied[arm_body, a] = -wrench[a] if a < 3 else 0.0


@njit_cached
def _add_row(stiffness, viscosity, row, direction, lever_x, lever_y, lever_z, spring, damper):
    """Add k row^T row and c row^T row for a point contact along ``direction`` at ``lever`` [m] (row = [n, r x n])."""
    row[0], row[1], row[2] = direction[0], direction[1], direction[2]
    row[3], row[4], row[5] = _cross(lever_x, lever_y, lever_z, direction[0], direction[1], direction[2])
    for a in range(6):
        for b in range(6):
            product = row[a] * row[b]
            stiffness[a, b] += spring * product
            viscosity[a, b] += damper * product


@njit_cached
def _implicit_wrench(config, state, rotation, velocity, spin, wrench, stiffness, viscosity, step, arm_velocity):
    """Replace ``wrench`` by the one that makes MuJoCo's explicit step the backward-Euler step of the contact
    (module docstring); the 6 x 6 system is symmetric positive definite: Cholesky by hand, no allocation per call
    beyond the small work arrays. The springs stretch with the object's motion relative to the fingers, which rise
    with the arm (``arm_velocity`` [m/s] along z): the stiffness acts on the relative twist (on the absolute one,
    a lifted object lagged the fingers by h v_arm and its bumps carried a spurious k h v_arm on top of its load)."""
    mass = config[C_OBJECT_MASS]
    inertia = (config[C_INERTIA_X], config[C_INERTIA_Y], config[C_INERTIA_Z])
    system = np.empty((6, 6))
    mass_matrix = np.zeros((6, 6))
    for a in range(3):
        mass_matrix[a, a] = mass
        for b in range(3):
            mass_matrix[3 + a, 3 + b] = (rotation[a, 0] * inertia[0] * rotation[b, 0]
                                         + rotation[a, 1] * inertia[1] * rotation[b, 1]
                                         + rotation[a, 2] * inertia[2] * rotation[b, 2])
    twist = np.empty(6)
    relative = np.empty(6)
    for a in range(3):
        twist[a], twist[3 + a] = velocity[a], spin[a]
        relative[a], relative[3 + a] = velocity[a], spin[a]
    relative[2] -= arm_velocity
    have_previous = state[S_HAVE_PREVIOUS] > 0.0
    right = np.empty(6)
    for a in range(6):
        other = 0.0
        if have_previous:
            for b in range(6):
                other += mass_matrix[a, b] * (twist[b] - state[S_TWIST + b]) / step
            other -= state[S_APPLIED + a]
        pushed = 0.0
        for b in range(6):
            system[a, b] = mass_matrix[a, b] + step * viscosity[a, b] + step * step * stiffness[a, b]
            pushed += stiffness[a, b] * relative[b]
        right[a] = step * (other + wrench[a] - step * pushed)
    change = _cholesky_solve(system, right)
    for a in range(6):
        correction = 0.0
        for b in range(6):
            correction += step * stiffness[a, b] * (relative[b] + change[b]) + viscosity[a, b] * change[b]
        state[S_TWIST + a] = twist[a]
        state[S_APPLIED + a] = wrench[a] - correction
    for a in range(6):
        wrench[a] = state[S_APPLIED + a]
    state[S_HAVE_PREVIOUS] = 1.0


@njit_cached
def _cholesky_solve(matrix, right):
    """Solve A x = b for a small symmetric positive definite A (overwritten by its factor)."""
    size = matrix.shape[0]
    for j in range(size):
        diagonal = matrix[j, j]
        for k in range(j):
            diagonal -= matrix[j, k] * matrix[j, k]
        matrix[j, j] = math.sqrt(diagonal)
        for i in range(j + 1, size):
            value = matrix[i, j]
            for k in range(j):
                value -= matrix[i, k] * matrix[j, k]
            matrix[i, j] = value / matrix[j, j]
    solution = right.copy()
    for i in range(size):
        for k in range(i):
            solution[i] -= matrix[i, k] * solution[k]
        solution[i] /= matrix[i, i]
    for i in range(size - 1, -1, -1):
        for k in range(i + 1, size):
            solution[i] -= matrix[k, i] * solution[k]
        solution[i] /= matrix[i, i]
    return solution


# --- one row of the trial's 100 Hz record, written after each block ---------------------------------------------
(R_GRIP_FORCE, R_HEIGHT, R_RELATIVE_X, R_RELATIVE_Y, R_RELATIVE_Z, R_ROTATION, R_SLIDING, R_SIZE) = range(8)


@njit_cached
def run_block(commands, lift_targets, config, geometry, state, bumps, out, xpos, xmat, xipos, qvel, xfrc_applied,
              mocap_pos, ctrl, model_address, data_address, mj_step, grasp_local, record):
    """``len(commands)`` physics steps: contact step with commands[j] (m,) [N], lift target [m], then MuJoCo's step;
    then the record of the block's end into ``record`` (R_SIZE,): grip force per finger [N], object bottom height
    [m], the object's grasp point (``grasp_local`` [m] in the object's frame) relative to the arm [mm], the object's
    rotation about the grasp axis [rad], sliding bumps.

    ``mj_step`` is MuJoCo's C function (a ctypes function taking the mjModel and mjData addresses), passed as an
    argument so that this loop runs without returning to Python between steps and still caches its compilation.
    """
    for j in range(commands.shape[0]):
        ctrl[0] = lift_targets[j]
        physics_step(config, geometry, state, bumps, out, xpos, xmat, xipos, qvel, xfrc_applied, mocap_pos,
                     commands[j])
        mj_step(model_address, data_address)
    obj, arm = int(config[C_OBJECT_BODY]), int(config[C_ARM_BODY])
    rotation = xmat[obj].reshape(3, 3)
    record[R_GRIP_FORCE] = state[S_GRIP_FORCE]
    record[R_HEIGHT] = xpos[obj, 2] - config[C_HALF_Z] / MM
    for a in range(3):
        point = xpos[obj, a] + rotation[a, 0] * grasp_local[0] + rotation[a, 1] * grasp_local[1] \
            + rotation[a, 2] * grasp_local[2]
        record[R_RELATIVE_X + a] = (point - xpos[arm, a]) * MM
    record[R_ROTATION] = math.atan2(rotation[0, 2], rotation[0, 0])
    record[R_SLIDING] = (out[:, O_SLIDING] > 0.0).sum()
