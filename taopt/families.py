"""Finding the problem families: every ``taopt/<package>/family.py`` declares one or more.

Each family declares its spec (:class:`taopt.registry.Family`) in the module ``family`` of its
own core package and registers it there (:func:`taopt.registry.register_family`). Looking up
a family by file kind (:func:`taopt.registry.family_for_kind`) or a payload by name
(:func:`taopt.result.payload_type`) first imports every such module with
:func:`ensure_families`. The modules are found on disk, so adding a family changes no
existing file. This module depends on no other part of taopt, so both the registry and the
result types can use it without importing each other.
"""

from __future__ import annotations

import functools
import importlib
from pathlib import Path

_ROOT = Path(__file__).resolve().parent


@functools.cache
def family_modules() -> tuple[str, ...]:
    """The modules that declare a family: ``taopt.<package>.family`` for each subpackage of
    taopt holding a ``family.py``, sorted by package name.

    Example
    -------
    >>> "taopt.routing.family" in family_modules()
    True
    """
    return tuple(
        f"taopt.{folder.name}.family"
        for folder in sorted(_ROOT.iterdir())
        if (folder / "__init__.py").is_file() and (folder / "family.py").is_file()
    )


def ensure_families() -> None:
    """Import every module of :func:`family_modules` (each registers its family).

    A family that fails to import fails loudly: its ImportError is raised as it is, never
    skipped (a family silently missing would make its file kind "unknown").
    """
    for module in family_modules():
        importlib.import_module(module)


__all__ = ["family_modules", "ensure_families"]
