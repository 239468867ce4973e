"""Every figure study on its default settings, one after another, into one output folder (the README's main job)."""

from __future__ import annotations

import time
from pathlib import Path

NAME = "figures"
FIGURE_STUDIES = ("fig2b", "fig3b", "torsion-theory", "fig3", "fig4", "fig6", "fig9", "convergence")


def run(out_dir, quick: bool = False) -> dict:
    """Run each study of FIGURE_STUDIES; a failing study is reported and the others still run."""
    from studies._registry import find_studies

    available = find_studies()
    failures = {}
    for name in FIGURE_STUDIES:
        if name not in available:
            continue
        start = time.perf_counter()
        try:
            available[name].run(Path(out_dir), quick=quick)
        except Exception as error:  # keep going: what the other studies compute must not be lost
            failures[name] = f"{type(error).__name__}: {error}"
            print(f"figures: {name} FAILED ({failures[name]})")
            continue
        print(f"figures: {name} done in {time.perf_counter() - start:.1f} s")
    if failures:
        raise RuntimeError(f"{len(failures)} study(ies) failed: {failures}")
    return {}
