"""Every figure and table study, in parallel, skipping what is up to date; writes index.html and REPORT.md.

``python -m studies all --out results [--quick] [--jobs N] [--only fig2b,fig3b] [--force]`` runs the studies of
``studies._report.CLAIMS`` that exist (and any other ``figN...`` / ``tableN...`` module), each on its default (or quick)
settings in its own worker process. A study is up to date, and is not run again, when ``.stamps/NAME.json`` in the
output folder records the same hash of its sources (the study module and every module of fem/, contact/,
controller/ and ``studies._*`` it imports, directly or not, and the scene files) and the same settings, and its
outputs still exist.
Each study's returned summary goes to ``NAME.summary.json`` (also for a failure: its message and traceback), its
printed output to ``logs/NAME.log``. A failing study is reported as failed; the others still run and are reported.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import hashlib
import importlib
import importlib.util
import json
import math
import os
import pkgutil
import re
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from datetime import datetime, timezone
from pathlib import Path

NAME = "all"
SOURCE_PACKAGES = ("fem", "contact", "controller")
OUTPUT_EXTENSIONS = ("png", "pdf", "csv")
STAMP_DIR, LOG_DIR = ".stamps", "logs"
# default wall times [s] measured on the shared 2-core machine (quick: about a tenth), to start the longest first
EXPECTED_SECONDS = {"convergence": 140, "fig6": 190, "fig3": 250, "fig4": 85, "fig9": 60, "fig10": 15, "fig11": 25,
                    "table1": 35, "robustness": 310}


def _study_names(text: str) -> list[str]:
    """--only's value: study names separated by commas, at least one."""
    names = [name for name in text.split(",") if name]
    if not names:
        raise argparse.ArgumentTypeError(f"{text!r} names no study")
    return names


def add_arguments(parser) -> None:
    """Options of ``python -m studies all``."""
    parser.add_argument("--jobs", type=int, default=2,
                        help="worker processes (default 2; 1 runs the studies in this process, one after another)")
    parser.add_argument("--only", type=_study_names, default=None, metavar="NAME,NAME",
                        help="run and report only these studies")
    parser.add_argument("--force", action="store_true", help="recompute even the studies that are up to date")


def run(out_dir, quick: bool = False, jobs: int = 2, only=None, force: bool = False) -> dict:
    """Run the selected studies (those not up to date), then write ``index.html`` and ``REPORT.md``.

    Parameters
    ----------
    out_dir : path -- folder of every study's outputs, the stamps, the logs and the report
    quick : bool -- coarse settings (each study's ``quick=True``)
    jobs : int -- worker processes; 1 runs in this process
    only : list of str or None -- study names to run and report (None: all of them)
    force : bool -- ignore the stamps

    Returns
    -------
    dict -- ``wall_time`` [s], ``computed``, ``reused``, ``failed``, ``not_available`` (lists of names), ``report``.
    Raises RuntimeError after writing the report when a study failed.
    """
    from studies._report import write_report

    if jobs < 1:
        raise ValueError(f"jobs={jobs!r} outside allowed range [1, inf)")
    out_dir = Path(out_dir)
    start = time.perf_counter()
    modules, import_errors = discover()
    names = selected_names(modules, import_errors, only)
    out_dir.mkdir(parents=True, exist_ok=True)
    records, todo = {}, []
    for name in names:
        if name in import_errors:
            records[name] = dict(name=name, status="failed", error=import_errors[name], wall_time=None)
        elif name not in modules:
            records[name] = dict(name=name, status="not available", wall_time=None)
        elif not force and is_up_to_date(out_dir, name, modules[name], quick):
            records[name] = {**read_summary(out_dir, name), "status": "reused"}
            print(f"{NAME}: {name} is up to date (sources and settings unchanged), reused")
        else:
            todo.append(name)
    todo.sort(key=lambda name: -_expected_seconds(out_dir, name, quick))
    tasks = [(name, modules[name].__name__, str(out_dir), quick, source_hash(modules[name], quick)) for name in todo]
    records.update(_run_parallel(tasks, jobs) if jobs > 1 and len(tasks) > 1 else _run_here(tasks))
    wall = time.perf_counter() - start
    run_info = dict(quick=quick, jobs=jobs, wall_time=wall, finished=_now(), only=only, force=force)
    report = write_report(out_dir, [records[name] for name in names], run_info)
    by_status = {status: [n for n in names if records[n]["status"] == status]
                 for status in ("ok", "reused", "failed", "not available")}
    print(f"{NAME}: {len(by_status['ok'])} computed, {len(by_status['reused'])} reused, {len(by_status['failed'])} "
          f"failed, {len(by_status['not available'])} not available; report {report['html']}; wall time {wall:.1f} s")
    if by_status["failed"]:
        raise RuntimeError(f"{len(by_status['failed'])} study(ies) failed (see {report['html']}): "
                           + "; ".join(f"{n}: {records[n]['error']}" for n in by_status["failed"]))
    return dict(wall_time=wall, computed=by_status["ok"], reused=by_status["reused"], failed=by_status["failed"],
                not_available=by_status["not available"], report=str(report["html"]))


