"""The minimum grasp force tau_min of a trial, found the way the paper does: constant-force trials, nothing else.

A constant grip force per finger is applied from the grasp on (lift, then ``hold_time`` of hold); it holds when the
object neither touches the table nor turns out of the grasp. The bracket comes from trials only - a force seen to
fail and one seen to hold, by dividing and multiplying a start force - never from the model's slip limit; then
bisection in log force until the bracket is within ``resolution``. The search keeps the trial's own settings (its
friction, grasp jitter, misalignment, sensor noise and seed), so tau_min belongs to that trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from fem.validation import check_positive, check_range

from ._trial import GraspObject, TrialSettings

__all__ = ["MinimumForce", "holds_at", "minimum_grip_force"]

MAXIMUM_DOUBLINGS = 12          # 1 N * 2^12: far beyond the finger's 30 N
MAXIMUM_HALVINGS = 12


@dataclass
class MinimumForce:
    """tau_min [N] (the least force seen to hold), the largest force seen to fail below it [N], and every trial
    (force [N], held) in order."""

    force: float
    failing: float
    trials: list = field(default_factory=list)

    @property
    def resolution(self) -> float:
        """Relative width of the final bracket, force / failing - 1 [-]."""
        return self.force / self.failing - 1.0


def holds_at(obj: GraspObject, settings: TrialSettings, force: float, hold_time: float = 1.0) -> bool:
    """Whether a constant grip of ``force`` [N] per finger lifts and holds the object (no table contact during the
    hold, not turned out of the grasp)."""
    from ._world import run_trial

    result = run_trial(obj, replace(settings, constant_force=float(force), hold_time=hold_time, place=False))
    return bool(result.success and not result.rotated)


def minimum_grip_force(obj: GraspObject, settings: TrialSettings, resolution: float = 0.02, start: float = 1.0,
                       hold_time: float = 1.0, maximum_force: float = 30.0, factor: float = 2.0) -> MinimumForce:
    """Least constant grip force per finger [N] that holds the object in this trial's conditions (module
    docstring): bracket by dividing / multiplying by ``factor`` from ``start`` [N] (e.g. a force a controller
    was seen to hold at, with a small factor), then bisection to ``resolution`` (relative).

    Raises ValueError if even ``maximum_force`` [N] does not hold, or if a force below ``start`` / factor^12 still
    holds.
    """
    check_range("resolution", resolution, 0.0, 1.0, low_open=True)
    check_positive("start", start, "N")
    check_positive("hold_time", hold_time, "s")
    check_range("factor", factor, 1.0 + resolution, 16.0, low_open=True)
    trials = []

    def held(force: float) -> bool:
        outcome = holds_at(obj, settings, force, hold_time)
        trials.append((force, outcome))
        return outcome

    force = float(start)
    if held(force):
        high = force
        for _ in range(MAXIMUM_HALVINGS):
            force /= factor
            if not held(force):
                break
            high = force
        else:
            raise ValueError(f"{obj.name}: a constant grip of {force:.3g} N still holds; no failing force below "
                             f"start={start!r} N / {factor:g}^{MAXIMUM_HALVINGS}")
        low = force
    else:
        low = force
        for _ in range(MAXIMUM_DOUBLINGS):
            force = min(factor * force, maximum_force)
            if held(force):
                break
            low = force
            if force >= maximum_force:
                raise ValueError(f"{obj.name}: not held even at maximum_force={maximum_force!r} N")
        high = force
    while high / low > 1.0 + resolution:
        middle = math.sqrt(low * high)
        if held(middle):
            high = middle
        else:
            low = middle
    return MinimumForce(high, low, trials)
