"""Progress of a long call that reports none itself (a mesher): a tqdm bar that ticks from a background thread."""

from __future__ import annotations

import threading
from contextlib import contextmanager

__all__ = ["ticking"]


@contextmanager
def ticking(description: str, enabled: bool = True, expected_seconds: float | None = None, interval: float = 0.5):
    """A tqdm bar for the body of the ``with`` block: elapsed seconds against ``expected_seconds`` (an estimate;
    None: elapsed time only), refreshed every ``interval`` seconds; closed (at 100 %) when the block ends."""
    if not enabled:
        yield
        return
    import time

    from tqdm import tqdm

    total = float(expected_seconds) if expected_seconds else None
    bar = tqdm(total=total, desc=description, unit="s", bar_format="{desc}: {n:.0f}/{total:.0f} s (estimate) "
               "{bar}" if total else "{desc}: {elapsed}")
    stop = threading.Event()
    start = time.perf_counter()

    def tick():
        while not stop.wait(interval):
            elapsed = time.perf_counter() - start
            bar.n = min(elapsed, total) if total else elapsed
            bar.refresh()

    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        bar.n = total if total else time.perf_counter() - start
        bar.close()
