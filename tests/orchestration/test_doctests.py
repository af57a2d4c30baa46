"""The docstring examples of every module run and print what they show.

Modules are imported by their installed names (``taopt.models.*``, ``taopt.heuristics.*``), so
the examples run against the package a user has. Examples that need a scratch folder or minutes
of work are marked ``# doctest: +SKIP`` where they stand; the modules whose examples take more
than a few seconds are in :data:`SLOW` and run with ``pytest -m slow``.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

#: Worker scripts that must not be imported into a process using HiGHS (see heuristics/peers.py).
EXCLUDED = {"taopt.heuristics._peer_worker"}
#: Modules whose examples solve real instances (seconds each).
SLOW: set[str] = set()


def _modules() -> list[str]:
    import taopt.heuristics
    import taopt.models

    names = ["taopt", "taopt.models", "taopt.heuristics"]
    for package in (taopt, taopt.models, taopt.heuristics):
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            if info.name not in EXCLUDED:
                names.append(info.name)
    return sorted(set(names))


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in _modules()],
)
def test_docstring_examples(name):
    """Every example in the module's docstrings gives the output it shows."""
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"


def test_every_source_folder_is_collected():
    """Every folder of the installed package holding modules is a regular package whose modules
    are collected here (a folder without __init__.py, once taopt/studies, is silently skipped
    by pkgutil)."""
    from pathlib import Path

    import taopt
    import taopt.heuristics
    import taopt.models

    collected = set(_modules())
    for package in (taopt, taopt.models, taopt.heuristics):
        root = Path(package.__path__[0])
        for path in root.rglob("*.py"):
            if "__pycache__" in path.parts:
                continue
            parts = path.relative_to(root).with_suffix("").parts
            folder = path.parent
            assert (folder / "__init__.py").exists(), f"{folder} has modules but no __init__.py"
            name = ".".join([package.__name__, *parts]).removesuffix(".__init__")
            if name not in EXCLUDED:
                assert name in collected, f"{name} is not collected"
    assert "taopt.orchestration.studies.drift" in collected
