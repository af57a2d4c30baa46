"""The layers' import rule read from the source: an exact model (``models/``) never imports
the heuristics package, not even inside a function (an incumbent and an improver are passed
in, or found through the registry)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parents[2] / "models"


def _heuristic_imports(path: Path) -> list[str]:
    """Every ``import``/``from`` of ``taopt.heuristics`` (or a module under it) in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        found += [
            f"{path.name}:{node.lineno} {name}"
            for name in names
            if name == "taopt.heuristics" or name.startswith("taopt.heuristics.")
        ]
    return found


@pytest.mark.parametrize("path", sorted(MODELS.rglob("*.py")), ids=lambda p: p.name)
def test_no_exact_model_imports_the_heuristics(path):
    """No module of ``models/`` imports ``taopt.heuristics``."""
    assert _heuristic_imports(path) == []