def discover() -> tuple[dict, dict]:
    """Study modules by NAME, like ``studies._registry.find_studies``, but a module that fails to import is kept as
    an error message (keyed by its expected name, module name with '-' for '_') instead of stopping everything."""
    import studies

    modules, errors = {}, {}
    for info in pkgutil.iter_modules(studies.__path__):
        if info.name.startswith("_") or info.name == "__main__":
            continue
        try:
            module = importlib.import_module(f"studies.{info.name}")
        except Exception as error:  # a study being written by someone else must not stop the others
            errors[info.name.replace("_", "-")] = f"import failed: {type(error).__name__}: {error}"
            continue
        if hasattr(module, "NAME") and callable(getattr(module, "run", None)):
            modules[module.NAME] = module
    return modules, errors


def selected_names(modules: dict, import_errors: dict, only=None) -> list[str]:
    """The claim table's studies in its order, then any other ``figN`` / ``tableN`` study; ``only``
    restricts (and orders) the selection and must name known or tabled studies."""
    from studies._report import CLAIMS

    extra = sorted(n for n in {*modules, *import_errors} if re.fullmatch(r"(fig|table)\d+\w*", n) and n not in CLAIMS)
    names = [*CLAIMS, *extra]
    if only is None:
        return names
    if not only:
        raise ValueError(f"--only={only!r} names no study; allowed: {names}")
    unknown = [n for n in only if n not in names]
    if unknown:
        raise ValueError(f"--only: unknown study name(s) {unknown}; allowed: {names}")
    return list(dict.fromkeys(only))


def source_files(module) -> list[Path]:
    """What a study's results depend on: its module and every module of ``studies._*`` and SOURCE_PACKAGES that it
    imports, directly or through others (static imports, also inside functions; with the packages' ``__init__``),
    the scene files and the JSON data next to those modules. A change elsewhere (another study, a module it never
    imports) keeps it up to date."""
    files, seen = set(), set()
    pending = [module.__name__]
    while pending:
        name = pending.pop()
        if name in seen:
            continue
        seen.add(name)
        spec = _spec(name)
        if spec is None or not spec.origin or not spec.origin.endswith(".py"):
            continue
        files.add(Path(spec.origin))
        package = name if spec.submodule_search_locations else name.rpartition(".")[0]
        pending += [".".join(name.split(".")[:depth]) for depth in range(1, name.count(".") + 1)]   # parents
        for node in ast.walk(ast.parse(Path(spec.origin).read_text())):
            if isinstance(node, ast.Import):
                pending += [alias.name for alias in node.names if _tracked(alias.name)]
            elif isinstance(node, ast.ImportFrom):
                base = importlib.util.resolve_name("." * node.level + (node.module or ""), package) \
                    if node.level else node.module or ""
                if _tracked(base):             # the module, and each imported name that is itself a module
                    pending += [base] + [f"{base}.{alias.name}" for alias in node.names]
    files.update((Path(module.__file__).parent / "scenes").glob("*.toml"))
    for path in list(files):                   # package data a tracked module reads (the calibrated fingertip)
        files.update((path.parent / "data").glob("*.json"))
    return sorted(files)


def _tracked(name: str) -> bool:
    return name.split(".")[0] in SOURCE_PACKAGES or name.startswith("studies._")


def _spec(name: str):
    try:
        return importlib.util.find_spec(name)
    except (ImportError, ValueError):          # a name imported from a module, not a module
        return None


def source_hash(module, quick: bool) -> str:
    """SHA-256 of the study's source files (path relative to the repository, and content) and of its settings."""
    digest = hashlib.sha256(json.dumps({"quick": bool(quick)}).encode())
    files = source_files(module)
    root = Path(os.path.commonpath([str(f) for f in files]))
    for path in files:
        digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def stamp_path(out_dir: Path, name: str) -> Path:
    return Path(out_dir) / STAMP_DIR / f"{name}.json"


def is_up_to_date(out_dir: Path, name: str, module, quick: bool) -> bool:
    """True when the stamp records this source hash and settings, the run succeeded and its outputs exist."""
    try:
        stamp = json.loads(stamp_path(out_dir, name).read_text())
    except (OSError, ValueError):
        return False
    if not isinstance(stamp, dict) or not isinstance(stamp.get("outputs", ()), (list, tuple)):
        return False                                  # a stamp of another shape: run the study again
    return (stamp.get("hash") == source_hash(module, quick)
            and all((Path(out_dir) / output).is_file() for output in stamp.get("outputs", ()))
            and read_summary(out_dir, name).get("status") == "ok")


