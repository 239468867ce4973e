"""The stability study: every case converges with a finite error against theory, or records a clear error."""

import csv
import math

import pytest


@pytest.fixture(scope="module")
def quick_rows(tmp_path_factory):
    from studies.stability import run

    out_dir = tmp_path_factory.mktemp("stability")
    summary = run(out_dir, quick=True)
    assert (out_dir / "stability.png").is_file() and (out_dir / "stability.pdf").is_file()
    with open(out_dir / "stability.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert summary["cases"] == len(rows) >= 8
    return rows


def test_every_case_converges_with_a_finite_error_or_has_an_error_message(quick_rows):
    for row in quick_rows:
        if row["outcome"] == "converged":
            values = [float(row[key]) for key in ("error", "tolerance", "residual", "contact_radius_error")]
            assert all(math.isfinite(v) for v in values), row["case"]
            assert float(row["residual"]) < 1e-6 and int(row["iterations"]) >= 1, row["case"]
            assert row["message"] == "", row["case"]
        else:
            assert row["outcome"] == "error" and len(row["message"]) > 20, row["case"]
        assert row["verdict"] not in ("NON-FINITE result", "error (unexpected)"), row["case"]


def test_expected_errors_are_clear(quick_rows):
    messages = {row["case"]: row["message"] for row in quick_rows if row["expect"] == "error"}
    assert all(messages.values()), messages
    assert "material.nu=0.5 outside allowed range" in messages["nu=0.5 (excluded)"]
    assert "not below friction_coefficient x P" in messages["Q/(mu P)=1 (gross slip)"]


def test_modulus_contrast_is_scale_invariant(quick_rows):
    # E with P ~ E leaves the problem unchanged up to scale (linear elasticity, rigid body, Coulomb friction):
    # identical stick ratios up to the Newton tolerance (1e-10 relative), far inside the stick-zone quantisation.
    # (mu with Q ~ mu is not exactly invariant at nu = 0.45: the normal-tangential coupling scales with beta/mu.)
    same = [float(row["stick_ratio"]) for row in quick_rows if row["group"] == "modulus"]
    assert len(same) >= 2 and max(same) - min(same) < 1e-6
    assert all(row["verdict"] == "within tolerance" for row in quick_rows if row["group"] in ("modulus", "friction"))
