"""Command line: ``python -m studies NAME [--out DIR] [--quick] [--debug] [study options]``; ``--help`` lists the
studies.

A bad input (a scene or sweep file, an option, an unwritable --out) or a load the gel cannot carry ends with a short
message on stderr naming the file, key, value and what is allowed, and exit code 2; a solve that does not converge
or a mesh that fails its quality check, exit code 1; no traceback unless ``--debug``. Warnings (small-strain
limits, locking) are printed as one line each.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

from studies._registry import find_studies

EXIT_BAD_INPUT = 2          # argparse's own code for a bad command line
EXIT_FAILED = 1


def _first_line(module) -> str:
    return (module.__doc__ or "").strip().splitlines()[0] if module.__doc__ else ""


def _out_folder(text: str) -> Path:
    """--out's value: a folder path, not empty (pathlib reads '' as the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is empty: give a folder")
    return Path(text)


def build_parser() -> argparse.ArgumentParser:
    """Parser with one sub-command per study module."""
    parser = argparse.ArgumentParser(
        prog="python -m studies",
        description="Fingertip contact studies: each writes NAME.png, NAME.pdf and NAME.csv into --out.",
    )
    commands = parser.add_subparsers(dest="study", metavar="STUDY", required=True)
    for name, module in find_studies().items():
        sub = commands.add_parser(name, help=_first_line(module), description=module.__doc__,
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
        sub.add_argument("--out", type=_out_folder, default=Path("results"), help="output folder (default: results/)")
        sub.add_argument("--quick", action="store_true", help="coarse settings for a fast look")
        sub.add_argument("--debug", action="store_true", help="show the Python traceback of an error")
        if hasattr(module, "add_arguments"):
            module.add_arguments(sub)
    return parser


def _exit_code(error: BaseException) -> int | None:
    """EXIT_BAD_INPUT for a bad input, EXIT_FAILED for a computation that failed, None for a bug (traceback)."""
    from contact import ContactNotConverged, PathNotCompleted
    from fem.tetmesh import MeshQualityError, MesherUnavailable

    if isinstance(error, (ValueError, OSError, ConnectionError, ImportError)):
        return EXIT_BAD_INPUT      # InputErrors, LoadNotCarried, ContactUnderResolved, files, --out, dask missing
    if isinstance(error, (PathNotCompleted, ContactNotConverged, MeshQualityError, MesherUnavailable, MemoryError)):
        return EXIT_FAILED
    return None


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Run one study; print where its outputs went, its largest error against theory and its wall time.

    Returns 0 on success, 2 for a bad input, 1 for a failed computation (the message on stderr)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    with warnings.catch_warnings():
        # from the start: importing the studies may warn (an unwritable cache); --de ... abbreviate --debug
        if not any(arg.startswith("--de") and "--debug".startswith(arg) for arg in argv):
            warnings.showwarning = _show_warning
        parser = build_parser()
        args = parser.parse_args(argv)
        module = find_studies()[args.study]
        options = {k: v for k, v in vars(args).items() if k not in ("study", "out", "quick", "debug")}
        start = time.perf_counter()
        try:
            from studies.run import check_out_folder

            check_out_folder(args.out)        # before any work: a file, a read-only place, a path under a file
            summary = module.run(args.out, quick=args.quick, **options) or {}
        except Exception as error:
            code = _exit_code(error)
            if args.debug or code is None:
                raise
            lines = str(error).splitlines() or [type(error).__name__]
            head = f"{args.study}: error" + (f" ({len(lines)} problems)" if len(lines) > 1 else "")
            print(f"{head}: {lines[0]}" if len(lines) == 1 else head + ":\n" + "\n".join(f"  {line}" for line in lines),
                  file=sys.stderr)
            print(f"{args.study}: (--debug shows the traceback)", file=sys.stderr)
            return code
    seconds = time.perf_counter() - start
    print(f"{args.study}: outputs in {Path(args.out).resolve()}")
    max_error = summary.get("max_error") if isinstance(summary, dict) else None
    if max_error is not None and math.isfinite(max_error):
        print(f"{args.study}: largest error {max_error:.4g} ({summary.get('error_meaning', 'against theory')})")
    print(f"{args.study}: wall time {seconds:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
