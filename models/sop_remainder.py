"""A completion bound re-optimised per order ideal: the assignment relaxation of the remainder.

Problem: the SOP of :mod:`taopt.models.sop` (cheapest Hamiltonian path ``start -> ... -> end``
respecting the precedences), searched by the DP over states ``(I, v)`` of
:mod:`taopt.models.sop_dp` (``I`` an order ideal, ``v`` its last node, ``f(I, v)`` the
cheapest prefix).

Bound. Every completion of a state ``(I, v)`` is a path ``v -> u_1 -> ... -> end`` through
exactly ``U = V \\ I`` on usable arcs: it leaves ``v`` and every node of ``U \\ {end}`` once
and enters every node of ``U`` once. Its arcs are therefore an assignment of the rows
``{v} ∪ U \\ {end}`` to the columns ``U`` (the assignment relaxation of the thesis's (2.2)-(2.3)
restricted to the remainder, subtours and precedences dropped), so

    cost(completion) >= AP(I, v) = min over assignments of Σ c[row, column].

Replacing row ``v`` by a row ``s`` with ``c[s, w] = min over v' ∈ L c[v', w]`` (``L`` any set of
last nodes holding ``v``) only lowers every entry of that row, so ``AP(I, s) <= AP(I, v)``:
one assignment per ideal bounds every state of the ideal whose last node is in ``L``, and
``f(I, v) + AP(I, s)`` is a lower bound on every order through ``(I, v)``. An assignment
with no finite solution proves that no completion exists (``inf``).

Why it is stronger than the DP's own bound. The DP's ``g`` (:class:`taopt.models.sop_dp._Bound`)
takes the cheapest arc per node on reduced costs of the assignment prices computed once at
the root: an additive bound that never re-optimises those prices. Solving the assignment on
the remainder re-optimises them per ideal. Measured on the forward layer 11 of prob.42 (the
root's cut loop run 6 s, the DP pruning at the optimum 243 + 0.5, 222,511 states on
146,063 ideals; ``/work/scratch`` script of stop 37): ``f + g`` has median 230, the DP's
bound with row credit 241, ``f + AP`` 245; the assignment drops 58 % of the layer against
23 % for the DP's bounds.

Where it is used. :func:`taopt.models.sop_dp.solve_sop_dp` applies it (``remainder=``) to
the states of each layer that survive the DP's own bounds, ideal by ideal (one
:func:`scipy.optimize.linear_sum_assignment` of at most ``|U|`` rows, 60-160 microseconds
under load), and drops those reaching the incumbent. The ideals whose states' bounds are
already closest to the incumbent go first, in chunks of :data:`CHUNK`; a layer stops after a
chunk in which it dropped under :data:`MIN_SHARE` of the states. It is off by default
(:data:`taopt.models.sop_dp.REMAINDER`): on prob.42 with the optimum as incumbent (30-60 s,
load 5) it cut the states kept by 2.6-4x, but took 20-47 s of the run and the DP reached no
deeper layer; the root's LP re-solved per state (:mod:`taopt.models.sop_statelp`) is the
stronger re-optimisation.

References
----------
Thesis (2.2)-(2.3) (the assignment rows), (5.7) (precedences). Fischetti and Toth, "An
additive bounding procedure for combinatorial optimization problems", Operations Research
37(2), 1989. Libralesso, Bouhassoun, Cambazard, Jost, "Tree search for the sequential ordering
problem", ECAI 2020 (the DP's states as a tree search's nodes).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from taopt.runtime import MARGIN, Deadline

__all__ = ["CHUNK", "MIN_SHARE", "RemainderBound"]

#: Share of a chunk's states the bound must drop for the layer's next chunk to be tried.
MIN_SHARE = 0.1

#: Ideals per chunk (between two looks at the deadline).
CHUNK = 256


class RemainderBound:
    """``AP(I, s)`` of the module docstring for the ideals of a DP layer.

    Parameters
    ----------
    usable : ndarray
        ``n x n`` costs of the usable arcs (``inf`` elsewhere), read in the search's direction.
    end : int
        The path's last node (it is never left).
    """

    def __init__(self, usable: np.ndarray, end: int) -> None:
        self.n = usable.shape[0]
        self.end = end
        finite = np.isfinite(usable)
        spread = float(np.abs(usable[finite]).max(initial=0.0))
        #: The cost standing for a missing arc: above any path's cost, so an assignment
        #: using it has no finite solution.
        self.big = 1.0 + 4.0 * self.n * max(spread, 1.0)
        self.costs = np.where(finite, usable, self.big)
        #: States evaluated and dropped, ideals evaluated, seconds spent, layers skipped.
        self.evaluated = 0
        self.dropped = 0
        self.ideals = 0
        self.seconds = 0.0
        self.skipped = 0

    def value(self, open_nodes: np.ndarray, lasts: np.ndarray) -> float:
        """``AP(I, s)`` for the nodes still to visit ``open_nodes`` (``U``) and the last nodes
        ``lasts`` (``L``): ``inf`` when no assignment uses usable arcs only."""
        if len(open_nodes) == 0:
            return 0.0
        rows = open_nodes[open_nodes != self.end]
        if len(rows) + 1 != len(open_nodes):  # end already visited: no completion
            return float(np.inf)
        table = self.costs[np.concatenate((lasts[:1], rows))][:, open_nodes]
        if len(lasts) > 1:
            table[0] = self.costs[lasts][:, open_nodes].min(axis=0)
        r, c = linear_sum_assignment(table)
        total = float(table[r, c].sum())
        return float(np.inf) if total >= self.big else total

    def layer(
        self,
        members: np.ndarray,
        group: np.ndarray,
        last: np.ndarray,
        value: np.ndarray,
        total: np.ndarray,
        below: float,
        deadline: Deadline,
    ) -> np.ndarray:
        """Per state, ``f + AP(I, s)`` over its ideal's states (``-inf`` where not evaluated).

        ``members`` is ``(ideals, n)`` bool, ``group`` each state's ideal (states of an ideal
        consecutive), ``value`` each state's ``f``, ``total`` its bound so far; ``below`` the
        pruning threshold. The ideals are taken closest to ``below`` first (by their states'
        largest bound so far), in chunks of :data:`CHUNK`; the layer stops after a chunk in
        which the bound dropped under :data:`MIN_SHARE` of the states, or at the deadline.
        """
        began = time.perf_counter()
        out = np.full(len(last), -np.inf)
        bounds = np.searchsorted(group, np.arange(len(members) + 1))
        highest = np.maximum.reduceat(total, bounds[:-1]) if len(total) else total
        order = np.argsort(-highest, kind="stable")
        for lo in range(0, len(order), CHUNK):
            if deadline.expired(MARGIN):
                break
            tried = dropped = 0
            for g in order[lo : lo + CHUNK]:
                a, b = bounds[g], bounds[g + 1]
                ap = self.value(np.flatnonzero(~members[g]), last[a:b])
                out[a:b] = value[a:b] + ap
                tried += b - a
                dropped += int((out[a:b] >= below).sum())
                self.ideals += 1
            self.evaluated += tried
            self.dropped += dropped
            if dropped < MIN_SHARE * tried:
                self.skipped += 1
                break
        self.seconds += time.perf_counter() - began
        return out
