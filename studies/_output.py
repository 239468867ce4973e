"""Atomic writers for study outputs (CSV, JSON) and figure saving (PNG and PDF)."""

from __future__ import annotations

import csv
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Iterable, Mapping


def _atomic_write_text(path: Path, text: str) -> Path:
    """Write text to ``path`` through a temporary file and a rename, so a crash never leaves half a file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, tmp_name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", newline="") as stream:
            stream.write(text)
        os.chmod(tmp_name, 0o644)                  # mkstemp makes 0600; results are meant to be shared
        os.replace(tmp_name, path)
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
    return path


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
    return _atomic_write_text(path, buffer.getvalue())


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
    return _atomic_write_text(path, text + "\n")


def save_figure(fig, out_dir: Path, name: str) -> list[Path]:
    """Save a matplotlib figure as ``out_dir/name.png`` (150 dpi) and ``.pdf``; close it; return the paths."""
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        target = out_dir / f"{name}.{ext}"
        tmp = out_dir / f".{name}.tmp.{ext}"
        fig.savefig(tmp, dpi=150, bbox_inches="tight")
        os.replace(tmp, target)
        paths.append(target)
    plt.close(fig)
    return paths


def largest_abs(values: Iterable[float]) -> float:
    """Largest absolute value of the finite entries (NaN if there are none)."""
    finite = [abs(float(v)) for v in values if v is not None and math.isfinite(float(v))]
    return max(finite) if finite else math.nan
