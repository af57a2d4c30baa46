"""The tree with the set path cuts separated in every node round (``sop_bc.NODE_SETS``): its
optimum equals brute force on random tiny SOPs, and every row it added (path, set and
alternation rows, sides kept) holds on every feasible order."""

from __future__ import annotations

import pytest

from taopt.models import sop_bc
from taopt.models.sop_cuts import SopCutModel
from taopt.result import OPTIMAL
from tests.reference_exact import assert_rows_hold, sop_brute_force
from tests.sop.test_sop_bc import _instance


@pytest.mark.parametrize("node_sets", [False, True])
def test_node_sets_match_brute_force(node_sets, monkeypatch):
    """Optimum equal to brute force on the 24 random SOPs of test_sop_bc; each row of the
    model holds on every feasible order (its side, 1 or 2, kept when the two families are
    added together)."""
    monkeypatch.setattr(sop_bc, "NODE_SETS", node_sets)
    for seed in range(24):
        problem = _instance(seed)
        model = SopCutModel(problem)
        result = sop_bc.solve_sop_bc(problem, model=model)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(sop_brute_force(problem))
        assert_rows_hold(model, problem, 1e-6)
