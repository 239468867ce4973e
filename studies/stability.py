"""Solver stability: nu -> 0.5 (P1, P2, P1 nodal-average), modulus contrast, friction, load ratio near gross slip,
load size, meshes.

Each case (studies/_stability_cases.py) either converges, and its error against Cattaneo-Mindlin / Lubkin / Hertz
is reported with the tolerance of docs/theory.md, sec. 11, or raises a clear error that is recorded with its message.
A NaN or an unexpected outcome is marked in the ``verdict`` column. Writes stability.csv, stability.png/.pdf.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

from studies._output import largest_abs, save_figure, write_csv_atomic

NAME = "stability"
MESSAGE_CHARS = 400          # error messages are cut to this length in the table (residual histories are long)


def _outcome_columns(result) -> dict:
    increments = result.increments
    return {"increments": len(increments), "iterations": max(i.iterations for i in increments),
            "substeps": max(getattr(i, "substeps", 1) for i in increments),
            "residual": max(i.residual for i in increments), "dofs": result.mesh_info["dofs"],
            "min_dihedral_deg": result.mesh_info["min_dihedral_deg"]}


def _verdict(row: dict, expect: str) -> str:
    if row["outcome"] == "error":
        return "clear error (expected)" if expect == "error" else "error (unexpected)"
    if expect == "error":
        return "converged (an error was expected)"
    numbers = [v for v in row.values() if isinstance(v, float)]
    if not all(math.isfinite(v) for v in numbers):
        return "NON-FINITE result"
    return "within tolerance" if abs(row["error"]) <= row["tolerance"] else "outside tolerance"


def solve_case(case, quick: bool) -> dict:
    """Solve one case; the row holds outcome, iterations, residual, theory comparison or the error message."""
    from contact import scene_from_dict, solve_scene
    from studies._stability_cases import build_scene, compare_with_theory

    row = {"group": case.group, "case": case.label, "expect": case.expect}
    start = time.perf_counter()
    try:
        document, force = build_scene(case, quick)
        row["size_contact"] = document["mesh"]["size_contact"]
        result = solve_scene(scene_from_dict(document))
        row.update(outcome="converged", **_outcome_columns(result),
                   **compare_with_theory(case, document, force, result))
    except Exception as error:                 # ValueError, PathNotCompleted, ...: the outcome of this case
        row.update(outcome="error", message=f"{type(error).__name__}: {error}"[:MESSAGE_CHARS])
    row["wall_time"] = time.perf_counter() - start
    row["verdict"] = _verdict(row, case.expect)
    return row


def run(out_dir, quick: bool = False) -> dict:
    """Run the cases (a handful of CI-size ones with ``quick``), write the table and the figure."""
    from tqdm import tqdm

    from studies._stability_cases import CASES

    out_dir = Path(out_dir)
    cases = [case for case in CASES if case.quick or not quick]
    rows = []
    for case in tqdm(cases, desc=NAME, unit="case"):
        rows.append(solve_case(case, quick))
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)          # keep what is done if the run is interrupted
    save_figure(_plot(rows), out_dir, NAME)
    unexpected = [r for r in rows if r["verdict"] not in ("within tolerance", "clear error (expected)")]
    for row in unexpected:
        print(f"{NAME}: {row['case']}: {row['verdict']} {row.get('message', '')[:200]}")
    relative = [r["error"] / r["tolerance"] for r in rows if r["outcome"] == "converged" and r.get("tolerance")]
    return {"max_error": largest_abs(relative), "error_meaning": "largest |error| / tolerance over converged cases",
            "unexpected": len(unexpected), "cases": len(rows)}


def _plot(rows: list[dict]):
    import matplotlib.pyplot as plt

    colours = {"within tolerance": "#2b8cbe", "outside tolerance": "#fdae61", "clear error (expected)": "#7f7f7f"}
    fig, (axis_error, axis_radius) = plt.subplots(2, 1, figsize=(max(8.0, 0.42 * len(rows)), 8.0), sharex=True)
    positions = range(len(rows))
    for x, row in zip(positions, rows):
        colour = colours.get(row["verdict"], "#d7191c")             # red: anything unexpected
        if row["outcome"] == "converged":
            scaled = abs(row["error"]) / row["tolerance"] if row["tolerance"] else math.nan
            axis_error.bar(x, scaled, color=colour)
            axis_radius.bar(x, row["contact_radius_error"], color=colour)
        else:
            axis_error.annotate("error", (x, 0), rotation=90, ha="center", va="bottom", fontsize=7, color=colour)
    axis_error.axhline(1.0, color="k", ls=":", lw=1)
    axis_error.set_xlim(-0.6, len(rows) - 0.4)
    axis_error.set_ylabel("|error vs theory| / tolerance")
    axis_error.set_yscale("symlog", linthresh=0.1)
    axis_radius.set_ylabel("a / a_Hertz - 1 (press)")
    axis_radius.set_xticks(list(positions), [f"{r['group']}: {r['case']}" for r in rows], rotation=70, ha="right",
                           fontsize=7)
    for verdict, colour in list(colours.items()) + [("unexpected", "#d7191c")]:
        axis_error.bar(0, 0, color=colour, label=verdict)
    axis_error.legend(fontsize=7, loc="upper left")
    for axis in (axis_error, axis_radius):
        axis.grid(True, axis="y", alpha=0.3)
    fig.suptitle("Solver stability: error against theory / tolerance (docs/theory.md, sec. 11) per case; "
                 "'error': the case raised (message in stability.csv)")
    fig.tight_layout()
    return fig
