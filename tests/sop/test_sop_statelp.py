"""The per-state LP's cheaper solves (issue 33): HiGHS stopped at the DP's cutoff and each LP
started from an ancestor's basis give the same drop decisions and bounds as the LP solved to its
optimum from the last basis, never above the cheapest order through the state (random tiny SOPs,
brute force, forward and backward)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from taopt.models.sop_cuts import SopCutModel
from taopt.models.sop_statelp import StateLp
from taopt.runtime import Deadline
from tests.reference_exact import sop_brute_force
from tests.sop.test_sop_remainder import _instance, _through

#: Relative tolerance of the DP's cutoff (``UB - tol``, :func:`taopt.models.sop_dp.solve_sop_dp`).
TOL = 1e-9


def _held(problem, members: frozenset[int]) -> np.ndarray:
    held = np.zeros(problem.n, dtype=bool)
    held[list(members)] = True
    return held


def _states(seed: int):
    """The tiny SOP of ``seed`` and its states with the cheapest order through each (None
    when it has no order)."""
    problem = _instance(seed)
    if not math.isfinite(sop_brute_force(problem)):
        return None
    forward, backward = _through(problem)
    states = [(False, s, last, c) for (s, last), c in forward.items()]
    states += [(True, s, last, c) for (s, last), c in backward.items()]
    return problem, states


def _cutoff_checked(seed: int) -> int:
    """Per state of SOP ``seed``, the LP stopped at a cutoff (HiGHS's ``objective_bound``)
    reaches the cutoff exactly when the LP solved to its optimum does, and its value never
    exceeds the cheapest order through the state. Returns how many LPs HiGHS stopped."""
    found = _states(seed)
    if found is None:
        return 0
    problem, states = found
    model = SopCutModel(problem)
    model.root()
    lp = StateLp(model)
    for reverse, members, last, cheapest in states:
        held = _held(problem, members)
        full = lp.bound(held, last, reverse, Deadline(None))
        assert full <= cheapest + 1e-6
        for upper in (c for c in {cheapest, full, full + 1} if math.isfinite(c)):
            cutoff = upper - TOL * abs(upper)
            # from another state's basis, so that HiGHS iterates before it stops
            lp.bound(_held(problem, frozenset()), problem.start, False, Deadline(None))
            value = lp.bound(held, last, reverse, Deadline(None), cutoff)
            assert value <= cheapest + 1e-6
            assert (value >= cutoff) == (full >= cutoff)
            if value < cutoff:
                assert value == pytest.approx(full, abs=1e-6)
    lp.release()
    assert model.highs.getOptionValue("objective_bound")[1] == math.inf
    assert (np.asarray(model.highs.getLp().col_upper_) == 1.0).all()
    return lp.stopped


@pytest.mark.parametrize("seed", range(1, 16))
def test_cutoff_keeps_the_drop_decision_and_a_valid_bound(seed):
    """:func:`_cutoff_checked` on the tiny SOPs."""
    _cutoff_checked(seed)


def test_cutoff_stops_highs_on_a_tiny_sop():
    """The stop at the cutoff is exercised (HiGHS stops some LPs of SOP 0 there), with the
    checks of :func:`_cutoff_checked`."""
    assert _cutoff_checked(0) > 0


@pytest.mark.parametrize("seed", range(12))
def test_ancestor_basis_gives_the_same_bound(seed):
    """Started from the optimal basis of an ancestor state (or the root's), each state's LP
    gives the bound it gives from the last LP's basis (any optimal duals give the LP's
    optimum, rounded up alike)."""
    found = _states(seed)
    if found is None:
        return
    problem, states = found
    model = SopCutModel(problem)
    model.root()
    lp = StateLp(model)
    root_basis = model.highs.getBasis()
    bases = {}
    for reverse, members, last, cheapest in sorted(states, key=lambda s: len(s[1])):
        held = _held(problem, members)
        plain = lp.bound(held, last, reverse, Deadline(None))
        if np.isfinite(plain):
            bases[(reverse, members)] = model.highs.getBasis()
        parents = [b for (r, m), b in bases.items() if r == reverse and m < members]
        for basis in [root_basis, *parents[-2:]]:
            value = lp.bound(held, last, reverse, Deadline(None), basis=basis)
            assert value <= cheapest + 1e-6
            if math.isfinite(plain) or math.isfinite(value):
                assert value == pytest.approx(plain, abs=1e-6)
    lp.release()
