"""Closed-loop grasp in MuJoCo: a parallel-jaw gripper with two 3x3-array gel fingertips on a lifting arm.

Loop (paper Fig. 7): reduced contact model -> base pressure -> sensor (100 Hz, noise) -> estimator (eq. 9 on a 3x3
BumpLayout) -> GraspForceController (1 kHz) -> AccelerationController with DOB (8 kHz) -> finger motor force, with
MuJoCo stepping at 8 kHz. Sequence: approach, grasp on the table, lift, hold (4 s), place, release. The controller
gets no object data (mass, moment, friction).

How the contact is enforced. MuJoCo's friction is soft (objects creep, docs/design.md, sec. 11), so the fingers and the
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
The world is SI; the reduced model is mm, N, N mm: ``ContactBridge`` converts at one place (names carry the unit).
Object-table contact stays MuJoCo's (elliptic cone): it only decides when the object leaves or touches the table.
"""


from ._bridge import ContactBridge
from ._sensing import SensingChain
from ._trial import (ARM_RADIUS, CONTACT_RATE_HZ, DESIGN_FRICTION, GRAVITY, LOOP_RATE, MM_PER_M, PHYSICS_RATE_HZ,
                     ROTATION_LIMIT, TABLE_I_OBJECTS, TORQUE_LIMIT, GraspObject, TargetDesign, TrialResult,
                     TrialSettings, default_tip, random_settings, required_grip_force)
from ._world import GraspWorld, run_trial

__all__ = ["GraspObject", "TABLE_I_OBJECTS", "TargetDesign", "TrialSettings", "TrialResult", "GraspWorld",
           "SensingChain", "ContactBridge", "run_trial", "random_settings", "required_grip_force", "default_tip",
           "DESIGN_FRICTION", "GRAVITY", "MM_PER_M", "PHYSICS_RATE_HZ", "CONTACT_RATE_HZ", "LOOP_RATE",
           "ROTATION_LIMIT", "TORQUE_LIMIT", "ARM_RADIUS"]
