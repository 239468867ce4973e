"""A small TOML writer for the tests' scene, sweep and design documents, and edits of such documents."""

from __future__ import annotations

import copy
import math
from pathlib import Path

DELETE = object()       # an edit that removes the key


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f'"{k}" = {_toml_value(v)}' for k, v in value.items()) + "}"
    raise TypeError(value)


def to_toml(document: dict, prefix: str = "") -> str:
    """A small TOML writer for the catalogue's documents (scalars, lists, tables, arrays of tables)."""
    lines, tables = [], []
    for key, value in document.items():
        quoted = f'"{key}"' if "." in key else key
        if isinstance(value, dict):
            tables.append((quoted, value))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            tables.extend((quoted, item, True) for item in value)
        else:
            lines.append(f"{quoted} = {_toml_value(value)}")
    text = "\n".join(lines) + "\n"
    for entry in tables:
        name = f"{prefix}{entry[0]}"
        header = f"[[{name}]]" if len(entry) == 3 else f"[{name}]"
        text += f"{header}\n" + to_toml(entry[1], prefix=f"{name}.")
    return text


def edited(base: dict, edits) -> dict:
    """``base`` with each (path, value) set (DELETE removes); a path is a tuple of keys and list indices."""
    document = copy.deepcopy(base)
    for path, value in edits:
        node = document
        for key in path[:-1]:
            node = node[key]
        if value is DELETE:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return document


def write_toml(path: Path, document: dict) -> Path:
    """Write ``document`` as TOML to ``path``; return the path."""
    path.write_text(to_toml(document))
    return path
