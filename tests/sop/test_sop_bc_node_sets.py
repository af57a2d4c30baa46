"""The tree with the set path cuts separated in every node round (``sop_bc.NODE_SETS``): its
optimum equals brute force on random tiny SOPs, and every row it added (path, set and
alternation rows, sides kept) holds on every feasible order."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.models import sop_bc
from taopt.models.sop_cuts import SopCutModel
from taopt.result import OPTIMAL
from tests.reference_exact import sop_brute_force, sop_orders
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
        for order in sop_orders(problem):
            used = np.zeros(model.n_arcs)
            used[model.arc_index[order[:-1], order[1:]]] = 1.0
            for row, side, weights in zip(
                model.cut_rows, model.cut_sides, model.cut_weights, strict=True
            ):
                lhs = used[row].sum() if weights is None else used[row] @ weights
                assert lhs >= side - 1e-6
