"""Reading CalculiX's output files: the printed tables of ``job.dat`` and the nodal result blocks of ``job.frd``.

``.dat`` (``*NODE PRINT``, ``*CONTACT PRINT``): each table starts with a header line naming the quantity, the set
and the time, e.g. `` forces (fx,fy,fz) for set REF and time  0.1000000E+00``, followed by rows of numbers.
``.frd`` (``*NODE FILE``, ``*CONTACT FILE``): ASCII blocks; ``    2C`` the node coordinates, ``    1PSTEP`` then
`` -4  NAME`` a result block at the time given on the ``  100C`` line, each data line `` -1`` + a 10-character node
number + 12-character values (they may touch: ``0.00000E+00-1.00000E+01``), ``-3`` ending a block (CalculiX manual,
"Result Format"). meshio reads neither format, so both are parsed here.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["DatTable", "read_dat", "FrdStep", "read_frd"]

_DAT_HEADER = re.compile(r"^\s*(?P<what>.+?)\s+for\s+(?:set\s+(?P<set>\S+)|(?P<all>all\s+contact\s+elements)|"
                         r"slave set\s+(?P<slave>\S+),\s*master set\s+(?P<master>\S+))\s+and\s+time\s+"
                         r"(?P<time>\S+)\s*$", re.IGNORECASE)


@dataclass
class DatTable:
    """One printed table of a ``.dat`` file: what it holds, the set, the (total) time and its numeric rows."""

    what: str                     # e.g. "forces (fx,fy,fz)", "total force (fx,fy,fz)", "statistics"
    set_name: str                 # node set, or "SLAVE/MASTER" for contact statistics
    time: float
    rows: list = field(default_factory=list)      # list of float lists, one per printed line

    @property
    def array(self) -> np.ndarray:
        """The rows as a 2D float array (rows of unequal length are padded with NaN)."""
        width = max((len(row) for row in self.rows), default=0)
        return np.array([row + [np.nan] * (width - len(row)) for row in self.rows], dtype=float).reshape(-1, width)


def _numbers(line: str) -> list[float] | None:
    try:
        return [float(token) for token in line.split()]
    except ValueError:
        return None


def read_dat(path: str | Path) -> list[DatTable]:
    """Every table of a CalculiX ``.dat`` file, in file order."""
    tables: list[DatTable] = []
    for line in Path(path).read_text(errors="replace").splitlines():
        match = _DAT_HEADER.match(line)
        if match:
            name = match["set"] or (f"{match['slave']}/{match['master']}" if match["slave"] else "ALL")
            tables.append(DatTable(match["what"].strip().lower(), name.upper(), float(match["time"])))
            continue
        if tables and line.strip():
            values = _numbers(line)
            if values is not None:
                tables[-1].rows.append(values)
    return tables


@dataclass
class FrdStep:
    """The result blocks written at one time: ``blocks[name]`` maps node number -> values (n, k) with ``nodes``."""

    time: float
    step: int                                      # running number of the 100C record (one per written time)
    blocks: dict = field(default_factory=dict)     # name -> (nodes (n,), values (n, k), component names (k,))

    def field(self, name: str, nodes: np.ndarray, component: str | None = None) -> np.ndarray:
        """Values (len(nodes), k) of block ``name`` at the given node numbers (0 where a node has no entry), or
        the one ``component`` (len(nodes),) by its name (e.g. 'CPRESS')."""
        numbers, values, names = self.blocks[name]
        nodes = np.asarray(nodes, dtype=int)
        lookup = np.zeros((int(max(numbers.max(initial=0), nodes.max(initial=0))) + 1, values.shape[1]))
        lookup[numbers] = values
        picked = lookup[nodes]
        return picked if component is None else picked[:, names.index(component)]


def _values(line: str, count: int) -> list[float]:
    count = min(count, (len(line.rstrip()) - 13) // 12)        # a DISP block names an 'ALL' it does not write
    return [float(line[13 + 12 * i: 25 + 12 * i]) for i in range(count)]


def read_frd(path: str | Path) -> tuple[dict, list[FrdStep]]:
    """Node coordinates {node: (3,)} and the result steps of a CalculiX ``.frd`` file (ASCII)."""
    coordinates: dict[int, np.ndarray] = {}
    steps: list[FrdStep] = []
    lines = Path(path).read_text(errors="replace").splitlines()
    i, time, step = 0, 0.0, 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("    2C"):
            i += 1
            while not lines[i].startswith(" -3"):
                coordinates[int(lines[i][3:13])] = np.array(_values(lines[i], 3))
                i += 1
        elif line.startswith("  100C"):
            time = float(line.split()[2])                     # 100CL, set number, value (the time), ...
            step += 1
        elif line.startswith(" -4"):
            name, count = line[5:13].strip(), int(line[13:18])
            i += 1
            names = []
            while lines[i].startswith(" -5"):
                names.append(lines[i][5:13].strip())
                i += 1
            nodes, values = [], []
            while not lines[i].startswith(" -3"):
                if lines[i].startswith(" -1"):
                    nodes.append(int(lines[i][3:13]))
                    values.append(_values(lines[i], count))
                i += 1
            if not steps or steps[-1].time != time:
                steps.append(FrdStep(time, step))
            width = min(len(v) for v in values) if values else 0
            steps[-1].blocks[name] = (np.array(nodes, dtype=int),
                                      np.array([v[:width] for v in values], dtype=float).reshape(-1, width),
                                      names[:width])
        i += 1
    return coordinates, steps
