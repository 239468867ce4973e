"""Record the reference outcomes of tests/test_closed_loop_kernel.py with the explicit closed loop this package
replaced: MuJoCo at 8 kHz with the fingers as MuJoCo joints, the reduced contact updated explicitly at 4 kHz and the
Acceleration Control stepped from Python (``studies/_grasp_world.py`` as of commit a63e2f9, read from git), on the
current reduced fingertip and displacement-target controller. Run from the repository root:

    python tests/data/record_closed_loop_reference.py

It takes a few minutes; it writes tests/data/closed_loop_reference.json.
"""

import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

EXPLICIT_LOOP = "a63e2f9:studies/_grasp_world.py"
REPOSITORY = Path(__file__).resolve().parents[2]


def explicit_loop():
    source = subprocess.run(["git", "show", EXPLICIT_LOOP], check=True, capture_output=True, text=True,
                            cwd=REPOSITORY).stdout
    path = Path(tempfile.mkdtemp()) / "explicit_grasp_world.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("explicit_grasp_world", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def main() -> None:
    old = explicit_loop()
    rng = np.random.default_rng(2026)
    cases = []
    for name in old.TABLE_I_OBJECTS:
        for k in range(3):
            cases.append((f"{name}_{k}", name, old.random_settings(rng, hold_time=1.5, place=False)))
    tuned = old.TargetDesign(0.4, 0.8, 0.8)
    for rotation in (True, False):
        cases.append((f"eclair_mu0.4_rotation_{rotation}", "eclair", old.TrialSettings(
            friction=0.4, rotational_slip_detection=rotation, hold_time=1.5, place=False, seed=3, targets=tuned)))
    cases.append(("bottle_horizontal_full", "bottle_horizontal", old.TrialSettings(friction=0.6, seed=3)))
    records = []
    for case, name, settings in cases:
        start = time.process_time()
        result = old.run_trial(old.TABLE_I_OBJECTS[name], settings)
        records.append(dict(case=case, object=name, settings=asdict(settings), success=result.success,
                            dropped=result.dropped, crushed=result.crushed, rotated=result.rotated,
                            hold_force_mean=result.hold_force_mean, max_force=result.max_force,
                            max_rotation_mrad=result.max_rotation_mrad, hold_rotation_mrad=result.hold_rotation_mrad,
                            cpu_seconds=round(time.process_time() - start, 2),
                            simulated_seconds=result.simulated_time))
        print(case, result.success, round(result.hold_force_mean, 3), round(result.max_rotation_mrad, 1), flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=REPOSITORY).stdout.strip()
    out = dict(explicit_loop=EXPLICIT_LOOP, package_commit=commit,
               note="Outcomes of the explicit closed loop (MuJoCo 8 kHz, reduced contact 4 kHz explicit, Acceleration "
                    "Control 8 kHz in Python) with the displacement-target controller on the packaged fingertip; "
                    "Table I's randomisation (seed 2026), hold shortened to 1.5 s.", records=records)
    Path(__file__).with_name("closed_loop_reference.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
