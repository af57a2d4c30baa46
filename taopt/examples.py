"""The example files shipped with taopt, found wherever taopt is installed.

One small file of each kind lives in ``taopt/data/examples/`` (``assignment_problem``,
``budgeted_problem``, ``capability_problem``, ``comm_problem``, ``delivery_instance``,
``sop_problem``, ``instance``, ``field``, ``solution``); ``demo`` (the embedded 10-target
instance) and ``delivery_example_20`` (20 customers) live in ``taopt/data/``. They are
package data (:mod:`importlib.resources`), so they are found from any folder after a plain
``pip install``, not only from a clone's root.

On the command line, ``example:NAME`` stands for :func:`path` of ``NAME`` wherever a file is
read (``taopt solve example:budgeted_problem``, ``verify``, ``simulate``, ``navigate
--field``).

Example
-------
>>> from taopt import examples
>>> examples.path("budgeted_problem").name
'budgeted_problem.json'
>>> "sop_problem" in examples.names()
True

This module imports only the standard library (``import taopt`` stays light).
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from taopt.errors import InstanceError

#: What marks an example on the command line: ``example:budgeted_problem``.
PREFIX = "example:"

#: Examples that live in ``taopt/data/`` itself (the others are in ``taopt/data/examples/``).
_TOP_LEVEL = ("demo", "delivery_example_20")


def _entries() -> dict[str, object]:
    data = resources.files("taopt").joinpath("data")
    found = {
        entry.name[: -len(".json")]: entry
        for entry in data.joinpath("examples").iterdir()
        if entry.name.endswith(".json")
    }
    for name in _TOP_LEVEL:
        found[name] = data.joinpath(f"{name}.json")
    return dict(sorted(found.items()))


def names() -> list[str]:
    """The names :func:`path` takes, sorted: ``['assignment_problem', ..., 'solution',
    'sop_problem']``."""
    return list(_entries())


def path(name: str) -> Path:
    """The file of the example ``name`` (with or without ``.json`` or ``example:``).

    Raises
    ------
    InstanceError
        No example of that name; the message lists them.
    """
    key = name.removeprefix(PREFIX).strip()
    key = key.removesuffix(".json")
    entries = _entries()
    if key not in entries:
        raise InstanceError(f"no example {key!r}; examples: {', '.join(entries)}")
    return Path(os.fspath(entries[key]))  # type: ignore[call-overload]


def resolve(text: str | os.PathLike[str]) -> str:
    """``example:NAME`` -> the example's path (as a string); any other text unchanged."""
    value = os.fspath(text)
    if isinstance(value, str) and value.startswith(PREFIX):
        return str(path(value))
    return str(value)


__all__ = ["PREFIX", "names", "path", "resolve"]
