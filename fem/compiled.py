"""numba kernels cached on disk in a folder keyed by the source of every kernel module of the toolkit.

numba's own cache checks only the time stamp of the file that defines a kernel, so a kernel that calls or inlines a
kernel of another file kept its stale machine code after that file was edited (seen: the fused closed loop ran the
old slip-centre search until the cache was cleared). Keying the folder by the hash of all kernel sources makes any
edit recompile every kernel once; nothing else changes.

numba unpickles its index and data files without a guard, so one damaged file (a truncated write, a bit flip) made
every later run fail with an ``UnpicklingError`` from inside numba. The cache here reports such a kernel's files once
with their path, deletes them and compiles the kernel again (``fem.cache_dir``). A cache folder that cannot be
written gives one warning naming FINGERTIP_CACHE, and the kernels are compiled without a disk cache.
"""

from __future__ import annotations

import hashlib
from functools import cache
from pathlib import Path

from fem.cache_dir import CacheWarning, default_cache_dir, discard_damaged, writable_folder

__all__ = ["kernel_cache_dir", "njit_cached"]

KERNEL_PACKAGES = ("fem", "contact", "controller")


@cache
def kernel_cache_dir() -> Path:
    """``<FINGERTIP_CACHE>/numba/<hash of the sources of every module that compiles kernels>``."""
    root = Path(__file__).resolve().parent.parent
    digest = hashlib.sha256()
    for package in KERNEL_PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            text = path.read_bytes()
            if b"numba" in text or b"njit_cached" in text:
                digest.update(path.relative_to(root).as_posix().encode() + b"\0" + text)
    return default_cache_dir() / "numba" / digest.hexdigest()[:16]


@cache
def _healing_cache_class():
    """numba's FunctionCache, but a kernel whose cached files do not load is compiled again instead of failing."""
    from numba.core.caching import FunctionCache

    class HealingFunctionCache(FunctionCache):
        def load_overload(self, sig, target_context):
            try:
                return super().load_overload(sig, target_context)
            except Exception as error:            # pickle.UnpicklingError, EOFError, ValueError, ... of a damaged file
                folder = Path(self._cache_path)
                data_files = sorted(folder.glob(f"{self._impl.filename_base}.*.nbc"))
                discard_damaged(folder / f"{self._impl.filename_base}.nbi",
                                f"{type(error).__name__}: {error}; with its {len(data_files)} data file(s)")
                for path in data_files:
                    path.unlink(missing_ok=True)
                return None                           # numba compiles the kernel and saves it again

        def save_overload(self, sig, data):
            try:
                super().save_overload(sig, data)
            except OSError as error:                  # the folder went away or filled up since it was probed
                import warnings

                warnings.warn(f"compiled kernel not cached in {self._cache_path!r} ({error.strerror or error})",
                              CacheWarning, stacklevel=2)

    return HealingFunctionCache


def njit_cached(function=None, **options):
    """``numba.njit(cache=True, **options)``, its cache in ``kernel_cache_dir()`` and healing damaged files; without
    a disk cache (one warning) when that folder cannot be written. Usable bare (``@njit_cached``) or with options
    (``@njit_cached(inline="always")``)."""
    from numba import config, njit

    def decorate(kernel):
        folder = kernel_cache_dir()
        if not writable_folder(folder):
            return njit(cache=False, **options)(kernel)
        previous = config.CACHE_DIR
        config.CACHE_DIR = str(folder)                # read once, when the dispatcher sets up its cache
        try:
            dispatcher = njit(cache=True, **options)(kernel)
            dispatcher._cache = _healing_cache_class()(dispatcher.py_func)    # numba has no public hook for this
            return dispatcher
        finally:
            config.CACHE_DIR = previous

    return decorate(function) if function is not None else decorate
