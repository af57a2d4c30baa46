"""Exact sequential ordering by dynamic programming over order ideals (dense precedence).

Problem: the SOP of :mod:`taopt.models.sop` (cheapest Hamiltonian path ``start -> ... ->
end`` on an asymmetric cost matrix, every precedence pair ``(r, j)`` with r before j).

States. A prefix of a feasible path visits a set ``I`` closed under predecessors (an
*order ideal* of the precedence closure) and stops at its last node ``v``, a maximal
element of ``I``. Its best value ``f(I, v)`` is the cheapest such prefix from ``start``:

    f({start}, start) = 0,
    f(I ∪ {w}, w) = min over v of f(I, v) + cost[v, w],

for every ``w`` not in ``I`` whose predecessors are all in ``I`` (the Held–Karp
recursion restricted to ideals; ``end`` succeeds every node, so it only closes the
path). The optimum is ``f(V, end)``. Only ideals are ever generated, so the work grows
with the number of ideals (tens of thousands on the TSPLIB ``.4`` instances, where
precedence is dense), not with 2^n. The DP is expanded layer by layer (``|I| = k``),
vectorised with numpy: ideals are ``uint64`` bitmasks, one word per mask up to 64 nodes and
rows of ``ceil(n / 64)`` words beyond (:mod:`taopt.ideals`), so any ``n``; a layer is sorted
to keep the best value of each ``(I, v)``.

Completion bound. For a state ``(I, v)`` with ``U = V \\ I`` still to visit, the rest
of any feasible path is ``v -> u_1 -> ... -> end`` through exactly ``U``, on arcs a
path respecting the precedences can use (:func:`taopt.sop.problem.usable_arcs`). So

* every ``w`` in ``U`` is entered once, from ``v`` or from another node of ``U``:
  ``in(I, v) = Σ_{w ∈ U} min(c[v, w], min_{u ∈ U \\ {w}} c[u, w])``;
* ``v`` and every node of ``U \\ {end}`` is left once, towards a node of ``U``:
  ``out(I, v) = min_{w ∈ U} c[v, w] + Σ_{u ∈ U \\ {end}} min_{w ∈ U \\ {u}} c[u, w]``;

and ``max(in, out)`` never exceeds the true cheapest completion (both are relaxations:
each counts one arc per node, the cheapest it could be). The same holds on *reduced*
costs ``c'[u, w] = c[u, w] - alpha_u - beta_w`` for any prices: the completion leaves
``v`` and every node of ``U \\ {end}`` once and enters every node of ``U`` once, so its
cost is ``P(I, v) + Σ c'`` over its arcs, with ``P(I, v) = alpha_v + Σ_{u ∈ U \\ {end}}
alpha_u + Σ_{w ∈ U} beta_w``. The DP uses

    g(I, v) = P(I, v) + max(in', out')   (in', out' computed on c'),

with the dual prices of the assignment relaxation (:func:`assignment_potentials`): at the
start ``g`` is the assignment bound, and deeper it adds the reduced cost of the cheapest
arcs still usable (the additive bounding of Fischetti and Toth). This is what closes
ESC25 and ESC47: without the prices the DP kept 2.3 million states on ESC25 and did not
finish ESC47 within 2 million; with them 454 and about 25,000. The minima over ``U``
are found per ideal as the first arc, in each node's arcs sorted by reduced cost, whose
other end is still unvisited, ``O(n log n)`` per state by binary search; a layer's ideals
share most of it (``_Bound._per_ideal_band``): a node every ideal of the layer holds
takes no part, and a node whose cheapest arc's other end no ideal holds gets that arc in
every ideal, so only the *band* (nodes some but not all ideals hold, a few dozen under the
dense precedence of the rbg files) is looked at per ideal. The arc
out of ``v`` goes to an *available* node (its predecessors all in ``I``), and exactly
one node of ``U`` is entered from ``v``: ``in`` takes the cheapest arc from ``U`` for every
node but one available node, entered from ``v`` (the cheapest such swap).

Two directions. The same DP on the reversed SOP (:func:`reversed_problem`: transposed
costs, reversed precedences, ``end`` first) builds paths backwards from ``end``, over the
order *filters*; its completion bound is the same bound on the reversed data. The two run
side by side, one layer at a time, the one that has kept fewer states advancing; when the
forward depth plus the backward depth reaches ``n - 2``, a forward state ``(I, v)`` and a
backward state ``(V \\ I, w)`` joined by the arc ``v -> w`` are exactly the paths, and the
cheapest join is the optimum (every path cheaper than the incumbent is unpruned in both).
The pruning is much stronger in one direction on some instances: rbg048a's forward
search kept 5.5 million states in 33 s without closing; the backward one closes it in
0.4 s. Meeting in the middle spares each direction its widest layers (the middle ones).

Pruning. With an incumbent of cost ``UB`` (the warm start, or ``incumbent=``), a state
with ``f + g >= UB - tol`` cannot lead to a path cheaper than ``UB`` by more than
``tol = 1e-9 |UB|``, and is dropped; the smallest ``f + g`` of the dropped states is kept,
so the proven bound is ``min(UB, that)``. A run stopped by its time limit proves
``min`` over the open layer and the dropped states of ``f + g`` (never below the
assignment and arborescence bounds, whose maximum is taken); when the DP exhausts every
state without a path, and every dropped state had ``g = inf`` (no completion), no
feasible path exists: status
"infeasible", proved by exhaustion.

An LP's Lagrangian bound. Given row duals ``y`` of an LP relaxation of the SOP over its
arcs (the cut engine's root, :meth:`taopt.models.sop_cuts.SopCutModel.lagrangian_prices`),
with the signs of their rows, and ``d = c - A^T y``, every feasible order ``x`` (an arc
vector satisfying the rows) costs ``c x = y^T A x + d x >= y^T b + d x >= L + Σ_{a ∈ x}
max(d_a, 0)`` with ``L = y^T b + Σ_a min(d_a, 0)``. Along a state's kept prefix ``p``
(its cheapest) the full order through the state is ``p`` plus a completion, so
``L + Σ_{a ∈ p} max(d_a, 0)`` (rounded up to a multiple of the costs' gcd when they are
integral: every order's cost is one) is a lower bound on every path through the state,
and the state is dropped when it reaches ``UB - tol`` like ``f + g``
(``lagrange=`` of :func:`solve_sop_dp`). The backward search reads ``d`` transposed. On
p43.1 the root's ``L`` is 28,098 against the optimum 28,140: a prefix of reduced cost
above 42 is dropped.

Row credit. The same duals say more about a prefix than its reduced cost. Write the LP's
rows as the degree rows (equalities) and path cuts ``Σ_{a ∈ C_r} x_a >= 1`` (0/1
coefficients, duals ``y_r >= 0``; :class:`~taopt.models.sop_dp.RowCredit`, from
:meth:`taopt.models.sop_cuts.SopCutModel.row_credit`). For an order ``x = p + q`` (the
state's kept prefix ``p``, a completion ``q``), ``c x = y^T A x + d x`` exactly, and each
cut row is crossed ``A_r x >= max(1, A_r p)`` times (``q >= 0``, coefficients >= 0), so

    c x >= y^T b + Σ_r y_r (A_r p - 1)^+ + d p + d q,

and ``q`` uses only arcs from ``{v} ∪ U`` into ``U`` (``U`` the nodes still to visit), so
``d q >= Σ d_a`` over the arcs of negative ``d`` among those. The DP keeps per state the
priced rows its prefix has crossed (one bit each, 64 rows of largest dual at most: rows left
out only lose credit) and adds ``y_r`` whenever an arc crosses row ``r`` again; the bound is
never below the prefix bound above (it differs by the credit and by the negative arcs the
rest can no longer use), and it is the one used when ``credit=`` is given. As above, the
kept prefix is the cheapest of its state, so a bound on the orders through it bounds every
order through the state. On prob.42 with its optimum 243 as the incumbent, the forward
search kept 80,945 states at depth 10 with the credit against 151,910 without (the
backward one 128,599 against 184,671).

The root's LP per state. ``state_lp=`` (:class:`~taopt.models.sop_statelp.StateLp`)
re-solves the root cut model's LP with a state's ideal fixed (no arc back into ``I``, none
out of ``I`` but from ``v``) for the states of a layer that survive the bounds above, and a
state's descendants inherit its prices: ``B + Σ_{a ∈ p} max(d_a, 0)`` along their kept prefix
``p``, ``B`` the restricted LP's Lagrangian bound (the proof is in
:mod:`taopt.models.sop_statelp`). It is a branch-and-bound with an LP per node whose nodes are
the DP's states. On prob.42 with its optimum as the incumbent, the DP with it ended in 27 s
(load 5-7); without it the DP kept 1.6 million states in 60 s without ending.

Position windows. ``window=`` (node prices ``lam`` of :mod:`taopt.models.sop_window`) bounds
every state's completion also by ``H(k, v) + Σ_{u ∈ U} lam_u``: the cheapest relaxed walk
from ``v`` at position ``k = |I| - 1`` to ``end`` through the nodes whose position windows
allow them (the proof is in that module), a table look-up and a masked sum per state, taken
first; the assignment-based ``g`` is then computed only for the states it leaves. On
rbg-atsp-175 with its optimum 1,879 as the incumbent the DP kept 3.59 million states with it
against 3.99 million without (prices of 300 subgradient steps from zero, root bound 1,833).

References
----------
Thesis §5.2, (5.7) (precedences), §5.4 (the orderings NIA, MMA, SMMA give the
incumbent). Held and Karp, "A dynamic programming approach to sequencing problems",
J. SIAM 10(1), 1962 (the recursion, here restricted to order ideals). Fischetti and
Toth, "An additive bounding procedure for combinatorial optimization problems",
Operations Research 37(2), 1989 (bounds on reduced costs).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt import ideals
from taopt.errors import InstanceError
from taopt.ideals import bits as node_bits
from taopt.ideals import differs, has, holds, lex_keys, nonzero, predecessor_masks, row_keys
from taopt.ideals import runs as _groups
from taopt.models.sop_remainder import RemainderBound
from taopt.models.sop_statelp import MIN_SHARE, StateLp
from taopt.models.sop_window import WindowCompletion
from taopt.result import TIME_LIMIT, Order, Solution, finish
from taopt.runtime import MARGIN, CancelToken, Deadline
from taopt.sop.problem import SopProblem, path_cost, usable_arcs

__all__ = [
    "GIVE_UP_GROWTH",
    "MAX_NODES",
    "TRIAL_STEP",
    "IDEAL_CAP",
    "RowCredit",
    "count_ideals",
    "completion_bound",
    "reversed_problem",
    "solve_sop_dp",
    "trial_cutoffs",
]

#: With an LP's Lagrangian bound (``lagrange=`` of :func:`solve_sop_dp`), also bound the
#: rest of each state's path on the reduced costs (``g`` on ``max(d, 0)``), not only its
#: prefix. Off: on p43.1 with the optimal order it dropped 0.1 % more states at 1.35 times
#: the time (the LP's reduced costs are mostly 0 on the arcs a completion needs).
LAGRANGE_REST = False

#: Default of ``solve_sop_dp(remainder=...)``: the states left by the DP's own bounds are
#: also bounded by the remainder's assignment, re-optimised per ideal
#: (:mod:`taopt.models.sop_remainder`). Off: it drops states but costs more time than they
#: save (its module docstring has the figures).
REMAINDER = False

#: With ``give_up`` (:func:`~taopt.models.sop_dp.solve_sop_dp`), the search stops when a
#: layer past the first grows more than this many times its parent layer. With their optima as
#: the incumbent and the root's LP per state, prob.42's layers grew at most 2x a layer (4, 8, 14,
#: 24, 34, ...) and it was proven; ft53.1's and ry48p.1's second layers grew 9-17x (31 -> 395,
#: 33 -> 563) and neither was proven in 60 s.
GIVE_UP_GROWTH = 4.0

#: :func:`trial_cutoffs` steps its trial cutoff up by this share of the bound: small steps
#: bound the cost of overshooting the optimum (a trial's work grows about geometrically with
#: its cutoff, 1.5x a unit of cost, 0.4 % of the bound, on prob.42), and the trials below it
#: add a geometric series dominated by the last. The root gaps of the shipped .1 files are
#: 0.02-6.5 % (p43.1, ft53.1, ry48p.1, prob.42): at most seven trials cross the widest. A step
#: relative to the incumbent's gap instead followed the incumbent, 30 % above the bound before
#: the primal search: prob.42's first trial was at 242 (optimum 243), ran 13 s and gave up.
TRIAL_STEP = 0.01

#: Share of the stage's time left one trial cutoff may use (the incumbent's own trial, the
#: last, gets all of it): a trial cut by its time proves nothing, and the rest is left for a
#: smaller step.
TRIAL_TIME_SHARE = 0.5

#: States per call of that bound between two looks at the deadline.
LAGRANGE_CHUNK = 20_000

#: No limit on the nodes any more (masks of more than 64 nodes are rows of several words,
#: :mod:`taopt.ideals`); kept for callers that compared against it.
MAX_NODES = 1 << 30

#: Default cap of :func:`count_ideals`: below it the portfolio runs the DP alone for the
#: whole limit. CPU seconds to count the ideals of the .4 files: p43.4 37,921 in 0.02,
#: ry48p.4 68,657 in 0.03, ft53.4 154,689 in 0.05 (at 20,000 they were "too many": the DP
#: got half of a 60 s limit and did not close ry48p.4 and ft53.4 at load 9-11; alone it
#: closes them); a count past the cap stops early (every layer checks it).
IDEAL_CAP = 200_000

#: Share of the time limit the beam passes may use.
BEAM_SHARE = 0.25

#: Share of the stage's time the first (narrowest) beam pass may use when the beam's budget
#: (:data:`BEAM_SHARE`) is shorter: a pass cut by its time finds nothing, and the DP then starts
#: from the warm start's order. ESC47 at 10 s under load (its own process niced, a spinner
#: beside, load 6-7): the 64-wide pass (1291 in 0.3 s quiet) was cut by a budget of about 1 s,
#: the DP kept 54,645 states from 1506 without closing, where from 1291 it closes with
#: 30,170 (2026-11-27).
FIRST_BEAM_SHARE = 0.5

#: A wider beam pass is started only when the last one's time, grown as the ratio of the widths
#: to this power, fits in the beam's budget. Measured 64 -> 256 -> 1,024: 1.6x and 3x on
#: rbg-atsp-150, 1.6x and 4x on rbg-atsp-175, 1.9x and 3.7x on ESC47, 3.1x and 7x on
#: rbg-atsp-255. 0.35 (1.62x a step) is the least growth measured, so a pass is skipped only
#: when even that would not fit: with the square root (2x) rbg-atsp-150 at 60 s under load
#: 6-10 skipped its middle pass in both DP stages and ended 2116 [2107] (the pass finds 2107).
BEAM_TIME_EXPONENT = 0.35

#: Width of the first, narrow beam pass.
NARROW_BEAM = 64

#: Width of the middle beam pass, between the narrow one and ``beam_width``: on the
#: 150-node rbg stand-in it finds the optimum 2107 in 1.5 s where the narrow pass ends at
#: 2116 and the 1,024-wide one did not finish in the first DP stage's beam share at 60 s.
MIDDLE_BEAM = 256

#: Default of ``solve_sop_dp(both_prices=...)``: off (see its docstring); the portfolio's
#: second DP stage turns it on.
BOTH_PRICES = False

#: The other prices are dropped when, over their first ``SECOND_PRICES_TRIAL`` states, they
#: prune under ``SECOND_PRICES_MIN_SHARE`` of them (ry48p.4, ft53.4: nothing to gain there,
#: and the second bound doubled the time).
SECOND_PRICES_TRIAL = 20_000
SECOND_PRICES_MIN_SHARE = 0.02

#: Seconds of completion bound between two deadline checks (the chunk of states is sized
#: by the rate measured on the last chunk).
CHUNK_SECONDS = 0.25

#: Most (state, node) pairs the completion bound is evaluated on at once (``_Search.totals``):
#: its work arrays are a few ``states x nodes`` tables (the ideals' cheapest arcs in and out,
#: their sums: about 50 bytes a pair), so a chunk's memory stays near 50 MB whatever the
#: bound's speed. Chunks sized by time alone (:data:`CHUNK_SECONDS`) grew with the band's
#: faster bound to 200,000 states of 48 nodes (ry48p.1).
BOUND_ENTRIES = 1 << 20

#: Seconds per state, node and mask word of the completion bound before one chunk was timed
#: (200,000 states on 49 nodes took 2-3 s on a loaded core, ESC47).
BOUND_SECONDS = 3e-7

#: Seconds per state to put a layer's merged blocks in order (``_Search.grow``), before one
#: was timed (1 million in 0.3 s).
MERGE_SECONDS = 3e-7

#: Relative tolerance of the pruning test ``f + g >= UB - tol``.
PRUNE_TOLERANCE = 1e-9

_ONE = np.uint64(1)

#: Below this many (state, arc) pairs the cheapest open arc is found by one 2-D test
#: instead of a binary search (numpy call overhead dominates small layers).
_DIRECT = 1 << 18

#: Entries (states x nodes) of the dense per-state arrays of the completion bound at a time.
DENSE_BLOCK = 1 << 20

#: Masks of two words (65 to this many nodes) with at least :data:`DENSE_ARC_SHARE` of the
#: pairs usable arcs get the per-ideal sums of the completion bound as dense ``n x n``
#: minima (CPU seconds for 3,000 states of esc-like-65: 0.040 against 0.052 by binary
#: search); one-word masks are faster by binary search (ESC47: 0.023 against 0.028).
DENSE_NODES = 100

#: The least share of usable arcs (among the ordered pairs) for the dense minima of
#: :data:`DENSE_NODES`.
DENSE_ARC_SHARE = 0.75


#: The completion bound's per-ideal sums by ``_Bound._per_ideal_band`` (the work
#: confined to the nodes some but not all of a layer's ideals hold) instead of a binary
#: search per node and ideal (the same values, tested). The DP alone on rbg-atsp-150 in 20 s
#: (load 2-5): 186,139 states kept before (13.2 s of the 20 in the per-ideal sums), 716,612
#: after; one layer of 12,196 states on it 0.017 s against 0.116 s, of 20,000 on
#: rbg-atsp-255 0.15 s against 0.7-0.8 s, on ESC47 0.20 s against 0.27 s.
BAND = True


def _predecessor_masks(problem: SopProblem) -> np.ndarray:
    """``pred[w]``: bitmask of every node that must come before ``w`` (closed relation)."""
    return predecessor_masks(problem.n, problem.closure.edges)


def count_ideals(
    problem: SopProblem, cap: int = IDEAL_CAP, deadline: Deadline | None = None
) -> tuple[int, bool]:
    """Number of order ideals containing ``start`` (the DP's sets), counted up to ``cap``.

    Parameters
    ----------
    problem : SopProblem
    cap : int
        Stop once more than ``cap`` ideals are counted.
    deadline : Deadline, optional
        Stop, as if capped, once it has expired (looked at for every node of every layer);
        given one, a layer whose candidates prove the cap passed (each ideal has at most
        as many parents as removable nodes) ends the count as capped without merging them.

    Returns
    -------
    count : int
        The exact number of ideals, or ``cap + 1`` when ``capped``.
    capped : bool
        True when the count passed ``cap`` or the deadline came first (the true number
        is larger or unknown).

    Notes
    -----
    :func:`taopt.ideals.count_ideals` on the precedence closure, from ``{start}``:
    ``O(n · count)``. Precedences only: forbidden arcs are ignored (an upper bound on the
    sets the DP meets).

    Example
    -------
    >>> count_ideals(SopProblem.load("ESC07"))
    (41, False)
    """
    first = 1 << problem.start
    return ideals.count_ideals(
        _predecessor_masks(problem), problem.n, cap, first=first, deadline=deadline
    )


class _Bound:
    """The completion bound ``P + max(in', out')`` of the module docstring, vectorised.

    ``usable[u, w]`` is the cost of a usable arc ``u -> w`` (``inf`` otherwise). For each
    node the arcs into it (and out of it) are sorted by cost; ``prefix[t]`` is the bitmask
    of the first ``t`` other ends, so "the cheapest arc from an unvisited node" is the
    first ``t`` with ``prefix[t] & ~I != 0``, found by binary search.
    """

    def __init__(
        self,
        usable: np.ndarray,
        start: int,
        end: int,
        potentials: tuple[np.ndarray, np.ndarray] | None = None,
        pred: np.ndarray | None = None,
    ) -> None:
        n = usable.shape[0]
        self.n, self.start, self.end = n, start, end
        if potentials is None:
            potentials = (np.zeros(n), np.zeros(n))
        self.alpha: np.ndarray = potentials[0]
        self.beta: np.ndarray = potentials[1]
        #: The open prices' total and byte table (:meth:`_price_bytes`), made when first used.
        self._price_table: tuple[float, np.ndarray] | None = None
        usable = usable - self.alpha[:, None] - self.beta[None, :]  # reduced costs (inf stays)
        self.usable = usable
        bits = node_bits(n)
        self.pred = np.zeros_like(bits) if pred is None else pred
        self.bits = bits
        self.wide = bits.ndim == 2
        #: Share of the ordered pairs that are usable arcs (sparse: short binary searches).
        self.arc_share = float(np.isfinite(usable).sum()) / max(n * (n - 1), 1)
        self._no_loops = usable.copy()
        np.fill_diagonal(self._no_loops, np.inf)
        self.into = [self._sorted(usable[:, w], bits) for w in range(n)]
        self.out = [self._sorted(usable[u, :], bits) for u in range(n)]
        #: Per node, the other ends of its usable arcs in and out (itself left out) and
        #: their reduced costs, cheapest first (:meth:`_per_ideal_band`).
        self.into_ends = [self._ends(usable[:, w], w) for w in range(n)]
        self.out_ends = [self._ends(usable[u, :], u) for u in range(n)]
        #: Per node, the nodes that must precede it (and as an ``n x n`` 0/1 matrix).
        self.pred_bool = _members(self.pred, n).astype(np.int32)
        self.pred_nodes = [np.flatnonzero(row) for row in self.pred_bool]
        #: Per node, the other end and cost of its cheapest arc in and out (-1, inf: none).
        self.in_first = self._firsts(self.into_ends)
        self.out_first = self._firsts(self.out_ends)

    @staticmethod
    def _firsts(arcs: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
        """Per node, the other end and the cost of the first of its ``arcs`` (-1, inf: none)."""
        end = np.array([e[0] if len(e) else -1 for e, _ in arcs], dtype=np.int64)
        cost = np.array([c[0] if len(c) else np.inf for _, c in arcs])
        return end, cost

    @staticmethod
    def _ends(costs: np.ndarray, own: int) -> tuple[np.ndarray, np.ndarray]:
        """The other ends of a node's finite arcs, cheapest first (stable), and their costs."""
        ends = np.flatnonzero(np.isfinite(costs))
        ends = ends[np.argsort(costs[ends], kind="stable")]
        ends = ends[ends != own]
        return ends, costs[ends]

    @staticmethod
    def _sorted(costs: np.ndarray, bits: np.ndarray) -> tuple[np.ndarray, ...]:
        ends = np.flatnonzero(np.isfinite(costs))
        ends = ends[np.argsort(costs[ends], kind="stable")]
        prefix = np.zeros((len(ends) + 1,) + bits.shape[1:], dtype=np.uint64)
        if len(ends):
            prefix[1:] = np.bitwise_or.accumulate(bits[ends], axis=0)
        values = np.append(costs[ends], np.inf)  # index len(ends): no arc left
        # wide masks: each end's word and bit, for the direct test
        return prefix, values, ends // 64, (ends % 64).astype(np.uint64)

    @staticmethod
    def _cheapest(open_mask: np.ndarray, table: tuple[np.ndarray, ...]) -> np.ndarray:
        """Per state, the cheapest arc whose other end is in ``open_mask`` (inf if none)."""
        prefix, values, word, shift = table
        k = len(prefix) - 1
        wide = prefix.ndim == 2
        if len(open_mask) * k <= _DIRECT:  # small: one 2-D test, no loop (less overhead)
            if wide:  # the bit of each end, gathered from its word
                hit = ((open_mask[:, word] >> shift[None, :]) & _ONE) != 0
            else:
                hit = (open_mask[:, None] & prefix[None, 1:]) != 0
            first = np.argmax(hit, axis=1) if k else np.zeros(len(open_mask), dtype=np.int64)
            found = hit.any(axis=1) if k else np.zeros(len(open_mask), dtype=bool)
            return np.where(found, values[first], np.inf)
        lo = np.zeros(len(open_mask), dtype=np.int64)
        # the answer is the first arc t (0-based) whose end is open, in [lo, hi]
        hi = np.full(len(open_mask), max(k - 1, 0), dtype=np.int64)
        found = nonzero(prefix[k] & open_mask, wide)
        while True:
            active = lo < hi
            if not active.any():
                break
            mid = (lo + hi) // 2  # < hi <= k - 1 where active; unused elsewhere
            hit = nonzero(prefix[np.minimum(mid + 1, k)] & open_mask, wide)  # an end in 0..mid
            hi = np.where(active & hit, mid, hi)
            lo = np.where(active & ~hit, mid + 1, lo)
        return np.where(found, values[np.minimum(lo, k)], np.inf)

    def potential(self, mask: np.ndarray, last: np.ndarray) -> np.ndarray:
        """``P(I, v)``: alpha of ``v`` and of every node still to be left, beta of every node
        still to be entered. With reduced costs >= 0 it is a valid bound by itself."""
        group, unique = _groups(mask)
        return self.alpha[last] + self._open_prices(unique)[group]

    def _open_prices(self, mask: np.ndarray) -> np.ndarray:
        """Per mask, the prices of the nodes still to be left and entered (``P`` less
        ``alpha_v``): the sum over all of them less those the mask holds, read byte by byte
        from a table (:meth:`_price_bytes`; a product with the membership table cast to
        floats took 20 % of ESC47's DP and 8 bytes per node and mask)."""
        if self._price_table is None:
            self._price_table = self._price_bytes()
        total, table = self._price_table
        if not len(mask):
            return np.zeros(0)
        raw = np.ascontiguousarray(mask.astype("<u8", copy=False)).view(np.uint8)
        raw = raw.reshape(len(mask), -1)
        out = np.full(len(mask), total)
        for k in range(min(raw.shape[1], len(table))):
            out -= table[k][raw[:, k]]
        return out

    def _price_bytes(self) -> tuple[float, np.ndarray]:
        """The sum of the open prices over every node and ``[k, b]``: the sum over the nodes
        whose bits in byte ``k`` of a mask are set in ``b``."""
        price = self.beta + np.where(np.arange(self.n) != self.end, self.alpha, 0.0)
        price[self.start] = 0.0
        padded = np.zeros(-(-self.n // 8) * 8)
        padded[: self.n] = price
        byte = np.arange(256)
        table = np.zeros((len(padded) // 8, 256))
        for k in range(len(table)):
            for bit in range(8):
                table[k] += np.where((byte >> bit) & 1, padded[8 * k + bit], 0.0)
        return float(price.sum()), table

    def __call__(self, mask: np.ndarray, last: np.ndarray) -> np.ndarray:
        """``g`` for each state ``(mask[i], last[i])``."""
        return self.potential(mask, last) + self.extra(mask, last)

    def extra(self, mask: np.ndarray, last: np.ndarray) -> np.ndarray:
        """``max(in', out')`` on the reduced costs (>= 0 when they are).

        Exactly one node of ``U`` is entered from ``v``, and only a node whose
        predecessors are all in ``I`` (*available*): ``in'`` is the sum over ``U`` of the
        cheapest arc from ``U``, plus the least ``c'[v, w] - (that arc)`` over available
        ``w`` (one node swaps its in-arc for the arc from ``v``); ``out'`` leaves ``v``
        towards an available node.

        The sums over ``U`` depend on the ideal alone: they are computed once per distinct
        mask among consecutive states (a layer is sorted by mask, and several last nodes
        share an ideal: 4.7 states per mask on ry48p.4), the terms of ``v`` as dense
        ``states x n`` arrays in blocks of :data:`DENSE_BLOCK` entries.
        """
        group, unique = _groups(mask)
        in_sum, out_sum, entry, ready, forced, todo_all = self._per_ideal(unique)
        done = ~np.asarray(todo_all.any(axis=1))  # per ideal: nothing left to visit
        # only the nodes available in some ideal, or entered from v only, take part in the
        # terms of v (every other column adds nothing): a few dozen under dense precedence
        unentered = todo_all & ~np.isfinite(entry)
        cols = np.flatnonzero(ready.any(axis=0) | unentered.any(axis=0))
        ready, entry, unentered = ready[:, cols], entry[:, cols], unentered[:, cols]
        usable = self.usable[:, cols]
        result = np.empty(len(mask))
        step = max(1, DENSE_BLOCK // max(len(cols), 1))
        for lo in range(0, len(mask), step):
            g = group[lo : lo + step]
            arc = usable[last[lo : lo + step]]  # c'[v, .] per state
            avail = ready[g]
            from_last = np.where(avail, arc, np.inf)
            out_last = from_last.min(axis=1, initial=np.inf)
            out_last[~avail.any(axis=1)] = 0.0
            one = entry[g]
            with np.errstate(invalid="ignore"):
                swap = np.where(avail & np.isfinite(one), from_last - one, np.inf).min(
                    axis=1, initial=np.inf
                )
            forced_here = forced[g]
            forced_cost = np.where(unentered[g], from_last, 0.0).sum(axis=1)
            total_in = in_sum[g] + np.where(
                forced_here == 0, swap, np.where(forced_here == 1, forced_cost, np.inf)
            )
            total_out = out_sum[g] + out_last
            finished = done[g]
            total_in[finished] = 0.0
            total_out[finished] = 0.0
            result[lo : lo + step] = np.maximum(total_in, total_out)
        return result

    def _per_ideal(self, mask: np.ndarray) -> tuple[np.ndarray, ...]:
        """Per ideal: the sums over ``U`` of the cheapest arc into (``in``) and out of
        (``out``) each node from/to ``U``, that arc into each node (``entry``, ``inf`` for
        a node not in ``U`` or entered from ``v`` only), the available nodes, the count of
        nodes entered from ``v`` only, and ``U`` less ``start`` (bool ``(k, n)`` arrays)."""
        n, bits, pred = self.n, self.bits, self.pred
        if self.wide and n <= DENSE_NODES and self.arc_share >= DENSE_ARC_SHARE:
            return self._per_ideal_dense(mask)
        if BAND:
            return self._per_ideal_band(mask)
        unvisited = ~mask & ideals.full(n)
        count = len(mask)
        in_sum = np.zeros(count)
        out_sum = np.zeros(count)
        entry = np.full((count, n), np.inf)
        ready = np.zeros((count, n), dtype=bool)
        todo_all = np.zeros((count, n), dtype=bool)
        forced = np.zeros(count, dtype=np.int64)
        for w in range(n):
            if w == self.start:
                continue
            todo = ~has(mask, w)
            if not todo.any():
                continue
            rows = np.flatnonzero(todo)
            todo_all[rows, w] = True
            others = unvisited[todo] & ~bits[w]
            from_open = self._cheapest(others, self.into[w])
            ready[rows, w] = holds(mask[todo], pred[w])
            finite = np.isfinite(from_open)
            entry[rows, w] = from_open
            in_sum[todo] += np.where(finite, from_open, 0.0)
            forced[todo] += ~finite
            if w != self.end:
                out_sum[todo] += self._cheapest(others, self.out[w])
        return in_sum, out_sum, entry, ready, forced, todo_all

    def _per_ideal_band(self, mask: np.ndarray) -> tuple[np.ndarray, ...]:
        """:meth:`_per_ideal` with the work confined to the layer's *band*: the nodes some but
        not all of its ideals hold.

        A node every ideal of the layer holds is neither entered nor left any more; a node
        no ideal holds is still open in every one. So in the list of a node's arcs, cheapest
        first, an end held by every ideal is never the answer, and the first end held by
        none is open in every ideal: the answer is among the ends up to it (the
        *candidates*), and when the first candidate is held by none it is the same for the
        whole layer. Only the candidates are tested per ideal, as one ``candidates x
        ideals`` look-up in the layer's membership table. Under dense precedence (the rbg
        files) the band is a few dozen nodes wide and the candidates one or two, where
        :meth:`_per_ideal` made a binary search over every node's arcs for every ideal. Same
        values (tested against it).
        """
        n = self.n
        member = _members(mask, n)  # (k, n) bool: node held by the ideal
        open_t = np.ascontiguousarray(~member.T)  # (n, k): node still to visit
        held_by_all = np.asarray(member.all(axis=0))
        held_by_some = np.asarray(member.any(axis=0))
        todo_all = ~member
        todo_all[:, self.start] = False
        # available: every predecessor held; decided for the whole layer unless one is in
        # the band (held by some ideals only)
        lacks_all = self.pred_bool @ ~held_by_all  # predecessors not held by every ideal
        lacks_some = self.pred_bool @ ~held_by_some  # predecessors held by no ideal
        ready = todo_all & (lacks_all == 0)[None, :]
        for w in np.flatnonzero((lacks_all > 0) & (lacks_some == 0) & ~held_by_all):
            ready[:, w] = todo_all[:, w] & holds(mask, self.pred[w])
        entry = self._band_minima(self.into_ends, self.in_first, held_by_all, held_by_some, open_t)
        leave = self._band_minima(self.out_ends, self.out_first, held_by_all, held_by_some, open_t)
        return self._sums(entry, leave, ready, todo_all)

    def _sums(
        self, entry: np.ndarray, leave: np.ndarray, ready: np.ndarray, todo_all: np.ndarray
    ) -> tuple[np.ndarray, ...]:
        """Per ideal, from its nodes' cheapest entering (``entry``) and leaving (``leave``)
        arcs over the nodes still to visit (``todo_all``): the sum of the finite entries, the
        sum of the leaving ones (the end node leaves nowhere), the entries (inf off the todo
        set), ``ready``, the count of todo nodes with no entering arc, and ``todo_all``: the
        tuple :meth:`_per_ideal` returns, shared by its band and dense forms."""
        entry[~todo_all] = np.inf
        finite = np.isfinite(entry)
        in_sum = np.where(finite, entry, 0.0).sum(axis=1)
        forced = (todo_all & ~finite).sum(axis=1)
        leaving = todo_all.copy()
        leaving[:, self.end] = False
        out_sum = np.where(leaving, leave, 0.0).sum(axis=1)
        return in_sum, out_sum, entry, ready, forced, todo_all

    def _band_minima(
        self,
        arcs: list[tuple[np.ndarray, np.ndarray]],
        first: tuple[np.ndarray, np.ndarray],
        held_by_all: np.ndarray,
        held_by_some: np.ndarray,
        open_t: np.ndarray,
    ) -> np.ndarray:
        """``(k, n)``: per ideal and node, the cheapest of the node's ``arcs`` whose other end
        is open (``inf`` if none), for every ideal (the caller masks the nodes held).

        A node whose cheapest arc's other end no ideal holds gets that arc in every ideal
        (one vector step); the others are looked up in the band (:meth:`_first_open`)."""
        end, cost = first  # per node, its cheapest arc's other end (-1: none) and cost
        same = (end >= 0) & ~held_by_some[np.maximum(end, 0)]
        out = np.broadcast_to(np.where(same, cost, np.inf), (open_t.shape[1], self.n)).copy()
        for w in np.flatnonzero(~same & ~held_by_all & (end >= 0)):
            out[:, w] = self._first_open(arcs[w], held_by_all, held_by_some, open_t)
        return out

    @staticmethod
    def _first_open(
        arcs: tuple[np.ndarray, np.ndarray],
        held_by_all: np.ndarray,
        held_by_some: np.ndarray,
        open_t: np.ndarray,
    ) -> np.ndarray | float:
        """Per ideal, the cost of the first arc of ``arcs`` (cheapest first)
        whose other end is open (``inf`` if none): a scalar when the same for every ideal."""
        ends, costs = arcs
        if not len(ends):
            return np.inf
        closed = held_by_some[ends]
        stop = int(np.argmin(closed)) if not closed.all() else len(ends) - 1
        keep = ~held_by_all[ends[: stop + 1]]
        cand, value = ends[: stop + 1][keep], costs[: stop + 1][keep]
        if not len(cand):
            return np.inf
        if not held_by_some[cand[0]]:
            return float(value[0])
        hit = open_t[cand]  # (candidates, ideals)
        first = np.argmax(hit, axis=0)
        values = np.append(value, np.inf)
        return np.where(hit.any(axis=0), values[first], np.inf)

    def _per_ideal_dense(self, mask: np.ndarray) -> tuple[np.ndarray, ...]:
        """:meth:`_per_ideal` as ``ideals x n x n`` minima in blocks (no loop over nodes):
        faster up to :data:`DENSE_NODES` nodes, where ``n`` binary searches per ideal cost
        more in numpy calls than ``n ** 2`` comparisons."""
        n = self.n
        count = len(mask)
        node = np.arange(n)
        if mask.ndim == 1:
            member = ((mask[:, None] >> node.astype(np.uint64)[None, :]) & _ONE) != 0
            ready = (mask[:, None] & self.pred[None, :]) == self.pred[None, :]
        else:
            member = ((mask[:, node // 64] >> (node % 64).astype(np.uint64)[None, :]) & _ONE) != 0
            ready = np.ones((count, n), dtype=bool)
            for i in range(mask.shape[1]):
                ready &= (self.pred[None, :, i] & ~mask[:, None, i]) == 0
        todo_all = ~member
        todo_all[:, self.start] = False
        ready &= todo_all
        arcs = self._no_loops
        entry = np.empty((count, n))
        leave = np.empty((count, n))
        step = max(1, DENSE_BLOCK // (n * n))
        for lo in range(0, count, step):
            open_ = ~member[lo : lo + step]
            entry[lo : lo + step] = np.where(open_[:, :, None], arcs[None], np.inf).min(axis=1)
            leave[lo : lo + step] = np.where(open_[:, None, :], arcs[None], np.inf).min(axis=2)
        return self._sums(entry, leave, ready, todo_all)


def _cheapest_per_state(
    mask: np.ndarray, last: np.ndarray, value: np.ndarray, n: int
) -> np.ndarray:
    """The index of the cheapest extension of each ``(mask, last)`` (the first of equal ones),
    in the order of the states (by mask, then last node).

    One stable sort by the state (mask and last node packed into one ``uint64`` when they fit
    in 64 bits, up to 58 nodes), then the least value of each run: the same states and
    parents as a stable sort by (mask, last, value), 4-5x faster on 600,000 extensions (no
    third sort key).
    """
    if mask.ndim == 1 and n <= 58:
        key = (mask << np.uint64(6)) | last.astype(np.uint64)
        order = np.argsort(key, kind="stable")
        key = key[order]
        start = np.ones(len(key), dtype=bool)
        start[1:] = key[1:] != key[:-1]
    else:
        order = np.lexsort((last, *lex_keys(mask)))
        start = np.ones(len(order), dtype=bool)
        start[1:] = differs(mask[order]) | (last[order][1:] != last[order][:-1])
    return order[_least_per_run(value[order], start)]


def _least_per_run(value: np.ndarray, start: np.ndarray) -> np.ndarray:
    """The position of the first least ``value`` in each run (``start`` marks a run's first
    item): the kept extension of each state when the extensions are ordered by state."""
    heads = np.flatnonzero(start)
    run = np.cumsum(start) - 1
    least = np.minimum.reduceat(value, heads)
    hits = np.flatnonzero(value == least[run])  # NaN-free: costs are finite here
    first = np.ones(len(hits), dtype=bool)
    first[1:] = run[hits][1:] != run[hits][:-1]
    return hits[first]


def _in_mask_order(mask: np.ndarray) -> bool:
    """Whether the masks are in the order :func:`_state_order` sorts them by (as integers,
    the last word most significant; equal ones anywhere in a run)."""
    if len(mask) <= 1:
        return True
    if mask.ndim == 1:
        return bool((mask[1:] >= mask[:-1]).all())
    greater = np.zeros(len(mask) - 1, dtype=bool)
    equal = np.ones(len(mask) - 1, dtype=bool)
    for i in range(mask.shape[1] - 1, -1, -1):
        before, after = mask[:-1, i], mask[1:, i]
        greater |= equal & (before > after)
        equal &= before == after
    return not greater.any()


def _cheapest_per_block(
    block: np.ndarray, value: np.ndarray, in_order: bool, n: int, w: int
) -> np.ndarray:
    """:func:`_cheapest_per_state` of the extensions of a layer by one node ``w`` (every
    last node ``w``). From a layer in mask order (``in_order``, :func:`_in_mask_order`) the
    block is in mask order too (adding a bit no mask holds keeps the order of the integers),
    and two extensions are one state only when their parents share the ideal, consecutive
    in the layer: the runs of equal masks are the states, with no sort. Else the sort."""
    if not in_order:
        return _cheapest_per_state(block, np.full(len(block), w, np.int64), value, n)
    start = np.ones(len(block), dtype=bool)
    start[1:] = differs(block)
    return _least_per_run(value, start)


def _state_order(mask: np.ndarray, last: np.ndarray, n: int) -> np.ndarray:
    """The stable order of the states by mask, then last node (the order
    :func:`_cheapest_per_state` returns them in), with no other work array than the key."""
    if mask.ndim == 1 and n <= 58:
        return np.argsort((mask << np.uint64(6)) | last.astype(np.uint64), kind="stable")
    return np.lexsort((last, *lex_keys(mask)))


def _members(mask: np.ndarray, n: int) -> np.ndarray:
    """``(k, n)`` bool: whether each mask holds each node (bits unpacked, little-endian)."""
    words = (mask[:, None] if mask.ndim == 1 else mask).astype("<u8", copy=False)
    flat = np.unpackbits(words.view(np.uint8), axis=1, bitorder="little")
    return flat[:, :n].astype(bool)


def _completion(usable: np.ndarray, start: int, end: int, pred: np.ndarray | None = None) -> _Bound:
    """``g`` on the reduced costs of the assignment prices (:func:`assignment_potentials`).

    The bound on the plain costs (zero prices) is valid too, but on ESC47, ft53.4 and
    ry48p.4 it pruned under 0.3 % more states than this one alone, at twice the time.
    """
    return _Bound(usable, start, end, assignment_potentials(usable, start, end), pred)


#: The last few assignment prices, by a digest of their data: a portfolio run builds the
#: same search up to six times (beam passes, both directions, two stages), 0.4 s of LP each
#: on 150 nodes.
_PRICES: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}


def assignment_potentials(
    usable: np.ndarray, start: int, end: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_assignment_potentials`, remembered for the last few inputs."""
    import hashlib

    key = hashlib.blake2b(
        np.ascontiguousarray(usable).tobytes() + np.array([start, end]).tobytes()
    ).digest()
    if key not in _PRICES:
        if len(_PRICES) >= 8:
            _PRICES.pop(next(iter(_PRICES)))
        fast = None
        if ideals.is_wide(usable.shape[0]):  # the LP took 19 s on 300 nodes (90,000 arcs)
            fast = _matching_potentials(usable, start, end)
        _PRICES[key] = fast if fast is not None else _assignment_potentials(usable, start, end)
    alpha, beta = _PRICES[key]
    return alpha.copy(), beta.copy()


def _matching_potentials(
    usable: np.ndarray, start: int, end: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """Optimal prices of the same assignment LP from an optimal matching, without an LP.

    With the optimal assignment ``a`` (:func:`scipy.optimize.linear_sum_assignment`), the
    prices with ``alpha_i + beta_a(i) = c[i, a(i)]`` and ``alpha_i + beta_j <= c[i, j]`` are
    ``beta`` = shortest distances in the graph of arcs ``a(i) -> j`` of length
    ``c[i, j] - c[i, a(i)]`` (no negative cycle, the assignment being optimal), ``alpha_i =
    c[i, a(i)] - beta_a(i)``: milliseconds where HiGHS's LP took seconds. Used beyond 64
    nodes (up to 64 the LP's prices are kept, so the DP's search is unchanged there). None
    when no assignment uses usable arcs only (the caller falls back to the LP).
    """
    from scipy.optimize import linear_sum_assignment
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import NegativeCycleError, shortest_path

    n = usable.shape[0]
    rows = np.array([v for v in range(n) if v != end])
    cols = np.array([v for v in range(n) if v != start])
    sub = usable[np.ix_(rows, cols)]
    finite = np.isfinite(sub)
    if not finite.any(axis=1).all() or not finite.any(axis=0).all():
        return None
    big = 1.0 + 2.0 * n * float(np.abs(sub[finite]).max(initial=0.0))
    r_idx, c_idx = linear_sum_assignment(np.where(finite, sub, big))
    if not finite[r_idx, c_idx].all():
        return None
    match = np.empty(len(rows), dtype=np.int64)
    match[r_idx] = c_idx  # row i -> column match[i]
    matched_cost = sub[np.arange(len(rows)), match]
    i_idx, j_idx = np.nonzero(finite)
    # edge match[i] -> j of length c[i, j] - c[i, match[i]]; a source 0 to every column
    m = len(cols)
    lengths = sub[i_idx, j_idx] - matched_cost[i_idx]
    tails = np.concatenate([match[i_idx] + 1, np.zeros(m, dtype=np.int64)])
    heads = np.concatenate([j_idx + 1, np.arange(1, m + 1)])
    weights = np.concatenate([lengths, np.zeros(m)])
    keep = tails != heads  # the matched arc itself is a self-loop of length 0
    # csgraph drops explicit zeros: a zero length becomes the smallest positive float (an
    # error of at most m * 2e-308, absorbed by the lowering of beta below)
    weights = np.where(weights == 0.0, np.finfo(float).tiny, weights)
    graph = csr_matrix((weights[keep], (tails[keep], heads[keep])), shape=(m + 1, m + 1))
    try:
        dist = shortest_path(graph, method="BF", directed=True, indices=0)
    except NegativeCycleError:
        return None
    beta_cols = np.minimum(dist[1:], 0.0)
    if not np.isfinite(beta_cols).all():
        return None
    alpha, beta = np.zeros(n), np.zeros(n)
    beta[cols] = beta_cols
    alpha[rows] = matched_cost - beta_cols[match]
    # exactness as the LP's prices: every reduced cost >= 0 (tolerance lowered into beta)
    reduced = usable - alpha[:, None] - beta[None, :]
    lowest = np.min(np.where(np.isfinite(reduced), reduced, np.inf), axis=0)
    beta += np.minimum(np.where(np.isfinite(lowest), lowest, 0.0), 0.0)
    return alpha, beta


def _assignment_potentials(
    usable: np.ndarray, start: int, end: int
) -> tuple[np.ndarray, np.ndarray]:
    """Dual prices ``(alpha, beta)`` of the assignment LP on the usable arcs.

    The LP ``min Σ c x`` with every node but ``end`` left once (price ``alpha_u``) and every
    node but ``start`` entered once (price ``beta_w``), solved by HiGHS through
    :func:`scipy.optimize.linprog`. Any prices give valid bounds (see the module
    docstring); these make the reduced costs ``c - alpha_u - beta_w`` non-negative and
    their sum the assignment bound; ``beta`` is then lowered by any negative reduced cost
    left by the LP's tolerance, so every reduced cost is >= 0 exactly (which lets
    ``f + P`` alone prune). Without an LP solution the prices start from zero (and are
    lowered the same way, which matters only for negative costs).
    """
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix, vstack

    n = usable.shape[0]
    tails, heads = np.nonzero(np.isfinite(usable))
    alpha, beta = np.zeros(n), np.zeros(n)
    rows_out = np.array([v for v in range(n) if v != end])
    rows_in = np.array([v for v in range(n) if v != start])
    if len(tails) == 0:
        return alpha, beta
    arcs = np.arange(len(tails))
    out_row = np.searchsorted(rows_out, tails)
    in_row = np.searchsorted(rows_in, heads)
    keep_out = tails != end
    keep_in = heads != start
    a_out = csr_matrix(
        (np.ones(keep_out.sum()), (out_row[keep_out], arcs[keep_out])),
        shape=(len(rows_out), len(tails)),
    )
    a_in = csr_matrix(
        (np.ones(keep_in.sum()), (in_row[keep_in], arcs[keep_in])),
        shape=(len(rows_in), len(tails)),
    )
    result = linprog(
        usable[tails, heads],
        A_eq=vstack([a_out, a_in]).tocsr(),
        b_eq=np.ones(len(rows_out) + len(rows_in)),
        bounds=(0, None),
        method="highs",
    )
    if result.status == 0:
        prices = np.asarray(result.eqlin.marginals, dtype=float)
        if np.isfinite(prices).all():
            alpha[rows_out] = prices[: len(rows_out)]
            beta[rows_in] = prices[len(rows_out) :]
    # lower beta so that every reduced cost is >= 0 exactly (the LP's are, up to tolerance)
    reduced = usable - alpha[:, None] - beta[None, :]
    lowest = np.min(np.where(np.isfinite(reduced), reduced, np.inf), axis=0)
    beta += np.minimum(np.where(np.isfinite(lowest), lowest, 0.0), 0.0)
    return alpha, beta


def completion_bound(problem: SopProblem, visited: set[int], last: int) -> float:
    """The completion bound ``g(I, v)`` of one state (see the module docstring).

    Parameters
    ----------
    problem : SopProblem
    visited : set of int
        The ideal ``I`` (contains ``start`` and ``last``).
    last : int

    Returns
    -------
    float
        A lower bound on the cheapest path ``last -> (every node not in I) -> end``
        respecting the precedences; ``inf`` when the bound sees that none exists.
    """

    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full((problem.n, problem.n), np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    bound = _completion(usable, problem.start, problem.end, _predecessor_masks(problem))
    mask = np.array([ideals.from_int(sum(1 << v for v in visited), problem.n)], dtype=np.uint64)
    return float(bound(mask, np.array([last]))[0])


def _incumbent(problem: SopProblem, incumbent: Any) -> tuple[float, list[int]] | None:
    from taopt.models.sop import _known_order

    return _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)


class _Search:
    """The DP's data and one layer step, shared by the exact run and the beam pass."""

    def __init__(self, problem: SopProblem) -> None:

        n = problem.n
        tails, heads = usable_arcs(problem.cost, problem.closure)
        self.usable = np.full((n, n), np.inf)
        self.usable[tails, heads] = problem.cost[tails, heads]
        self.pred = _predecessor_masks(problem)
        self.bits = node_bits(n)
        self.bound = _completion(self.usable, problem.start, problem.end, self.pred)
        self.more_bounds: list[_Bound] = []  # the same bound on other prices (max taken)
        #: The position-window completion bound (``window=`` of :func:`solve_sop_dp`), first.
        self.window: WindowCompletion | None = None
        self.trial: dict[int, list[int]] = {}  # per extra bound: states evaluated, pruned
        self.problem = problem
        #: Seconds per extension merged (sorted and deduplicated), the slowest seen.
        self.merge_rate = MERGE_SECONDS
        #: Seconds per state, node and word of the completion bound, the last measured.
        self.bound_rate = BOUND_SECONDS
        self.merge_refused = False

    def first(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        start = self.problem.start
        return (
            np.array([self.bits[start]], dtype=np.uint64),  # (1,) or (1, W)
            np.array([start], dtype=np.int64),
            np.zeros(1),
            np.array([-1], dtype=np.int64),
        )

    def grow(
        self,
        mask: np.ndarray,
        last: np.ndarray,
        value: np.ndarray,
        deadline: Deadline,
        limit: float = np.inf,
    ) -> tuple[np.ndarray, ...] | None:
        """Every one-node extension of the layer, the cheapest per (ideal, last), in the order
        of the states (by mask, then last node); None when the deadline passed first, the
        merge could not end in time, or the extensions before merging passed ``limit``.

        The extensions by one node ``w`` are merged as they are made: two extensions
        ``(I ∪ {w}, w)`` and ``(I' ∪ {w}, w)`` with ``w`` in neither ideal are the same state
        only when ``I = I'``, so states made by different nodes never coincide and each
        node's block is reduced to its distinct states at once (:func:`_cheapest_per_state`
        on the block). Only the merged blocks are kept (a few states per ideal instead of
        every extension: ry48p.1's last layer of a 10 s run held 2.7 million extensions,
        180 MB, before its merge), then one sort puts them in order. The same states and
        parents as one merge of all the extensions: within a block the parents keep their
        order, and no state is in two blocks.
        """
        bits, pred, usable = self.bits, self.pred, self.usable
        n = self.problem.n
        new_mask, new_last, new_value, new_parent = [], [], [], []
        count = merged = 0
        index = np.arange(len(mask))
        left = deadline.remaining()
        ends = None if left is None else time.perf_counter() + left - MARGIN
        # a node every mask holds, or one with a predecessor no mask holds, extends none
        held_by_all = _members(np.bitwise_and.reduce(mask, axis=0)[None], n)[0]
        held_by_some = _members(np.bitwise_or.reduce(mask, axis=0)[None], n)[0]
        in_order = _in_mask_order(mask)  # every layer of the exact run; not a beam's
        for w in range(n):
            if w == self.problem.start or held_by_all[w]:
                continue
            if not held_by_some[self.bound.pred_nodes[w]].all():
                continue
            if deadline.expired(MARGIN):
                return None
            ok = ~has(mask, w) & holds(mask, pred[w])
            if not ok.any():
                continue
            step = usable[last[ok], w]
            finite = np.isfinite(step)
            if not finite.any():
                continue
            chosen = index[ok][finite]
            del ok
            count += len(chosen)
            if count > limit:
                return None
            block = mask[chosen] | bits[w]
            block_value = value[chosen] + step[finite]
            del step, finite
            ours = _cheapest_per_block(block, block_value, in_order, n, w)
            new_mask.append(block[ours])
            new_last.append(np.full(len(ours), w, dtype=np.int64))
            new_value.append(block_value[ours])
            new_parent.append(chosen[ours])
            merged += len(ours)
            del block, block_value, chosen, ours
            # the final sort cannot be interrupted: stop as soon as it cannot end in time
            # (at the slowest rate seen so far; millions of states take seconds on a loaded
            # core), before more extensions are made for nothing
            if ends is not None and merged * self.merge_rate > ends - time.perf_counter():
                self.merge_refused = True  # out of time, not of states
                return None
        if not new_mask:
            empty = np.zeros(0)
            return (mask[:0], empty.astype(np.int64), empty, empty.astype(np.int64))
        began = time.perf_counter()
        c_mask = np.concatenate(new_mask)
        del new_mask
        c_last = np.concatenate(new_last)
        del new_last
        # no two states are equal now: this sort only orders them (by mask, then last)
        order = _state_order(c_mask, c_last, n)
        c_mask, c_last = c_mask[order], c_last[order]
        c_value = np.concatenate(new_value)[order]
        del new_value
        c_parent = np.concatenate(new_parent)[order]
        if merged >= 10_000:  # the final sort, per state
            self.merge_rate = max(self.merge_rate, (time.perf_counter() - began) / merged)
        return c_mask, c_last, c_value, c_parent

    def totals(
        self,
        mask: np.ndarray,
        last: np.ndarray,
        value: np.ndarray,
        deadline: Deadline,
        cutoff: float = np.inf,
        chunk: int | None = None,
    ) -> np.ndarray | None:
        """``f + g`` per state, in chunks between deadline checks; None when it passed.

        A state whose ``f + P`` already reaches ``cutoff`` gets that (smaller, valid) value:
        it is pruned anyway, so ``max(in', out')`` is not computed for it (the reduced costs
        are non-negative, :func:`assignment_potentials`).
        """
        words = self.bits.shape[1] if self.bits.ndim == 2 else 1
        unit = self.problem.n * words  # the work of one state
        best = None
        if self.window is not None:  # O(words) per state: first, the others where it fails
            best = value + self.window(mask, last)
        for bound in [self.bound, *self.more_bounds]:
            out = value + bound.potential(mask, last)
            if best is not None:  # a second price set: only where the first did not prune
                out = np.maximum(out, best)
            need = np.flatnonzero(out < cutoff)
            lo = 0
            while lo < len(need):
                if deadline.expired(MARGIN):
                    return None
                # a chunk takes about CHUNK_SECONDS at the rate last measured (the load
                # changes it: 37,000 states on 54 nodes took 4.8 s at load 16), and never
                # more than the time left, so the deadline is looked at in time
                size = chunk or max(1_000, int(CHUNK_SECONDS / (self.bound_rate * unit)))
                # and at most BOUND_ENTRIES (state, node) pairs: the bound's work arrays are
                # a few ``states x nodes`` tables of floats (``_Bound._per_ideal_band``)
                size = min(size, max(100, BOUND_ENTRIES // self.problem.n))
                left = deadline.remaining()
                if left is not None:
                    fits = int((left - MARGIN) / (self.bound_rate * unit))
                    if fits < min(size, len(need) - lo, 100):
                        return None  # not even a small chunk ends in time
                    size = min(size, max(fits, 100))
                part = need[lo : lo + size]
                began = time.perf_counter()
                out[part] = np.maximum(out[part], value[part] + bound(mask[part], last[part]))
                if len(part) >= 500:
                    self.bound_rate = (time.perf_counter() - began) / (len(part) * unit)
                lo += len(part)
            if bound is not self.bound:
                self._judge(bound, len(need), int((out[need] >= cutoff).sum()))
            best = out
        return best

    def _judge(self, bound: _Bound, evaluated: int, pruned: int) -> None:
        """Drop a second price set that prunes under :data:`SECOND_PRICES_MIN_SHARE` of the
        states it was evaluated on, once it has seen :data:`SECOND_PRICES_TRIAL` states."""
        seen = self.trial.setdefault(id(bound), [0, 0])
        seen[0] += evaluated
        seen[1] += pruned
        if seen[0] >= SECOND_PRICES_TRIAL and seen[1] < SECOND_PRICES_MIN_SHARE * seen[0]:
            self.more_bounds = [b for b in self.more_bounds if b is not bound]

    def path(self, layers: Sequence[tuple[np.ndarray, ...]], k: int, top: int = -1) -> list[int]:
        """The path ending at state ``k`` of layer ``top`` (the last), by the parents."""
        top = top % len(layers)
        path = [int(layers[top][1][k])]
        at = int(layers[top][3][k])
        for level in range(top - 1, -1, -1):
            path.append(int(layers[level][1][at]))
            at = int(layers[level][3][at])
        path.reverse()
        return path


def reversed_problem(problem: SopProblem) -> SopProblem:
    """The same SOP read backwards: transposed costs, reversed precedences, ``end`` first.

    A path of it reversed is a path of ``problem`` of the same cost (and conversely), so
    the DP over its ideals (the *filters* of ``problem``) is the backward DP.
    """
    return SopProblem(
        np.ascontiguousarray(problem.cost.T),
        tuple((j, r) for r, j in problem.precedences),
        problem.end,
        problem.start,
        problem.name,
    )


@dataclass(frozen=True)
class RowCredit:
    """An LP's prices for the prefix bound with row credit (module docstring, "Row credit").

    Attributes
    ----------
    constant : float
        ``y^T b`` (the rows' sides times their sign-clipped duals), plus ``d`` of the arcs of
        negative ``d`` not in ``negative`` (counted as usable by every rest).
    reduced : ndarray
        ``n x n`` signed reduced costs ``d = c - A^T y`` of the usable arcs (``inf`` elsewhere).
    bits : ndarray
        ``n x n`` ``uint64``: bit ``r`` of arc ``(u, w)`` is set when the arc is in priced row
        ``r`` (a row ``Σ_{a ∈ C_r} x_a >= 1`` with dual ``weights[r] > 0``).
    weights : ndarray
        The priced rows' duals (64 at most).
    negative : (ndarray, ndarray, ndarray)
        Tails, heads and ``d`` of the arcs with ``d < 0``.
    """

    constant: float
    reduced: np.ndarray
    bits: np.ndarray
    weights: np.ndarray
    negative: tuple[np.ndarray, np.ndarray, np.ndarray]

    def transposed(self) -> RowCredit:
        """The same prices read backwards (:func:`~taopt.models.sop_dp.reversed_problem`: arcs
        reversed)."""
        tails, heads, values = self.negative
        return RowCredit(
            self.constant,
            np.ascontiguousarray(self.reduced.T),
            np.ascontiguousarray(self.bits.T),
            self.weights,
            (heads, tails, values),
        )

    def byte_sums(self) -> np.ndarray:
        """``(8, 256)``: ``[k, b]`` the sum of the weights of the rows whose bits in byte ``k``
        of a mask are set in ``b`` (a weighted popcount by table look-ups)."""
        weights = np.zeros(64)
        weights[: len(self.weights)] = self.weights
        byte = np.arange(256)
        table = np.zeros((8, 256))
        for k in range(8):
            for bit in range(8):
                table[k] += np.where((byte >> bit) & 1, weights[8 * k + bit], 0.0)
        return table


def _weighted(table: np.ndarray, masks: np.ndarray) -> np.ndarray:
    """Per ``uint64`` mask, the sum of the weights of its bits
    (:meth:`~taopt.models.sop_dp.RowCredit.byte_sums`)."""
    total = np.zeros(len(masks))
    for k in range(8):
        total += table[k][((masks >> np.uint64(8 * k)) & np.uint64(255)).astype(np.intp)]
    return total


class _Run:
    """One direction of the exact DP, advanced one layer per :meth:`step`.

    ``lagrange``: ``(L, d, step)`` of the module docstring's LP bound, ``d`` an ``n x n``
    matrix of ``max(d_a, 0)`` read in this direction (transposed for the backward run).
    """

    def __init__(
        self,
        problem: SopProblem,
        reverse: bool,
        lagrange: tuple[float, np.ndarray, float] | None = None,
        credit: RowCredit | None = None,
        remainder: bool = False,
        state_lp: StateLp | None = None,
        window: np.ndarray | None = None,
    ) -> None:
        self.reverse = reverse
        #: The root's LP re-solved per state (``state_lp=`` of :func:`solve_sop_dp`).
        self.state_lp = state_lp
        #: States dropped by it.
        self.lp_pruned = 0
        #: Per layer, the restricted-LP prices each state inherits (an index into
        #: :attr:`prices`, -1: none) and the bound they give it (:meth:`_inherited`).
        self.lp_sets: list[np.ndarray] = [np.full(1, -1, dtype=np.int64)]
        self.lp_low: list[np.ndarray] = [np.full(1, -np.inf)]
        #: ``max(d, 0)`` of the restricted LPs solved whose prices some kept state uses.
        self.prices: dict[int, np.ndarray] = {}
        #: The optimal basis of each of those LPs (each descendant's LP starts from it).
        self.bases: dict[int, Any] = {}
        self._next_prices = 0
        self._pending: list[np.ndarray] = []
        #: Every order's cost is a multiple of this (0: not integral), for rounding bounds up.
        self._unit = _cost_unit(problem) if state_lp is not None else 0.0
        self.lagrange = lagrange
        #: The row-credit prices read in this direction, and their byte tables.
        self.credit = credit
        self._table = None if credit is None else credit.byte_sums()
        #: Per layer, the priced rows each state's kept prefix has crossed (with ``credit``).
        self.crossed: list[np.ndarray] = [np.zeros(1, dtype=np.uint64)]
        #: Per layer, the reduced cost ``Σ max(d_a, 0)`` of each state's kept prefix.
        self.reduced: list[np.ndarray] = [np.zeros(1)]
        #: States dropped by the LP bound alone (``f + g`` not evaluated).
        self.lagrange_pruned = 0
        #: ``g`` of the module docstring on the reduced costs ``max(d, 0)`` of the usable arcs
        #: (a completion bound on any costs): the rest of the path adds at least that.
        self.lagrange_rest: _Bound | None = None
        self.n = problem.n
        self.search = _Search(problem)
        if window is not None:
            self.search.window = WindowCompletion(problem, window, self.search.usable)
        #: The remainder's assignment per ideal (``remainder=`` of :func:`solve_sop_dp`).
        self.remainder: RemainderBound | None = None
        if remainder:
            self.remainder = RemainderBound(self.search.usable, problem.end)
        #: States dropped by that bound.
        self.remainder_pruned = 0
        mask, last, value, parent = self.search.first()
        self.layers: list[tuple[np.ndarray, ...]] = [
            (mask, last, value, parent)
        ]  # layer k: (mask, last, value, parent)
        if lagrange is not None and LAGRANGE_REST:
            search = self.search
            rest = np.where(np.isfinite(search.usable), lagrange[1], np.inf)
            self.lagrange_rest = _completion(rest, problem.start, problem.end, search.pred)
        # one layer of one state: never stopped (a token of its own, not the run's: a run
        # cancelled meanwhile, e.g. by CP-SAT's proof beside the portfolio, stops at the
        # DP's next loop head instead)
        total = self.search.totals(mask, last, value, Deadline(None, cancel=CancelToken()))
        assert total is not None
        self.layer_total = total
        self.pruned_min = np.inf
        self.pruned = 0
        self.kept = 1
        self.peak = 1
        self.finished = False
        self.best_cost = np.inf
        self.best_path: list[int] | None = None

    def _drop_priced(
        self,
        grown: tuple[np.ndarray, ...],
        reduced: np.ndarray,
        low: np.ndarray,
        below: float,
        crossed: np.ndarray | None = None,
    ) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray, np.ndarray | None]:
        """Keep the grown states whose LP bound ``low`` is below ``below`` (counted as pruned,
        by the LP bound, otherwise)."""
        fits = low < below
        if fits.all():
            return grown, reduced, low, crossed
        dropped = int((~fits).sum())
        self.pruned += dropped
        self.lagrange_pruned += dropped
        self.pruned_min = min(self.pruned_min, float(low[~fits].min()))
        kept = None if crossed is None else crossed[fits]
        return tuple(a[fits] for a in grown), reduced[fits], low[fits], kept

    def _credited(
        self, grown: tuple[np.ndarray, ...], unit: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(reduced, crossed, low)`` of the grown states by the row-credit bound: the kept
        prefix's signed reduced cost plus the credit of its repeated crossings of priced rows,
        its rows crossed, and the bound ``y^T b + that + Σ d_a`` over the negative arcs the
        rest can still use (tail not yet visited or the last node, head not yet visited)."""
        credit, table = self.credit, self._table
        assert credit is not None and table is not None
        parent, mask, last = grown[3], grown[0], grown[1]
        before = self.layers[-1][1][parent]
        was = self.crossed[-1][parent]
        arc_bits = credit.bits[before, last]
        reduced = (
            self.reduced[-1][parent]
            + credit.reduced[before, last]
            + _weighted(table, was & arc_bits)
        )
        crossed = was | arc_bits
        rest = np.zeros(len(last))
        for tail, head, value in zip(*credit.negative, strict=True):
            usable = ~has(mask, int(head)) & (~has(mask, int(tail)) | (last == tail))
            rest += np.where(usable, value, 0.0)
        low = _rounded_up(credit.constant + reduced + rest, unit)
        return reduced, crossed, low

    def _reoptimised(
        self,
        grown: tuple[np.ndarray, ...],
        total: np.ndarray,
        reduced: np.ndarray | None,
        crossed: np.ndarray | None,
        below: float,
        deadline: Deadline,
    ) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray | None, np.ndarray | None]:
        """Drop the states whose bound by the restricted LP
        (:class:`~taopt.models.sop_statelp.StateLp`: its own, or an ancestor's prices along the
        kept prefix, :meth:`_inherited`) or by the remainder's assignment
        (:class:`~taopt.models.sop_remainder.RemainderBound`) reaches ``below``; the kept
        states' bounds raised to them."""
        extra: list[np.ndarray] = []
        if self.state_lp is not None:
            sets, low = self._inherited(grown)
            extra = [sets, low]
            grown, total, reduced, crossed, extra, dropped = self._tighten(
                grown, total, _rounded_up(low, self._unit), reduced, crossed, below, extra
            )
            self.lp_pruned += dropped
        if self.state_lp is not None and self.state_lp.usable() and len(grown[0]):
            members = _members(grown[0], self.n)
            sets, low = extra
            starts = [self.bases.get(int(key)) for key in sets]
            bound, prices = self.state_lp.layer(
                members, grown[1], total, below, self.reverse, deadline, starts
            )
            for k, (own, positive, basis) in prices.items():  # the state's own prices from now
                path = self.search.path([*self.layers, grown], k)
                key = self._next_prices
                self._next_prices += 1
                self.prices[key] = positive
                if basis is not None:
                    self.bases[key] = basis
                sets[k] = key
                low[k] = own + float(positive[path[:-1], path[1:]].sum())
            bound = np.maximum(bound, _rounded_up(low, self._unit))
            grown, total, reduced, crossed, extra, dropped = self._tighten(
                grown, total, bound, reduced, crossed, below, extra
            )
            self.lp_pruned += dropped
        if self.remainder is not None and len(grown[0]):
            mask, last, value = grown[0], grown[1], grown[2]
            group, unique = _groups(mask)
            members = _members(unique, self.n)
            bound = self.remainder.layer(members, group, last, value, total, below, deadline)
            grown, total, reduced, crossed, extra, dropped = self._tighten(
                grown, total, bound, reduced, crossed, below, extra
            )
            self.remainder_pruned += dropped
        self._pending = extra
        return grown, total, reduced, crossed

    def _inherited(self, grown: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
        """Per grown state, the restricted-LP prices it inherits from its kept parent (an index
        into :attr:`prices`, -1: none) and the bound they give: ``B + Σ max(d_a, 0)`` over its
        kept prefix, ``B`` the Lagrangian bound of the LP solved at an ancestor state (valid
        for the descendant's own restricted LP: its fixed arcs hold the ancestor's, and any
        sign-clipped duals bound an LP; the kept prefix's arcs are in every order it stands
        for, :mod:`taopt.models.sop_statelp`). ``-inf`` without prices."""
        parent, last = grown[3], grown[1]
        sets = self.lp_sets[-1][parent]
        low = self.lp_low[-1][parent].copy()
        have = sets >= 0
        if have.any():
            before = self.layers[-1][1][parent]
            order = np.flatnonzero(have)
            order = order[np.argsort(sets[order], kind="stable")]
            keys, starts = np.unique(sets[order], return_index=True)
            ends = np.append(starts[1:], len(order))
            for key, lo, hi in zip(keys, starts, ends, strict=True):  # one price set at a time
                at = order[lo:hi]
                low[at] += self.prices[int(key)][before[at], last[at]]
        return sets.copy(), low

    def _tighten(
        self,
        grown: tuple[np.ndarray, ...],
        total: np.ndarray,
        bound: np.ndarray,
        reduced: np.ndarray | None,
        crossed: np.ndarray | None,
        below: float,
        extra: list[np.ndarray],
    ) -> tuple[
        tuple[np.ndarray, ...],
        np.ndarray,
        np.ndarray | None,
        np.ndarray | None,
        list[np.ndarray],
        int,
    ]:
        """The states whose ``max(total, bound)`` is below ``below``, that bound, the per-state
        arrays filtered alike, and how many were dropped (counted as pruned)."""
        total = np.maximum(total, bound)
        fits = total < below
        if fits.all():
            return grown, total, reduced, crossed, extra, 0
        dropped = int((~fits).sum())
        self.pruned += dropped
        self.pruned_min = min(self.pruned_min, float(total[~fits].min()))
        return (
            tuple(a[fits] for a in grown),
            total[fits],
            None if reduced is None else reduced[fits],
            None if crossed is None else crossed[fits],
            [a[fits] for a in extra],
            dropped,
        )

    def step(
        self, upper: float, tolerance: float, deadline: Deadline, limit: float, room: int | None
    ) -> str | None:
        """Expand one layer; the reason to stop ("time_limit", "max_states") or None."""
        mask, last, value, _ = self.layers[-1]
        self._pending = []
        grown = self.search.grow(mask, last, value, deadline, limit)
        if grown is None:
            out_of_time = deadline.expired(MARGIN) or self.search.merge_refused
            return "time_limit" if out_of_time else "max_states"
        reduced = low = crossed = None
        if self.credit is not None and self.lagrange is not None:  # the bound with row credit
            reduced, crossed, low = self._credited(grown, self.lagrange[2])
            grown, reduced, low, crossed = self._drop_priced(
                grown, reduced, low, upper - tolerance, crossed
            )
        elif self.lagrange is not None:  # the LP bound first: it is one addition per state
            constant, matrix, unit = self.lagrange
            parent = grown[3]
            reduced = self.reduced[-1][parent] + matrix[self.layers[-1][1][parent], grown[1]]
            low = _rounded_up(constant + reduced, unit)
            grown, reduced, low, _ = self._drop_priced(grown, reduced, low, upper - tolerance)
            if self.lagrange_rest is not None and len(low):
                rest = np.empty(len(low))
                for lo in range(0, len(low), LAGRANGE_CHUNK):  # the deadline between chunks
                    if deadline.expired(MARGIN):
                        return "time_limit"
                    part = slice(lo, lo + LAGRANGE_CHUNK)
                    rest[part] = self.lagrange_rest(grown[0][part], grown[1][part])
                low = np.maximum(low, _rounded_up(constant + reduced + rest, unit))
                grown, reduced, low, _ = self._drop_priced(grown, reduced, low, upper - tolerance)
        # drop the states whose value plus completion bound cannot beat the incumbent
        # (with no incumbent: those the bound sees cannot be completed, g = inf)
        total = self.search.totals(grown[0], grown[1], grown[2], deadline, cutoff=upper - tolerance)
        if total is None:
            return "time_limit"
        if low is not None:
            total = np.maximum(total, low)
        keep = total < upper - tolerance
        if not keep.all():
            self.pruned += int((~keep).sum())
            self.pruned_min = min(self.pruned_min, float(total[~keep].min()))
            grown = tuple(a[keep] for a in grown)
            if reduced is not None:
                reduced = reduced[keep]
            if crossed is not None:
                crossed = crossed[keep]
        kept_total = total[keep]
        tighter = self.remainder is not None or self.state_lp is not None
        if tighter and np.isfinite(upper) and len(grown[0]):
            grown, kept_total, reduced, crossed = self._reoptimised(
                grown, kept_total, reduced, crossed, upper - tolerance, deadline
            )
        if room is not None and len(grown[0]) > room:
            return "max_states"  # the previous layer stays the open one
        if reduced is not None:
            self.reduced.append(reduced)
        if crossed is not None:
            self.crossed.append(crossed)
        self.layers.append(grown)
        self.layer_total = kept_total
        if self.state_lp is not None:
            sets, low = self._pending if self._pending else self._inherited(grown)
            self.lp_sets.append(sets)
            self.lp_low.append(low)
            used = set(np.unique(sets[sets >= 0]).tolist())
            self.prices = {k: v for k, v in self.prices.items() if k in used}
            self.bases = {k: v for k, v in self.bases.items() if k in used}
        self.kept += len(grown[0])
        self.peak = max(self.peak, len(grown[0]))
        if len(grown[0]) == 0 or len(self.layers) == self.n:
            self.finished = True
            if len(self.layers) == self.n and len(grown[0]) > 0:
                # the last layer is (V, end): a path cheaper than the incumbent
                path = self.search.path(self.layers, int(np.argmin(grown[2])))
                if self.reverse:
                    path.reverse()
                self.best_path = path
                self.best_cost = float(np.min(grown[2]))
        return None

    def proven(self) -> float:
        """The bound this direction proves while unfinished: every cheaper path is in the
        open layer or among the dropped states."""
        open_min = float(self.layer_total.min()) if len(self.layer_total) else np.inf
        return min(open_min, self.pruned_min)


def _rounded_up(values: np.ndarray, unit: float) -> np.ndarray:
    """``values`` raised to the next multiple of ``unit`` (1e-6 tolerance; unchanged when
    ``unit`` is 0): every order's cost is a multiple of the costs' gcd."""
    if not unit:
        return values
    return unit * np.ceil((values - 1e-6) / unit)


def _join(forward: _Run, backward: _Run, cost: np.ndarray) -> tuple[float, list[int]] | None:
    """Meet in the middle: the cheapest path through a forward state ``(I, v)`` of the
    forward's last layer, an arc ``v -> w`` and a backward state ``(V \\ I, w)``.

    Returns ``(cost, path)`` or None (no pair joins). Every path cheaper than the
    incumbent crosses both layers unpruned, so it is among the pairs.
    """
    n = forward.n
    top = len(forward.layers) - 1
    other = n - 2 - top  # the backward layer with the complementary sets
    f_mask, f_last, f_value, _ = forward.layers[top]
    b_mask, b_first, b_value, _ = backward.layers[other]
    b_keys = row_keys(b_mask)
    order = np.argsort(b_keys, kind="stable")
    sorted_mask = b_keys[order]
    wanted = row_keys(~f_mask & ideals.full(n))
    lo = np.searchsorted(sorted_mask, wanted, side="left")
    hi = np.searchsorted(sorted_mask, wanted, side="right")
    counts = hi - lo
    if counts.sum() == 0:
        return None
    left = np.repeat(np.arange(len(f_mask)), counts)
    offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    right = order[np.repeat(lo, counts) + offsets]
    total = f_value[left] + forward.search.usable[f_last[left], b_first[right]] + b_value[right]
    best = int(np.argmin(total))
    if not np.isfinite(total[best]):
        return None
    head = forward.search.path(forward.layers, int(left[best]), top)
    tail = backward.search.path(backward.layers, int(right[best]), other)
    path = head + tail[::-1]
    return path_cost(cost, path), path


def beam_order(
    problem: SopProblem, width: int = 2000, time_limit: float | None = None
) -> tuple[float, list[int]] | None:
    """A feasible order by beam search over the DP's states (a heuristic incumbent).

    The layers of :func:`solve_sop_dp`, each cut to the ``width`` states of smallest
    value plus completion bound. Returns ``(cost, order)`` or None (no path kept, or the
    time limit passed). Deterministic; ``O(width · n^2 log n)``.
    """
    deadline = Deadline(time_limit)
    search = _Search(problem)
    mask, last, value, parent = search.first()
    layers = [(mask, last, value, parent)]
    for _size in range(1, problem.n):
        grown = search.grow(mask, last, value, deadline)
        if grown is None or len(grown[0]) == 0:
            return None
        total = None
        if len(grown[0]) > 4 * width:  # bound only the cheapest prefixes of the layer
            cheapest = np.argsort(grown[2], kind="stable")[: 4 * width]
            grown = tuple(a[cheapest] for a in grown)
            # bounded in the layer's order (by mask: the states of one ideal side by side
            # share its sums, _Bound.extra), then put back in the order of their values
            by_mask = np.argsort(cheapest)
            part = search.totals(grown[0][by_mask], grown[1][by_mask], grown[2][by_mask], deadline)
            if part is not None:
                total = np.empty(len(part))
                total[by_mask] = part
        else:
            total = search.totals(grown[0], grown[1], grown[2], deadline)
        if total is None:
            return None
        alive = np.flatnonzero(np.isfinite(total))
        if len(alive) > width:
            alive = alive[np.argsort(total[alive], kind="stable")[:width]]
        mask, last, value, parent = (a[alive] for a in grown)
        layers.append((mask, last, value, parent))
        if len(mask) == 0:
            return None
    path = search.path(layers, int(np.argmin(value)))
    return path_cost(problem.cost, path), path


def solve_sop_dp(
    problem: SopProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    cheap_bound: float | None = None,
    max_states: int | None = None,
    beam_width: int = 1024,
    both: bool = True,
    both_prices: bool = BOTH_PRICES,
    lagrange: tuple[float, np.ndarray] | None = None,
    credit: RowCredit | None = None,
    watch: Callable[[Sequence[_Run]], None] | None = None,
    remainder: bool | None = None,
    state_lp: StateLp | None = None,
    cutoff: float | None = None,
    give_up: bool = False,
    window: np.ndarray | None = None,
) -> Solution:
    """Exact SOP by dynamic programming over (order ideal, last node), with pruning.

    Parameters
    ----------
    problem : SopProblem
        Any number of nodes (masks of several words beyond 64).
    time_limit : float, optional
        Wall-clock seconds; on the limit the incumbent (or no path, objective ``inf``) is
        returned with status "time_limit" and the proven bound of the module docstring.
    incumbent : Order, list of int or Solution, optional
        A feasible order (NIA/MMA/SMMA's best through the registry's warm start): its
        cost prunes; it is returned when nothing cheaper exists. An infeasible one is
        ignored.
    cheap_bound : float, optional
        A valid lower bound computed elsewhere (the portfolio's assignment/arborescence
        bound); a stopped run never reports less. Computed here when needed and not given.
    max_states : int, optional
        Stop (as on the time limit, ``info["stopped_by"] == "max_states"``) before the
        states kept over all layers would pass this, or one layer's extensions before
        merging and pruning would pass four times this (memory: about 40 bytes a state).
    beam_width : int
        Width of the widest beam pass (:func:`beam_order`), run first to improve the
        incumbent: width :data:`NARROW_BEAM`, :data:`MIDDLE_BEAM`, then ``beam_width``, within
        :data:`BEAM_SHARE` of the time (0: no beam).
    both : bool
        Search forward and backward (:func:`reversed_problem`) and meet in the middle
        (the module docstring); False: forward only.
    both_prices : bool
        With ``both``: each direction's bound is also taken on the other direction's
        assignment prices (transposed; the LP is degenerate, these are other optimal
        prices) and the larger value kept. It certifies rbg050c (2.9 million states,
        36 s) where one price set does not within 10 million, but costs 1.5–1.7 × the
        time on ESC47, ry48p.4 and ft53.4, so it is off by default.
    lagrange : (float, ndarray), optional
        ``(L, d)`` of an LP relaxation's duals (the module docstring's LP bound; ``d`` the
        ``n x n`` reduced costs of the usable arcs,
        :meth:`~taopt.models.sop_cuts.SopCutModel.lagrangian_prices`): a state whose kept
        prefix has ``L + Σ max(d_a, 0) >= UB`` is dropped before its completion bound is
        computed, and ``L`` (rounded up to the costs' gcd) is a proven bound of a stopped
        run. Valid for the orders cheaper than ``UB``, as long as the LP's rows hold for
        them. ``info["lagrange_pruned"]``: the states it dropped.
    credit : RowCredit, optional
        The same LP's prices with its priced rows (with ``lagrange``;
        :meth:`~taopt.models.sop_cuts.SopCutModel.row_credit`): the states are then dropped
        by the bound with row credit of the module docstring instead, never weaker.
    watch : callable, optional
        Called with the directions' runs once before the first layer and after each layer
        kept (the portfolio's memory probe, :class:`taopt.models.sop.LayerWatch`).
    remainder : bool, optional
        Also drop the states that survive the bounds above by ``f`` plus the assignment
        relaxation of the remainder, solved per ideal
        (:class:`~taopt.models.sop_remainder.RemainderBound`); None: :data:`REMAINDER`.
        ``info["remainder_pruned"]``: the states it dropped.
    state_lp : StateLp, optional
        The root cut model's LP, re-solved per state with the state's ideal fixed
        (:class:`~taopt.models.sop_statelp.StateLp`): the states of each layer left by the
        bounds above are bounded by it, highest bound first, while it fits in its share of the
        time. ``info["lp_pruned"]``, ``info["lp_solved"]``: the states it dropped, the LPs.
    cutoff : float, optional
        A trial value below the incumbent's cost: states are dropped when their bound
        reaches it instead (``info["cutoff"]``). Every order is either found or passes
        through a dropped state, so a run that ends proves ``min(found, least dropped)``
        whatever pruned: it finds an order below the cutoff (and proves it optimal), or it
        proves a bound of at least the cutoff (to 1e-9 relative) and returns the incumbent
        with status "time_limit" (stop "solver_limit", ``info["cutoff_proven"]``). A run
        stopped by its limit proves the open layer's bound as always.
    give_up : bool
        With ``state_lp``: stop early ("time_limit", ``info["gave_up"]`` says why) when a
        layer past the first grew more than :data:`GIVE_UP_GROWTH` times the layer before,
        the next layer's LPs are predicted past the time left, or the LPs stopped after their
        trial, so that a caller gives the time to another stage.
    window : ndarray, optional
        Node prices ``lam`` of the position-window relaxation
        (:func:`taopt.models.sop_window.window_prices`): every state's completion is also
        bounded by :class:`~taopt.models.sop_window.WindowCompletion` (``H(k, v) + Σ_{u ∈ U}
        lam_u``, proof in :mod:`taopt.models.sop_window`), the larger bound kept; the backward
        run reads the same prices on the reversed problem. Valid for any prices.

    Returns
    -------
    Solution
        ``order``, ``objective`` (its path cost recomputed from the data), ``status``
        "optimal", "time_limit" or "infeasible", ``bound``; ``info`` has ``states`` (kept
        over all layers, both directions), ``pruned``, ``peak_layer``, ``beam`` (the
        beam's cost when it improved the incumbent), ``direction`` ("both" when the
        directions met, "forward"/"backward" when one finished alone, None when
        stopped) and ``stopped_by``.

    Raises
    ------
    InstanceError
        A non-positive time limit.

    Notes
    -----
    Time ``O(S · n log n)`` and memory ``O(S)`` for ``S`` states kept (both directions),
    at most ``2n ×`` the number of ideals; the bound and the incumbent cut ``S`` by orders of
    magnitude on the TSPLIB instances (``benchmarks/bench_sop.py``).

    Example
    -------
    >>> s = solve_sop_dp(SopProblem.load("ESC07"))
    >>> str(s.status), s.objective, s.order[0], s.order[-1]
    ('optimal', 2125.0, 0, 8)
    """
    from taopt.models.sop import _cheap_bound

    began = time.perf_counter()
    if time_limit is not None and not time_limit > 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    deadline = Deadline(time_limit)
    info: dict[str, Any] = {"beam": None}
    known = _beam_start(problem, _incumbent(problem, incumbent), beam_width, deadline, info)
    best = np.inf if known is None else known[0]  # the incumbent's cost
    upper = best if cutoff is None else min(best, float(cutoff))  # what prunes
    tolerance = PRUNE_TOLERANCE * max(1.0, abs(upper)) if np.isfinite(upper) else 0.0
    if cutoff is not None:
        info["cutoff"] = upper
    setting_up = time.perf_counter()
    oriented = None
    if lagrange is not None:
        constant, reduced = lagrange
        unit = _cost_unit(problem)
        positive = np.maximum(np.nan_to_num(np.asarray(reduced, float), posinf=0.0), 0.0)
        oriented = (float(constant), positive, unit)
        cheap_bound = max(
            _cheap_bound(problem) if cheap_bound is None else cheap_bound,
            float(_rounded_up(np.array([constant]), unit)[0]),
        )
    if remainder is None:
        remainder = REMAINDER
    runs = _directions(
        problem,
        both,
        both_prices,
        oriented,
        credit if oriented else None,
        remainder,
        state_lp,
        None if window is None else np.asarray(window, float),
    )
    info["setup_seconds"] = time.perf_counter() - setting_up  # bounds and first layers
    if state_lp is not None:
        state_lp.budget(deadline.remaining())
    try:
        done, stopped_by = _expand(
            problem,
            runs,
            upper,
            tolerance,
            deadline,
            max_states,
            info,
            watch,
            state_lp if give_up else None,
        )
    finally:
        if state_lp is not None:
            state_lp.release()
    if done is not None and done.best_path is not None:
        cost = path_cost(problem.cost, done.best_path)  # re-scored on the original data
        if cost < best:
            known = (cost, done.best_path)
    kept = sum(r.kept for r in runs)
    pruned = sum(r.pruned for r in runs)
    peak = max(r.peak for r in runs)
    info["direction"] = None if done is None else ("backward" if done.reverse else "forward")
    if info.get("met"):
        info["direction"] = "both"
    info.update(states=kept, pruned=pruned, peak_layer=peak)
    if lagrange is not None:
        info["lagrange_pruned"] = sum(r.lagrange_pruned for r in runs)
    if state_lp is not None:
        info["lp_pruned"] = sum(r.lp_pruned for r in runs)
        info["lp_solved"] = state_lp.solved
        info["lp_seconds"] = state_lp.seconds
        info["lp_stopped"] = state_lp.stopped
        info["lp_iterations"] = state_lp.iterations
    if remainder:
        info["remainder_pruned"] = sum(r.remainder_pruned for r in runs)
        info["remainder_seconds"] = sum(
            r.remainder.seconds for r in runs if r.remainder is not None
        )
    objective = np.inf if known is None else known[0]
    runtime = time.perf_counter() - began
    if stopped_by is None and done is not None:  # done is set when nothing stopped the loop
        pruned_min = done.pruned_min
        if known is None and not np.isfinite(pruned_min):  # no state can reach the end
            return finish(
                problem,
                None,
                method="exact-sop-dp",
                stop="infeasible",
                bound=np.inf,
                runtime=runtime,
                info={**info, "proof": "every ideal expanded"},
            )
        # every path is found or passes through a dropped state: min(found, dropped) bounds
        # them all, whatever pruned (the incumbent or a trial cutoff below it)
        proven = min(objective, pruned_min)
        if cutoff is not None and proven < objective:  # the cutoff proven, no cheaper order
            info["cutoff_proven"] = True
            return finish(
                problem,
                None if known is None else Order(known[1]),
                method="exact-sop-dp",
                stop="solver_limit",
                bound=proven,
                runtime=runtime,
                info=info,
            )
        assert known is not None  # a pruned state needs an incumbent (upper < inf)
        return finish(
            problem,
            Order(known[1]),
            method="exact-sop-dp",
            stop="complete",
            solver="dp",
            bound=proven,
            runtime=runtime,
            info=info,
        )
    # stopped: the open layer and the dropped states hold every cheaper path
    # each direction alone proves min(open layer, dropped states); both hold: the larger
    proven = max(r.proven() for r in runs)
    if cheap_bound is None:
        cheap_bound = _cheap_bound(problem)
    proven = max(proven, cheap_bound) if np.isfinite(proven) else max(cheap_bound, 0.0)
    return finish(
        problem,
        None if known is None else Order(known[1]),
        method="exact-sop-dp",
        stop=stopped_by or "error",
        bound=proven,
        runtime=time.perf_counter() - began,
        info=info,
    )


def _beam_start(
    problem: SopProblem,
    known: tuple[float, list[int]] | None,
    beam_width: int,
    deadline: Deadline,
    info: dict[str, Any],
) -> tuple[float, list[int]] | None:
    """The incumbent improved by beam passes (:func:`beam_order`): a narrow beam first (a
    good path in a fraction of a second), then :data:`MIDDLE_BEAM`, then ``beam_width``, within
    :data:`BEAM_SHARE` of the time (the first, narrowest pass at least
    :data:`FIRST_BEAM_SHARE`), each started only if it should end in it
    (:data:`BEAM_TIME_EXPONENT`); ``info["beam"]`` the beam's cost when it improved the
    incumbent, ``info["beam_skipped"]`` the first width not started."""
    if beam_width:
        budget = Deadline(deadline.share(BEAM_SHARE))
        last: tuple[int, float] | None = None  # the last pass's width and seconds
        for width in sorted({min(w, beam_width) for w in (NARROW_BEAM, MIDDLE_BEAM, beam_width)}):
            if budget.expired(MARGIN) and (last is not None or deadline.expired(MARGIN)):
                break
            left = budget.remaining()
            if last is not None and left is not None:
                # a pass cut by the budget finds nothing: not started when it should not end
                # in time, the time left going to the DP (ESC47 at 10 s: the passes of 256 and
                # 1,024 took 1.6 s and 5.9 s against a budget of about 1 s)
                if last[1] * (width / last[0]) ** BEAM_TIME_EXPONENT > left:
                    info["beam_skipped"] = width
                    break
            if last is None:  # the first pass: at least FIRST_BEAM_SHARE of the stage
                first = deadline.share(FIRST_BEAM_SHARE)
                if left is not None and first is not None:
                    left = max(left, first)
            key = _problem_key(problem, width)
            beam: tuple[float, list[int]] | None
            if key in _BEAMS:  # ran to its end in an earlier stage (deterministic): reused
                beam, seconds = _BEAMS[key]
            else:
                began = time.perf_counter()
                beam = beam_order(problem, width, left)
                seconds = time.perf_counter() - began
                if beam is not None:
                    if len(_BEAMS) >= 16:
                        _BEAMS.pop(next(iter(_BEAMS)))
                    _BEAMS[key] = (beam, seconds)
            last = (width, seconds)
            if beam is not None and (known is None or beam[0] < known[0]):
                known = beam
                info["beam"] = beam[0]
    return known


#: The beam passes that ran to their end, by problem and width, with their seconds: a
#: portfolio's second DP stage would run the same passes again (the narrow one first), and
#: the wider one that did not fit in the first stage's budget then fits in the second's.
_BEAMS: dict[bytes, tuple[tuple[float, list[int]], float]] = {}


def _problem_key(problem: SopProblem, width: int) -> bytes:
    """A digest of the problem's data and a beam width."""
    import hashlib

    pairs = np.array(sorted(problem.precedences), dtype=np.int64)
    data = np.ascontiguousarray(problem.cost).tobytes() + pairs.tobytes()
    extra = np.array([problem.start, problem.end, width], dtype=np.int64).tobytes()
    return hashlib.blake2b(data + extra).digest()


def trial_cutoffs(
    problem: SopProblem,
    incumbent: Order,
    lower: float,
    time_limit: float | None,
    state_lp: StateLp,
    lagrange: tuple[float, np.ndarray] | None = None,
    credit: RowCredit | None = None,
    max_states: int | None = None,
    window: np.ndarray | None = None,
) -> Solution:
    """Raise a proven bound by the DP with the per-state LP at trial cutoffs, stepping up from
    ``lower`` (a proven bound) towards the incumbent's cost ``UB``.

    Each trial runs :func:`solve_sop_dp` with ``cutoff = lower + step`` (rounded up to the
    costs' gcd; the incumbent itself, no cutoff, once that reaches ``UB``), ``step`` =
    :data:`TRIAL_STEP` ``* lower``, its give-up rule, and at most
    :data:`TRIAL_TIME_SHARE` of the time left; ``lagrange``, ``credit`` and ``window`` are
    :func:`solve_sop_dp`'s (each a bound valid for every order whatever its prices, so the
    trials may take the best the caller has: the window's where they beat the root's, both
    where neither is known to). Every trial that ends proves what ``cutoff=``
    promises: an order below the cutoff, the cheapest there is (returned: optimal), or no order
    below it, so ``cutoff`` is a bound, the new ``lower``. A trial that gave up (or ran out of
    its time) proves nothing more than its own bound; the next one halves the step, down to one
    gcd. The stage stops on its time or once no step is left; it returns the incumbent with the
    largest bound proven (status "time_limit" unless proven optimal), ``info["trials"]`` listing
    each trial's cutoff, outcome and seconds.

    Why small steps up: a trial's work grows about geometrically with its cutoff's distance
    above the root's bound (prob.42, root bound 230, optimum 243: 713 LPs at a cutoff of 240,
    3,913 at 244, 5,703 at 245), so the trials below the optimum are cheap bound raises (ft53.1:
    7,270 in 1.6 s, 7,360 in 19 s, against a root bound of 7,189), their sum is dominated by
    the last one, and a trial just above the optimum finds it and proves it; a trial far above
    it costs the geometric factor of its overshoot (bisecting prob.42's gap 230-259 from the
    middle, the first trial at 245 ran 16 s and gave up). The bound proven is also the
    trials' whole output when they stop: a proven cutoff is kept whatever follows.
    """
    began = time.perf_counter()
    deadline = Deadline(time_limit)
    upper = path_cost(problem.cost, list(incumbent))
    unit = _cost_unit(problem)
    best_bound = lower
    step = TRIAL_STEP * abs(lower)
    trials: list[dict[str, Any]] = []
    last: Solution | None = None
    while lower < upper - 1e-9 * abs(upper) and not deadline.expired(MARGIN):
        raised = lower + max(step, unit)
        target = float(_rounded_up(np.array([raised]), unit)[0]) if unit else raised
        cutoff = None if target >= upper else target
        left = deadline.remaining()
        if left is not None and cutoff is not None:
            left *= TRIAL_TIME_SHARE
        trial_began = time.perf_counter()
        found = solve_sop_dp(
            problem,
            None if left is None else max(left - MARGIN, MARGIN),
            incumbent=incumbent,
            max_states=max_states,
            beam_width=0,
            lagrange=lagrange,
            credit=credit,
            state_lp=state_lp,
            cutoff=cutoff,
            give_up=True,
            window=window,
        )
        last = found
        proven = bool(found.info.get("cutoff_proven"))
        trials.append(
            {
                "cutoff": upper if cutoff is None else cutoff,
                "status": str(found.status),
                "proven": proven,
                "bound": found.bound,
                "gave_up": found.info.get("gave_up"),
                "seconds": time.perf_counter() - trial_began,
            }
        )
        if found.status != TIME_LIMIT:  # optimal (or infeasible): the whole answer
            return found.replace(info={**found.info, "trials": trials})
        if found.bound is not None:
            best_bound = max(best_bound, float(found.bound))
        if proven and cutoff is not None:
            if not cutoff > lower:
                break  # no step left to prove (a share of 0 on non-integral costs)
            lower = max(lower, cutoff, best_bound)
            step = TRIAL_STEP * abs(lower)
        elif cutoff is None or step <= max(unit, 1e-9 * abs(upper)):
            break  # the smallest trial gave up: nothing cheaper is left to try
        else:
            step /= 2
    info = {} if last is None else dict(last.info)
    info["trials"] = trials
    return finish(
        problem,
        Order(list(incumbent)),
        method="exact-sop-dp",
        stop="time_limit",
        bound=min(best_bound, upper),
        runtime=time.perf_counter() - began,
        info=info,
    )


def _cost_unit(problem: SopProblem) -> float:
    """The gcd of the usable arcs' costs when they are integers (every order's cost is a
    multiple of it), else 0."""
    from taopt.models.sop_cuts import _cost_step

    tails, heads = usable_arcs(problem.cost, problem.closure)
    costs = np.asarray(problem.cost[tails, heads], dtype=float)
    if not len(costs) or not np.all(costs == np.round(costs)):
        return 0.0
    return float(_cost_step(costs))


def _directions(
    problem: SopProblem,
    both: bool,
    both_prices: bool,
    lagrange: tuple[float, np.ndarray, float] | None = None,
    credit: RowCredit | None = None,
    remainder: bool = False,
    state_lp: StateLp | None = None,
    window: np.ndarray | None = None,
) -> list[_Run]:
    """The forward search and (``both``) the backward one on :func:`reversed_problem`,
    each (``both_prices``) also bounded on the other's assignment prices; ``lagrange``
    (:class:`_Run`) read forward, transposed for the backward run."""
    backward = None
    if lagrange is not None:
        backward = (lagrange[0], np.ascontiguousarray(lagrange[1].T), lagrange[2])
    back_credit = None if credit is None else credit.transposed()
    runs = [_Run(problem, False, lagrange, credit, remainder, state_lp, window)] + (
        [_Run(reversed_problem(problem), True, backward, back_credit, remainder, state_lp, window)]
        if both
        else []
    )
    if both and both_prices:
        # the assignment LP is degenerate: the reversed problem's optimal prices (read
        # transposed) are other optimal prices, and often prune other states
        for run, other in ((runs[0], runs[1]), (runs[1], runs[0])):
            s, o = run.search, other.search.bound
            s.more_bounds.append(
                _Bound(s.usable, s.problem.start, s.problem.end, (o.beta, o.alpha), s.pred)
            )
    return runs


def _expand(
    problem: SopProblem,
    runs: list[_Run],
    upper: float,
    tolerance: float,
    deadline: Deadline,
    max_states: int | None,
    info: dict[str, Any],
    watch: Callable[[Sequence[_Run]], None] | None = None,
    give_up: StateLp | None = None,
) -> tuple[_Run | None, str | None]:
    """Layer after layer, the direction with the smaller last layer first (forward on
    ties: each grows into its widest layers only as far as the other is wider), until one
    finishes, the two meet (joined; ``info["met"]``) or a limit stops them. Returns the
    finished run (None if stopped) and why it stopped (None if it finished); ``watch(runs)``
    before the first layer and after each one kept. ``give_up``: the run's per-state LP; the
    search stops ("time_limit", ``info["gave_up"]``) once :func:`_hopeless` says so."""
    both = len(runs) > 1
    if watch is not None:
        watch(runs)
    stopped_by = None
    done = None
    while done is None:
        run = min(runs, key=lambda r: len(r.layers[-1][0]))
        limit = np.inf if max_states is None else 4 * max_states
        room = None if max_states is None else max_states - sum(r.kept for r in runs)
        stopped_by = run.step(upper, tolerance, deadline, limit, room)
        if stopped_by is not None:
            break
        if watch is not None:
            watch(runs)
        if give_up is not None and not run.finished:
            why = _hopeless(runs, give_up, deadline)
            if why is not None:
                info["gave_up"] = why
                stopped_by = "time_limit"
                break
        if run.finished:
            done = run
        elif both and sum(len(r.layers) - 1 for r in runs) >= problem.n - 2:
            done = runs[0]  # the two directions meet: join them
            joined = _join(runs[0], runs[1], problem.cost)
            done.best_path = None if joined is None else joined[1]
            done.pruned_min = min(r.pruned_min for r in runs)
            info["met"] = True
    return done, stopped_by


def _hopeless(runs: Sequence[_Run], lp: StateLp, deadline: Deadline) -> str | None:
    """Why a search that relies on its per-state LP cannot end in its time (None: it may).

    A layer past the first that grew more than :data:`GIVE_UP_GROWTH` times its parent layer
    says the LPs do not narrow the search: it would multiply its width by about the branching
    factor again at each layer. The next layer to expand is the smaller direction's; its
    states' LPs are predicted at its
    width times its growth over the layer before (at least 1) times the LP's measured rate
    (:attr:`~taopt.models.sop_statelp.StateLp.rate`). When that passes the time left, the
    search would stop inside that layer, its bound no higher than the open layer's: it gives
    the time back instead. It also stops once the LPs stopped for good after their trial
    (:meth:`~taopt.models.sop_statelp.StateLp.failed`): the DP alone is then what the earlier
    stages ran already.
    """
    if lp.failed():
        return f"the LPs dropped under {MIN_SHARE:.0%} of their first states"
    for grown in runs:  # past the start's own branching, a layer that multiplies its width
        if len(grown.layers) > 2:
            width, before = len(grown.layers[-1][0]), len(grown.layers[-2][0])
            if width > GIVE_UP_GROWTH * max(before, 1):
                direction = "backward" if grown.reverse else "forward"
                return (
                    f"{direction} layer {len(grown.layers) - 1}: {before:,} -> {width:,} states "
                    f"(more than {GIVE_UP_GROWTH:g}x)"
                )
    run = min(runs, key=lambda r: len(r.layers[-1][0]))
    width = len(run.layers[-1][0])
    before = len(run.layers[-2][0]) if len(run.layers) > 1 else 1
    growth = max(1.0, width / max(before, 1))
    need = width * growth * lp.rate
    left = deadline.remaining()
    if left is not None and need > left:
        direction = "backward" if run.reverse else "forward"
        return (
            f"{direction} layer {len(run.layers) - 1}: {width:,} states growing {growth:.1f}x, "
            f"their LPs predicted {need:.1f} s against {left:.1f} s left"
        )
    return None
