"""Shared pytest setup: a non-interactive matplotlib backend for study tests, and the installed versions against
the ones CI tested (``constraints.txt``), named in the header and again beside any failure."""

import re
from importlib import metadata
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

CONSTRAINTS = Path(__file__).resolve().parent.parent / "constraints.txt"


def untested_versions() -> list[str]:
    """'name installed (tested pinned)' for every package of constraints.txt installed at another version."""
    if not CONSTRAINTS.is_file():
        return []
    differing = []
    for line in CONSTRAINTS.read_text().splitlines():
        match = re.fullmatch(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)\s*", line.split("#")[0])
        if not match:
            continue
        name, tested = match.groups()
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
        if installed != tested:
            differing.append(f"{name} {installed} (tested {tested})")
    return differing


def pytest_report_header(config):
    differing = untested_versions()
    if not differing:
        return f"dependencies: the versions of {CONSTRAINTS.name}"
    return f"dependencies at versions CI did not test ({CONSTRAINTS.name}): " + ", ".join(differing)


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    differing = untested_versions()
    if exitstatus != 0 and differing and terminalreporter.stats.get("failed"):
        terminalreporter.write_line(
            "Failures with dependencies at versions CI did not test - suspects first: " + ", ".join(differing)
            + f". To install the tested versions: pip install -e '.[all]' -c {CONSTRAINTS.name}", red=True)


REFERENCE_MACHINE = {"machine_memory": 16e9, "available_memory": 8e9}   # bytes: physical, free


@pytest.fixture(autouse=True)
def reference_machine(monkeypatch):
    """Every test sees the same machine, 16 GB with 8 GB free: no outcome depends on the free memory at one instant
    (the memory refusals of contact.limits and contact.budget read these two functions)."""
    import contact.limits

    for name, value in REFERENCE_MACHINE.items():
        monkeypatch.setattr(contact.limits, name, lambda value=value: value)
    return REFERENCE_MACHINE


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
