"""`taopt solve --out` writes certificates that `taopt verify` re-checks from the problem alone."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from taopt.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "taopt" / "data" / "examples"


@pytest.mark.parametrize(
    "kind", ["assignment_problem", "delivery_instance", "sop_problem", "comm_problem"]
)
def test_saved_solutions_verify(tmp_path, kind, capsys):
    """Every solution `taopt solve --out` writes passes `taopt verify --exact`."""
    problem = EXAMPLES / f"{kind}.json"
    assert main(["solve", str(problem), "--out", str(tmp_path), "--quiet"]) == 0
    saved = sorted(tmp_path.glob("*.json"))
    assert saved
    for path in saved:
        assert main(["verify", str(path), str(problem), "--exact"]) == 0, path.name
    assert "NOT VALID" not in capsys.readouterr().out


def test_tampered_solutions_fail(tmp_path, capsys):
    """A changed objective, a false 'optimal' claim or infeasible routes are each caught."""
    problem = EXAMPLES / "assignment_problem.json"
    good = json.loads((EXAMPLES / "solution.json").read_text())
    cases = {
        "objective": {**good, "objective": good["objective"] - 1},
        "claim": {**good, "status": "optimal", "bound": good["objective"] / 2},
        "routes": {**good, "payload": {"routes": [[0], [0, 1, 2]]}},
        "family": {**good, "payload_kind": "order", "payload": {"order": [0, 1, 2]}},
    }
    for name, data in cases.items():
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(data))
        assert main(["verify", str(path), str(problem)]) == 1, name
    out = capsys.readouterr().out
    assert "visited twice" in out and "payload is 'order'" in out
