"""FEM samples of the reduced-calibration study on disk: every path's per-bump arrays, sensor CoPs and force targets.

A run writes them (``reduced_calibration_samples.npz``) as soon as the FEM paths are solved, so nothing computed is
lost if a later step fails, and ``python -m studies reduced-calibration --samples FILE`` refits from them without
solving again.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import fields
from pathlib import Path

import numpy as np

from contact.reduced._fit_plan import force_targets   # one definition: the design fit's


def save_samples(path: Path, fem: dict, scenes: dict) -> Path:
    """Every FEM path's PathSamples arrays, sensor CoPs and force targets, and the mesh facts, in one .npz.

    Keys "<case>/<field>"; "<case>/provenance" and "mesh" hold JSON text. ``load_samples`` reads it back.
    """
    from fem.atomic import atomic_path

    arrays = {"mesh": np.array(json.dumps(fem["mesh"]))}
    for name, data in fem["paths"].items():
        for field in fields(data):
            value = getattr(data, field.name)
            if isinstance(value, np.ndarray):
                arrays[f"{name}/{field.name}"] = value
        arrays[f"{name}/friction"] = np.array(data.friction)
        arrays[f"{name}/provenance"] = np.array(json.dumps(data.provenance))
        arrays[f"{name}/sensor_cop"] = fem["sensor_cop"][name]
        arrays[f"{name}/force_targets"] = force_targets(scenes[name])
    with atomic_path(path) as temporary, open(temporary, "wb") as stream:      # a stream: np.savez adds no suffix
        np.savez_compressed(stream, **arrays)
    return path


def load_samples(path, scenes: dict) -> dict:
    """The FEM paths of ``save_samples`` for these scenes (ValueError naming a missing case or other loads)."""
    from contact.reduced import PathSamples

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"samples={str(path)!r} is not a file (a reduced_calibration_samples.npz of an earlier run)")
    not_samples = f"samples={str(path)!r} is not a reduced_calibration_samples.npz of an earlier run"
    try:
        stored = np.load(path, allow_pickle=False)
    except (OSError, EOFError, ValueError, zipfile.BadZipFile) as error:    # empty, truncated, text, pickled
        raise ValueError(f"{not_samples}: numpy cannot read it as an .npz archive ({type(error).__name__})") from None
    if not isinstance(stored, np.lib.npyio.NpzFile):
        raise ValueError(f"{not_samples}: it holds a single array, not an archive")
    with stored:
        names = {key.split("/")[0] for key in stored.files if "/" in key}
        missing = sorted(set(scenes) - names)
        if missing or "mesh" not in stored.files:
            raise ValueError(f"{path}: no FEM samples for cases {missing or ['mesh']}; it was written by another "
                             f"plan (--quick or not) or version")
        array_fields = [f.name for f in fields(PathSamples) if f.name not in ("case", "friction", "provenance")]
        absent = [f"{name}/{field}" for name in scenes
                  for field in ["force_targets", "friction", "provenance", "sensor_cop", *array_fields]
                  if f"{name}/{field}" not in stored.files]
        if absent:
            raise ValueError(f"{not_samples}: it lacks {absent[:3]}{' ...' if len(absent) > 3 else ''}")
        paths, sensor_cop = {}, {}
        try:                                        # a damaged member (truncated, pickled, of another shape) fails here
            members = {key: stored[key] for key in stored.files}
            mesh = json.loads(str(members["mesh"]))
            for name in scenes:
                paths[name] = PathSamples(case=name, friction=float(members[f"{name}/friction"]),
                                          provenance=json.loads(str(members[f"{name}/provenance"])),
                                          **{field: members[f"{name}/{field}"] for field in array_fields})
                sensor_cop[name] = members[f"{name}/sensor_cop"]
        except (OSError, EOFError, TypeError, ValueError, zipfile.BadZipFile) as error:
            raise ValueError(f"{not_samples}: {type(error).__name__} reading it ({error})") from None
    for name in scenes:
        stored_targets, targets = members[f"{name}/force_targets"], np.asarray(force_targets(scenes[name]))
        if stored_targets.shape != targets.shape or not np.allclose(stored_targets, targets):
            raise ValueError(f"{path}: case {name!r} was run with other loads than this plan's")
    return {"paths": paths, "sensor_cop": sensor_cop, "mesh": mesh}
