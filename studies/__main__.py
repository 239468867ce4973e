"""Command line: ``python -m studies NAME [--out DIR] [--quick] [study options]``; ``--help`` lists the studies."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from studies._registry import find_studies


def _first_line(module) -> str:
    return (module.__doc__ or "").strip().splitlines()[0] if module.__doc__ else ""


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
        sub.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results/)")
        sub.add_argument("--quick", action="store_true", help="coarse settings for a fast look")
        if hasattr(module, "add_arguments"):
            module.add_arguments(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one study; print where its outputs went, its largest error against theory and its wall time."""
    parser = build_parser()
    args = parser.parse_args(argv)
    module = find_studies()[args.study]
    options = {k: v for k, v in vars(args).items() if k not in ("study", "out", "quick")}
    start = time.perf_counter()
    summary = module.run(args.out, quick=args.quick, **options) or {}
    seconds = time.perf_counter() - start
    print(f"{args.study}: outputs in {Path(args.out).resolve()}")
    max_error = summary.get("max_error") if isinstance(summary, dict) else None
    if max_error is not None and math.isfinite(max_error):
        print(f"{args.study}: largest error {max_error:.4g} ({summary.get('error_meaning', 'against theory')})")
    print(f"{args.study}: wall time {seconds:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