def read_summary(out_dir: Path, name: str) -> dict:
    """The record ``NAME.summary.json`` (empty dict if missing or unreadable)."""
    try:
        summary = json.loads((Path(out_dir) / f"{name}.summary.json").read_text())
    except (OSError, ValueError):
        return {}
    return summary if isinstance(summary, dict) else {}


def run_study(name: str, module_name: str, out_dir: str, quick: bool, digest: str) -> dict:
    """Run one study (in a worker or here), print into ``logs/NAME.log``; write its summary and, on success, its
    stamp. Never raises: a failure becomes the record's ``error`` and ``traceback``."""
    from studies._output import write_json_atomic

    out_dir = Path(out_dir)
    log = out_dir / LOG_DIR / f"{name}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    record = dict(name=name, quick=quick, started=_now(), log=str(log.relative_to(out_dir)))
    start = time.perf_counter()
    with open(log, "w") as stream, contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
        try:
            summary = importlib.import_module(module_name).run(out_dir, quick=quick)
            record.update(status="ok", summary=_jsonable(summary if isinstance(summary, dict) else {}))
        except Exception as error:  # reported as failed; the other studies go on
            record.update(status="failed", error=f"{type(error).__name__}: {error}", traceback=traceback.format_exc())
            print(record["traceback"])
    record.update(wall_time=time.perf_counter() - start, finished=_now())
    write_json_atomic(out_dir / f"{name}.summary.json", record)
    if record["status"] == "ok":
        outputs = [f"{name}.summary.json"] + [f"{name}.{ext}" for ext in OUTPUT_EXTENSIONS
                                              if (out_dir / f"{name}.{ext}").is_file()]
        write_json_atomic(stamp_path(out_dir, name), dict(name=name, hash=digest, quick=quick, outputs=outputs,
                                                          finished=record["finished"]))
    else:
        stamp_path(out_dir, name).unlink(missing_ok=True)
    return record


def _progress(tasks):
    """A bar over the studies on stderr, weighted by their expected seconds (the longest start first)."""
    from tqdm import tqdm

    return tqdm(total=len(tasks), desc=NAME, unit="study", leave=True,
                bar_format="{desc}: {n}/{total} studies |{bar}| {elapsed} elapsed{postfix}")


def _run_here(tasks) -> dict:
    records = {}
    with _progress(tasks) as bar:
        for task in tasks:
            bar.set_postfix_str(f"running {task[0]}")
            print(f"{NAME}: {task[0]} started")
            records[task[0]] = _announce(run_study(*task))
            bar.update()
    return records


def _run_parallel(tasks, jobs: int) -> dict:
    """Each task in a fresh 'spawn' worker process (no forked solver threads), BLAS threads shared out by jobs."""
    import multiprocessing

    from controller.closed_loop._batch import MAX_PROCESSES, available_cpus

    threads = max(1, available_cpus() // jobs)
    records = {}
    pool = ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=multiprocessing.get_context("spawn"),
                               initializer=_limit_threads, initargs=(threads, min(threads, MAX_PROCESSES)))
    with pool, _progress(tasks) as bar:
        futures = {pool.submit(run_study, *task): task[0] for task in tasks}
        print(f"{NAME}: running {', '.join(futures.values())} on {min(jobs, len(tasks))} workers")
        for future in as_completed(futures):
            name = futures[future]
            try:
                records[name] = _announce(future.result())
            except BrokenProcessPool as error:   # a worker died (killed, out of memory): its record was not written
                records[name] = dict(name=name, status="failed", wall_time=None,
                                     error=f"worker process ended abruptly ({error}); run again to retry")
            bar.set_postfix_str(f"{name} done")
            bar.update()
    return records


def _limit_threads(threads: int, processes: int) -> None:
    """Share the CPUs out: BLAS threads, and the closed-loop studies' trial workers (``default_processes``)."""
    for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(variable, str(threads))
    os.environ.setdefault("FINGERTIP_PROCESSES", str(processes))


def _announce(record: dict) -> dict:
    outcome = "done" if record["status"] == "ok" else f"FAILED ({record['error']})"
    seconds = f" in {record['wall_time']:.1f} s" if record.get("wall_time") is not None else ""
    print(f"{NAME}: {record['name']} {outcome}{seconds}")
    return record


def _expected_seconds(out_dir: Path, name: str, quick: bool) -> float:
    previous = read_summary(out_dir, name)
    if previous.get("wall_time") and previous.get("quick") == quick:
        return float(previous["wall_time"])
    return EXPECTED_SECONDS.get(name, 30.0) * (0.25 if quick else 1.0)


def _jsonable(value):
    """Summary made JSON-safe: numpy scalars and arrays as Python numbers and lists, NaN and inf as None."""
    if isinstance(value, dict):
        return {str(key): _jsonable(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(item) for item in value]
    if hasattr(value, "tolist"):                       # numpy array or scalar
        return _jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
