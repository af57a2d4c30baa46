"""Which core packages register a problem family, and importing them on demand.

Each family registers itself (:func:`taopt.registry.register_family`) when its core package
is imported. Looking up a family by file kind (:func:`taopt.registry.family_for_kind`) or a
payload by name (:func:`taopt.result.payload_type`) first imports them all with
:func:`ensure_families`. This module depends on no other part of taopt, so both the registry
and the result types can use it without importing each other.

Adding a family touches its own modules and one line of :data:`FAMILY_PACKAGES`.
"""

from __future__ import annotations

import importlib

#: Core packages whose import registers a family (imported on demand by kind look-ups).
FAMILY_PACKAGES = (
    "taopt.routing",
    "taopt.delivery",
    "taopt.capability",
    "taopt.comm",
)


def ensure_families() -> None:
    """Import every package of :data:`FAMILY_PACKAGES` (each registers its family).

    A family that fails to import fails loudly: its ImportError is raised as it is, never
    skipped (a family silently missing would make its file kind "unknown").
    """
    for package in FAMILY_PACKAGES:
        importlib.import_module(package)


__all__ = ["FAMILY_PACKAGES", "ensure_families"]
