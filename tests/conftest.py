"""Shared pytest setup: a non-interactive matplotlib backend for study tests."""

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")


@pytest.fixture
def failing_after_press(monkeypatch):
    """Make every Newton solve after the press fail, as a stalled increment would (bisection cannot rescue it)."""
    import contact.solver
    from contact._newton import ContactNotConverged

    real = contact.solver.solve_increment

    def solve(compliance, gap0, lever, augmentation, mu, previous, control, **options):
        if control.normal_force is None or np.any(previous.normal_force > 0):
            raise ContactNotConverged("forced failure", [1.0, 0.5, 0.25])
        return real(compliance, gap0, lever, augmentation, mu, previous, control, **options)

    monkeypatch.setattr(contact.solver, "solve_increment", solve)
