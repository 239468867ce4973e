"""Closed loop: the MuJoCo grasp (a parallel-jaw gripper with two 3x3-array gel fingertips on a lifting arm) and the
multi-rate runner, plant and control joined; may import sensing, estimation, control and plant.

Loop (paper Fig. 7): reduced contact model -> base pressure -> sensor (100 Hz, noise) -> estimator (per-bump forces
and load ratios, and eq. 9's shear displacement on a 3x3 BumpLayout) -> grasp-force controller (1 kHz; by default
the incipient-slip law of ``controller.control.incipient_slip``, ``ControllerKind``) -> Acceleration Control with DOB (8
kHz) -> finger motor force. The controller gets no object data (mass, moment, friction) and no simulator slip state.
Sequence: approach, grasp on the table, lift, hold (4 s), place, release. From Python::

    from controller.closed_loop import TABLE_I_OBJECTS, TrialSettings, run_trial
    result = run_trial(TABLE_I_OBJECTS["eclair"], TrialSettings(friction_coefficient=0.5))
    result.trace_frame()                      # pandas DataFrame of the 100 Hz trace

How the contact is enforced. MuJoCo's friction is soft (objects creep, docs/design.md, sec. 11), so the fingers and
the object do not collide in MuJoCo: every bump tip is a contact of the reduced model, applied to the object (and,
reversed, to the arm) through ``xfrc_applied`` by a compiled step (``_kernel``):

* normal: P_i = k_n d_i^(3/2) (1 + tau_d 1.5 d_i'/d_i), d_i the penetration of bump tip i into the object's face;
* tangential: at first touch the bump is anchored to the material point of the face it touches (object frame); the
  shear displacement delta_i is the anchor's position relative to the bump tip in the sensor plane and phi_i the
  object's rotation about the fingertip normal since the anchor was set; ``contact.reduced.bump_law`` gives the
  loads (Mindlin, Lubkin, elliptic combined limit), plus a viscous term tau_d k_t delta_i';
* slip: a bump on its friction limit moves its anchor so that its elastic displacement is the one that carries the
  limit load (an elasto-plastic "bristle", one per bump): stick is exact (the anchor does not move, so a held
  object does not creep), partial slip is Mindlin's inside each bump, incipient slip of the array is some bumps
  sliding, gross slip (translation or rotation) all of them.

Rates. MuJoCo steps the arm, the object and its table contact at ``PHYSICS_RATE_HZ`` (500 Hz); within each step
the kernel sub-steps the fingers and the Acceleration Control at 8 kHz against the object's pose, and couples the
contact to the object implicitly (backward Euler on the contact terms, so the light eclair between two stiff
fingertips needs no 4 kHz step); a sensor frame's physics steps run in compiled code, MuJoCo's own ``mj_step`` called
from it. Outcomes match the explicit 8 kHz loop this replaced within the tolerances of
tests/test_closed_loop_kernel.py. With the incipient-slip controller the whole trial is one compiled call
(``_fused``): per frame the sensing, the controller's observe and 1 kHz steps (the law's compiled kernels,
``controller.control._slip_law``, on the controller's arrays) and the physics steps, the same arithmetic as the
Python frame loop the displacement-target law keeps (tests/test_closed_loop_fused.py).
The world is SI; the reduced model is mm, N, N mm: ``ContactBridge`` converts at one place (names carry the unit).
Object-table contact stays MuJoCo's (elliptic cone): it only decides when the object leaves or touches the table.
"""


from ._batch import default_processes, map_trials, run_trials
from ._bench import EstimatorBench, belief_errors, estimator_bench
from ._bridge import ContactBridge
from ._minimum import MinimumForce, holds_at, minimum_grip_force
from ._multirate import LoopSample, MultiRateRunner, rate_ratio
from ._sensing import SensingChain, SensorFrame
from ._trial import (ACTUATOR_RATE_HZ, ARM_RADIUS, CREEP_WINDOW, DESIGN_FRICTION, FRICTION_RANGE, GRAVITY,
                     GRIP_LIMIT, HELD_OUT_SEED, LOOP_RATE, MM_PER_M, OUTCOMES, PHYSICS_RATE_HZ, PLANT_SPREAD,
                     ROTATION_LIMIT, TABLE_I_OBJECTS, TORQUE_LIMIT, TUNING_SEED, ControllerKind, GraspObject,
                     TargetDesign, TrialResult, TrialSettings, default_tip, random_settings, required_grip_force)
from ._world import GraspWorld, run_trial

__all__ = ["GraspObject", "TABLE_I_OBJECTS", "TargetDesign", "TrialSettings", "TrialResult", "ControllerKind",
           "GraspWorld", "SensingChain", "SensorFrame", "ContactBridge", "run_trial", "run_trials", "map_trials",
           "default_processes", "MinimumForce", "holds_at", "minimum_grip_force", "random_settings",
           "required_grip_force", "default_tip", "DESIGN_FRICTION", "GRAVITY", "MM_PER_M", "PHYSICS_RATE_HZ",
           "ACTUATOR_RATE_HZ", "LOOP_RATE", "ROTATION_LIMIT", "CREEP_WINDOW", "TORQUE_LIMIT", "ARM_RADIUS",
           "GRIP_LIMIT", "LoopSample", "MultiRateRunner", "rate_ratio", "FRICTION_RANGE", "PLANT_SPREAD", "OUTCOMES",
           "TUNING_SEED", "HELD_OUT_SEED", "estimator_bench", "EstimatorBench", "belief_errors"]
