"""Atomic writers for study outputs (CSV, JSON) and figure saving (PNG and PDF)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Iterable, Mapping

from fem.atomic import atomic_path, write_text_atomic


def write_csv_atomic(path: Path, rows: Iterable[Mapping[str, object]]) -> Path:
    """Write a list of dicts as a tidy CSV (header from the union of keys, in first-seen order)."""
    rows = list(rows)
    columns: list[str] = []
    for row in rows:
        columns.extend(key for key in row if key not in columns)
    import io

    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return write_text_atomic(path, buffer.getvalue())


def _json_default(value):
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def write_json_atomic(path: Path, data: object) -> Path:
    """Write ``data`` as indented JSON (numpy arrays become lists; NaN is refused)."""
    text = json.dumps(data, indent=1, default=_json_default, allow_nan=False)
    return write_text_atomic(path, text + "\n")


def save_figure(fig, out_dir: Path, name: str) -> list[Path]:
    """Save a matplotlib figure as ``out_dir/name.png`` (150 dpi) and ``.pdf``; close it; return the paths."""
    import matplotlib.pyplot as plt

    paths = []
    for ext in ("png", "pdf"):
        with atomic_path(Path(out_dir) / f"{name}.{ext}") as temporary:
            fig.savefig(temporary, dpi=150, bbox_inches="tight", format=ext)
        paths.append(Path(out_dir) / f"{name}.{ext}")
    plt.close(fig)
    return paths


def largest_abs(values: Iterable[float]) -> float:
    """Largest absolute value of the finite entries (NaN if there are none)."""
    finite = [abs(float(v)) for v in values if v is not None and math.isfinite(float(v))]
    return max(finite) if finite else math.nan
