"""numba kernels cached on disk in a folder keyed by the source of every kernel module of the toolkit.

numba's own cache checks only the time stamp of the file that defines a kernel, so a kernel that calls or inlines a
kernel of another file kept its stale machine code after that file was edited (seen: the fused closed loop ran the
old slip-centre search until the cache was cleared). Keying the folder by the hash of all kernel sources makes any
edit recompile every kernel once; nothing else changes.
"""

from __future__ import annotations

import hashlib
from functools import cache
from pathlib import Path

from fem.mesh_cache import default_cache_dir

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


def njit_cached(function=None, **options):
    """``numba.njit(cache=True, **options)``, its cache in ``kernel_cache_dir()`` (numba's default place when that
    folder cannot be written); usable bare (``@njit_cached``) or with options (``@njit_cached(inline="always")``)."""
    from numba import config, njit

    def decorate(kernel):
        previous = config.CACHE_DIR
        config.CACHE_DIR = str(kernel_cache_dir())     # read once, when the dispatcher sets up its cache
        try:
            return njit(cache=True, **options)(kernel)
        finally:
            config.CACHE_DIR = previous

    return decorate(function) if function is not None else decorate
