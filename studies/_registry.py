"""Discover study modules: every public module of ``studies`` that defines ``NAME`` and ``run``."""

from __future__ import annotations

import importlib
import pkgutil
import warnings
from types import ModuleType


def find_studies() -> dict[str, ModuleType]:
    """Map each study's command-line name to its module, sorted by name."""
    import studies

    found: dict[str, ModuleType] = {}
    for info in pkgutil.iter_modules(studies.__path__):
        if info.name.startswith("_"):
            continue
        try:
            module = importlib.import_module(f"studies.{info.name}")
        except Exception as error:  # one broken study must not take the whole command line down
            warnings.warn(f"study module studies.{info.name} does not import ({type(error).__name__}: {error}); "
                          f"skipped", stacklevel=2)
            continue
        if hasattr(module, "NAME") and callable(getattr(module, "run", None)):
            found[module.NAME] = module
    return dict(sorted(found.items()))
