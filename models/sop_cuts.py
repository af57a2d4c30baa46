"""A precedence-aware cut model of the SOP, built as arrays straight into HiGHS.

The model is the arc formulation of :mod:`taopt.models.sop` without its flow columns:
binary ``x_a`` per usable arc (``taopt.sop.problem.usable_arcs``), the two degree
rows, and rows added in a cut loop. Every row added is a *precedence path cut*:

    For a pair ``i ≺ j`` of the precedence closure (which holds ``start ≺ v`` and
    ``v ≺ end`` for every inner v), let ``W(i, j) = V \\ (π(i) ∪ σ(j))`` be the nodes that
    are neither predecessors of i nor successors of j. For every ``S ⊂ W(i, j)`` with
    ``i ∈ S``, ``j ∉ S``::

        Σ_{a = (u, v): u ∈ S, v ∈ W(i, j) \\ S} x_a  >=  1.

Proof: in a feasible order the stretch of the path from i to j visits only nodes that
come after i and before j, none of which precedes i or follows j, so the stretch is a
path from i to j inside ``W(i, j)`` and crosses the cut once at least. With ``i = start``
(``π(start) = ∅``) these rows contain the subtour rows of Dantzig, Fulkerson & Johnson
(the thesis's (2.5) in the form "every S not holding start is entered"), strengthened by
dropping the arcs that leave a successor of j; with general pairs they carry the
precedences (5.7) into the LP, in the spirit of the predecessor/successor inequalities of
Balas, Fischetti & Pulleyblank (1995) used by Ascheuer, Jünger & Reinelt (2000). They are
separated *exactly* on an LP point: for each pair one maximum flow from i to j on the
point's support restricted to ``W(i, j)`` (``scipy.sparse.csgraph.maximum_flow``); a
flow below 1 gives a violated row (the source side of a minimum cut).

Once no pair's row is violated, two generalisations are separated over a list of candidates
(:meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets`, proofs there): *set path cuts*,
with two sources preceding one sink (or one source preceding two sinks) and W shrunk by
the predecessors (successors) of both, and *alternation rows* of side 2, for a chain
``i ≺ t ≺ s ≺ j`` whose cut holds i and s on one side and t and j on the other. Root bounds
(the cut loop run to its end, ``benchmarks/bench_sop.py``; optimum in brackets): p43.1
28,100 → 28,135 [28,140], ry48p.1 14,712 → 14,775 [15,805], ft53.1 7,116 → 7,189 [7,531],
prob.42 229 → 230 [243], ESC47 1,247 → 1,254 [1,288], br17.10 43 → 55 [55], ft53.4
13,833 → 14,370 [14,425].

In :func:`solve_sop_cuts` (not in the portfolio's root stage), once those hold too, the
*stretch-partition rows* of :mod:`taopt.models.sop_stretch` are added: per inner precedence
pair, the three stretches of an order (start to i, i to j, j to end) as unit flows sharing the
arcs, projected to the arc space from one extended LP (root ft53.1 7,189 → 7,286, ry48p.1
14,775 → 14,832).

Each row found is lifted by the precedences of its two sides
(:meth:`~taopt.models.sop_cuts.SopCutModel.lifted`): the σ- and π-inequalities of Balas, Fischetti &
Pulleyblank (1995) when i is the start or j the end, and their restrictions to the stretch from i to
j otherwise; the lifted row may be violated where the plain one is not.

:class:`SopCutModel` holds one live HiGHS model; :meth:`SopCutModel.root` runs the LP cut
loop and :func:`solve_sop_cuts` then solves the MIP with the rows found, checks the
integral point, adds the rows it violates and solves again (an exact method: each MIP is a
relaxation, so its proven bound is a bound of the SOP, and an integral point that is an
order is optimal). :mod:`taopt.models.sop_bc` searches a branch-and-cut tree of its own over the
same model instead (every row separated at every node; the portfolio's choice between the two is
:func:`taopt.models.sop_bc.wants_tree`).

References
----------
Thesis (5.7) (precedence), (2.5) (subtour rows). E. Balas, M. Fischetti, W. Pulleyblank,
"The precedence-constrained asymmetric traveling salesman polytope", Math. Programming 68
(1995). N. Ascheuer, M. Jünger, G. Reinelt, "A branch & cut algorithm for the asymmetric
traveling salesman problem with precedence constraints", Comput. Optim. Appl. 17 (2000).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import highspy
import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from taopt.models.highs import new_highs, thread_options
from taopt.models.sop import _cheap_bound, _known_order, usable_arcs
from taopt.models.sop_dp import RowCredit
from taopt.models.sop_statelp import clipped_duals, constraint_matrix
from taopt.models.sop_stretch import STRETCH_ROUNDS, StretchRow, stretch_rows
from taopt.result import Order, Solution, finish
from taopt.runtime import MARGIN, Deadline
from taopt.runtime.highs import DETACHED, interrupt_when, run_interruptibly
from taopt.sop.problem import SopProblem

__all__ = [
    "ALL_PAIRS_FIRST",
    "BAD_POINTS",
    "CREDIT_NEGATIVE",
    "CREDIT_ROWS",
    "CUTS_PER_ROUND",
    "SET_CANDIDATES",
    "SET_CUTS",
    "SET_TIGHT",
    "STRETCH_CUTS",
    "STRETCH_MIN_GAP",
    "STRETCH_BACK_TO_BACK",
    "CUT_TOLERANCE",
    "FLOW_SCALE",
    "KEEP_HIGHS_CUTS",
    "LIFT",
    "LIFT_ALL",
    "LIFT_TRY",
    "MIP_RESERVE",
    "MIP_RESERVE_MAX",
    "MIP_ROUNDS",
    "MIP_SUB_HEURISTICS",
    "POLISH_BLOCK",
    "POLISH_PASSES",
    "REDUCED_COST_FIXING",
    "ROOT_ROUNDS",
    "ROOT_STALL",
    "ROOT_STALL_ROUNDS",
    "ROUND_LP_ROUNDS",
    "SUB_HEURISTIC_OPTIONS",
    "RootCuts",
    "SopCutModel",
    "cut_bound",
    "cut_solution",
    "polish",
    "root_stage",
    "round_point",
    "row_key",
    "solve_sop_cuts",
]

#: Cut rows of largest dual whose crossings the DP tracks per state
#: (:meth:`~taopt.models.sop_cuts.SopCutModel.row_credit`: one bit each in a ``uint64``).
CREDIT_ROWS = 64

#: Arcs of negative reduced cost that the DP's row-credit bound tracks per state at most
#: (the most negative; :meth:`~taopt.models.sop_cuts.SopCutModel.row_credit`).
CREDIT_NEGATIVE = 64

#: The root loop separates the set path cuts and alternation rows
#: (:meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets`) once the pair cuts hold.
SET_CUTS = True

#: Candidates (sources, sinks) of :meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets`
#: at most (one maximum flow each per round).
SET_CANDIDATES = 6000

#: A candidate of :meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets` is tried only
#: when the maximum flow of each of its pairs (source, sink) at the point, found by the pair
#: separation just before, is below ``side + SET_TIGHT`` (a heuristic: the set rows found
#: on p43.1, ry48p.1 and ft53.1 were of nearly tight pairs).
SET_TIGHT = 0.5

#: Capacities of the maximum flows are the LP values times this, rounded down (scipy's
#: maximum flow takes integers); a cut is added only if its value in floating point is
#: below ``1 - CUT_TOLERANCE``.
FLOW_SCALE = 1_000_000

#: Stretch-partition rows (:mod:`taopt.models.sop_stretch`) once the path and set rows hold,
#: in :func:`solve_sop_cuts` (its root loop and the LP loops between its MIP rounds).
STRETCH_CUTS = True

#: Stretch rows only while the best order is more than this share above the bound
#: (``_wants_stretch``).
STRETCH_MIN_GAP = 0.01

#: Whether one LP loop (:meth:`SopCutModel.root`) may start a second extended LP right after
#: the first one's rows (the model's :data:`~taopt.models.sop_stretch.STRETCH_ROUNDS` allowing).
#: At its optimum the first one's rows give the x-LP the extended LP's value (LP duality,
#: :mod:`taopt.models.sop_stretch`), so a second one right after it adds only what the path
#: and set rows separated in between add: +0.3 on ft53.1 and prob.42, +3 on ry48p.1, +0.7 on
#: ftv33-0.02-1 for 2-10 s each. Off, the second waits for a later loop (after a MIP round's
#: rows, :func:`solve_sop_cuts`). On, as before: off, the tree needed more nodes to proof
#: (prob.42 479 against 415, ftv33-0.02-1 235 against 143, the optimum as incumbent) and its
#: bound at 60 s on ft53.1 was lower in both runs (docs/benchmarks.md, issue 33, branch b14).
STRETCH_BACK_TO_BACK = True

#: A row is violated when the LP point's left-hand side is below ``1 - CUT_TOLERANCE``.
CUT_TOLERANCE = 1e-4

#: The path cuts are lifted by the precedences of their two sides
#: (:meth:`~taopt.models.sop_cuts.SopCutModel.lifted`); False separates the plain rows only.
LIFT = True

#: With :data:`LIFT`, a pair's minimum cut is lifted when its value is below this (the
#: lifted row can be violated where the plain one holds).
LIFT_TRY = 2.0

#: With :data:`LIFT`, every pair's cut holding at the point is lifted too (True), or only
#: those of the pairs ``(start, j)`` and ``(i, end)`` (False; the other pairs lift the
#: violated cuts only).
LIFT_ALL = False

#: Rows added per separation round at most (the most violated first).
CUTS_PER_ROUND = 400

#: The root loop separates every pair from its first round (True), or the pairs
#: ``(start, k)`` alone until they stall (False).
ALL_PAIRS_FIRST = True

#: LP rounds of the root cut loop at most.
ROOT_ROUNDS = 200

#: The root loop stops when ``ROOT_STALL_ROUNDS`` rounds in a row raise the LP value by
#: less than this fraction.
ROOT_STALL = 1e-5

#: See :data:`ROOT_STALL`.
ROOT_STALL_ROUNDS = 5


#: :meth:`~taopt.models.sop_cuts.SopCutModel._near` passes a pair to the exact check when a
#: candidate row's left-hand side, summed in another order, is below ``1 - CUT_TOLERANCE``
#: plus this: far above the rounding of a sum of at most ``n`` units over some ten thousand
#: arcs (``1e-16`` relative per term), far below any violation that matters.
NEAR_MARGIN = 1e-6

#: The pairs whose maximum flows one call of scipy's ``maximum_flow`` computes together
#: (:func:`pair_flows`); also how often the separation looks at its deadline.
PAIR_BATCH = 64

#: :func:`pair_flows` measures each pair's flow up to this many units (above every threshold
#: read from ``SopCutModel.flows``: :data:`LIFT_TRY`, ``1 +`` :data:`SET_TIGHT`, ``2 +``
#: :data:`SET_TIGHT`).
FLOW_CAP = 3


def pair_flows(
    n: int,
    tails: np.ndarray,
    heads: np.ndarray,
    caps: np.ndarray,
    pairs: np.ndarray,
    inside: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The maximum flows of several pairs at once: (each pair's flow from i to j on the arcs
    ``tails -> heads`` of capacities ``caps`` inside its node mask ``inside[k]``, at most
    ``FLOW_CAP * FLOW_SCALE``; per pair, the source side of a minimum cut, a boolean row of
    ``n``, meaningful where the flow is below the cap): :func:`copy_flows` with one source
    and one sink per copy."""
    copies = np.arange(len(pairs))
    return copy_flows(n, tails, heads, caps, inside, (copies, pairs[:, 0]), (copies, pairs[:, 1]))


def copy_flows(
    n: int,
    tails: np.ndarray,
    heads: np.ndarray,
    caps: np.ndarray,
    inside: np.ndarray,
    starts: tuple[np.ndarray, np.ndarray],
    stops: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """The maximum flows of several copies of one graph at once, copy k restricted to the
    nodes ``inside[k]``, from its sources to its sinks (``starts`` and ``stops``: (copy,
    node) arrays): (each copy's flow on the arcs ``tails -> heads`` of capacities ``caps``,
    exact below ``FLOW_CAP * FLOW_SCALE`` and at least that otherwise; per copy, the source
    side of a minimum cut, a boolean row of ``n``, meaningful where the flow is below the
    cap).

    One graph holds the copies (copy k's node v is ``k n + v``), a super source with an arc
    of capacity ``FLOW_CAP * FLOW_SCALE`` to each copy's sources and an arc of the same
    capacity from each copy's sinks to a super sink. The copies share no node, so every
    maximum flow of the whole is a maximum flow in each copy (the sum of the copies' maxima
    is reached only when each is); a copy whose flow is below the cap saturates none of its
    arcs from the super source, so its flow is that with uncapped sources and sinks, and the
    nodes reached from the super source in the residual graph within that copy are the
    source side of its minimum cut (the same set for every maximum flow). Why: one scipy call
    per pair spent about 0.3 ms of its 0.4 ms in the set-up of sparse matrices (csr checks,
    the reverse arcs, the flow matrix; ft53.1, 117 pairs, 109 support arcs), the flow itself
    about 0.05 ms.
    """
    count = len(inside)
    cap = FLOW_CAP * FLOW_SCALE
    copy, arc = np.nonzero(inside[:, tails] & inside[:, heads])
    source, sink = count * n, count * n + 1
    first = starts[0] * n + starts[1]
    graph = sp.csr_matrix(
        (
            np.concatenate([caps[arc], np.full(len(first) + len(stops[0]), cap)]).astype(np.int32),
            (
                np.concatenate(
                    [copy * n + tails[arc], np.full(len(first), source), stops[0] * n + stops[1]]
                ),
                np.concatenate([copy * n + heads[arc], first, np.full(len(stops[0]), sink)]),
            ),
        ),
        shape=(count * n + 2, count * n + 2),
    )
    graph.sum_duplicates()
    result = maximum_flow(graph, source, sink)
    flow = result.flow.tocsr()
    out = np.bincount(starts[0], weights=flow[source].toarray().ravel()[first], minlength=count)
    residual = (graph - flow).tocsr()
    residual.data = (residual.data > 0).astype(np.int8)
    residual.eliminate_zeros()
    reached = np.zeros(count * n + 2, dtype=bool)
    reached[breadth_first_order(residual, source, directed=True, return_predecessors=False)] = True
    return np.round(out).astype(np.int64), reached[: count * n].reshape(count, n)


def _before_matrix(closure: nx.DiGraph, n: int) -> np.ndarray:
    """``before[i, j]``: i ≺ j in the closed precedence DAG."""
    return np.asarray(nx.to_numpy_array(closure, nodelist=range(n), dtype=bool, weight=None))


@dataclass
class RootCuts:
    """What the root cut loop found.

    Attributes
    ----------
    value : float
        The last LP's value (``-inf`` if none finished).
    bound : float
        A proven lower bound from the LP's duals (:meth:`SopCutModel.dual_bound`).
    rounds : int
        LPs solved.
    rows : int
        Cut rows in the model.
    complete : bool
        The last separation found no violated row.
    values : ndarray or None
        The last LP point.
    """

    value: float
    bound: float
    rounds: int
    rows: int
    complete: bool
    values: np.ndarray | None = field(default=None, repr=False)


def row_key(arcs: np.ndarray, side: float, weights: np.ndarray | None = None) -> bytes:
    """The identity of a cut row (its arcs, side and weights) by which
    :class:`SopCutModel` adds a row only once: a 0/1 row of ``add_cuts`` (``weights`` None),
    or a weighted row of ``add_weighted_rows``."""
    if weights is None:
        return np.sort(arcs).astype(np.int64).tobytes() + (b"" if side == 1.0 else b"=2")
    return b"w" + np.concatenate([arcs, np.round(weights, 9), [side]]).astype(float).tobytes()


class SopCutModel:
    """The arc model of one SOP in a live HiGHS object, with precedence path cuts.

    Parameters
    ----------
    problem : SopProblem
    verbose : bool
        HiGHS's log.
    """

    def __init__(self, problem: SopProblem, verbose: bool = False) -> None:
        self.problem = problem
        n = problem.n
        self.n = n
        self.before = _before_matrix(problem.closure, n)
        self.tails, self.heads = usable_arcs(problem.cost, problem.closure)
        self.costs = problem.cost[self.tails, self.heads].astype(float)
        self.integral_costs = bool(np.all(self.costs == np.round(self.costs)))
        #: Every order's cost is a multiple of this (the gcd of the usable arcs' integral
        #: costs; 0 when a cost is not an integer): bounds are rounded up to a multiple of it.
        self.step = _cost_step(self.costs) if self.integral_costs else 0
        n_arcs = len(self.tails)
        self.n_arcs = n_arcs
        self.arc_index = -np.ones((n, n), dtype=np.int64)
        self.arc_index[self.tails, self.heads] = np.arange(n_arcs)
        # pairs to separate: every closure pair (start ≺ v and v ≺ end included)
        pairs = np.argwhere(self.before)
        self.pairs = pairs
        # W(i, j) = not a predecessor of i and not a successor of j
        self._keys: set[bytes] = set()
        self.highs = new_highs(verbose)
        for key, value in thread_options().items():
            self.highs.setOptionValue(key, value)
        lp = highspy.HighsLp()
        lp.num_col_ = n_arcs
        lp.col_cost_ = self.costs
        lp.col_lower_ = np.zeros(n_arcs)
        lp.col_upper_ = np.ones(n_arcs)
        arcs = np.arange(n_arcs)
        # degree rows: v != end left once (rows 0..n-1 by tail), v != start entered once
        out_rows = self.tails
        in_rows = n + self.heads
        matrix = sp.csc_matrix(
            (
                np.ones(2 * n_arcs),
                (np.concatenate([out_rows, in_rows]), np.concatenate([arcs, arcs])),
            ),
            shape=(2 * n, n_arcs),
        )
        keep = np.array(
            [v != problem.end for v in range(n)] + [v != problem.start for v in range(n)]
        )
        matrix = matrix[keep].tocsc()
        self.degree_rows = int(keep.sum())
        lp.num_row_ = self.degree_rows
        lp.row_lower_ = np.ones(self.degree_rows)
        lp.row_upper_ = np.ones(self.degree_rows)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = matrix.indptr.astype(np.int32)
        lp.a_matrix_.index_ = matrix.indices.astype(np.int32)
        lp.a_matrix_.value_ = matrix.data.astype(float)
        lp.a_matrix_.num_col_ = n_arcs
        lp.a_matrix_.num_row_ = self.degree_rows
        self.highs.passModel(lp)
        self.cut_rows: list[np.ndarray] = []
        #: The right-hand side of each cut row (1, or 2 for the alternation rows of
        #: :meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets`).
        self.cut_sides: list[float] = []
        #: The weights of each cut row's arcs: None for the 0/1 rows of
        #: :meth:`~taopt.models.sop_cuts.SopCutModel.add_cuts`, an array for the stretch rows of
        #: :meth:`~taopt.models.sop_cuts.SopCutModel.add_weighted_rows`.
        self.cut_weights: list[np.ndarray | None] = []
        #: Extended LPs of :mod:`taopt.models.sop_stretch` solved so far.
        self.stretch_solves = 0
        #: Seconds in :meth:`~taopt.models.sop_cuts.SopCutModel._stretch` so far (the
        #: extended LPs, built and solved, started or not).
        self.stretch_seconds = 0.0
        self.is_mip = False
        #: True once a MIP round was left running past the deadline
        #: (:data:`taopt.runtime.highs.DETACHED`): ``highs`` must not be touched again.
        self.detached = False
        #: Arcs fixed to 0 by :meth:`~taopt.models.sop_cuts.SopCutModel.fix_by_reduced_cost`.
        self.fixed = np.zeros(n_arcs, dtype=bool)
        #: Rows of HiGHS's own cut pool kept across MIP rounds
        #: (:meth:`~taopt.models.sop_cuts.SopCutModel.add_pool_rows`).
        self.pool_rows = 0
        #: Some row or fixing holds only for the orders cheaper than the best one known,
        #: so a bound ``B`` of the model bounds the SOP as ``min(B, best)``.
        self.conditional = False
        #: The clipped row duals and ``y^T b`` of the last Lagrangian bound worked out.
        self._last_duals: tuple[np.ndarray, float] = (np.zeros(0), 0.0)
        #: The row duals of the root loop's last optimal LP (None before one), for the prices
        #: of a loop stopped after it added rows (``saved=`` of
        #: :meth:`~taopt.models.sop_cuts.SopCutModel.lagrangian_prices`).
        self.root_duals: np.ndarray | None = None
        self._candidates: list[tuple[tuple[int, ...], tuple[int, ...], int]] | None = None
        self._set_cache: tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        #: The last maximum flow of each closure pair at a separated point (``inf``: none
        #: yet), which picks the candidates of the set path cuts.
        self.flows = np.full((n, n), np.inf)
        #: HiGHS's model status after the last LP of
        #: :meth:`~taopt.models.sop_cuts.SopCutModel.root`.
        self.last_status: Any = None

    # ------------------------------------------------------------------ rows
    def add_cuts(self, cuts: list[np.ndarray], sides: list[float] | None = None) -> int:
        """Add rows ``Σ_{a in cut} x_a >= side`` (side 1 unless ``sides`` says; new ones
        only); returns how many were added."""
        fresh, fresh_sides = [], []
        for k, cut in enumerate(cuts):
            side = 1.0 if sides is None else float(sides[k])
            key = row_key(cut, side)
            if key not in self._keys:
                self._keys.add(key)
                fresh.append(np.sort(cut).astype(np.int32))
                fresh_sides.append(side)
        if fresh:
            self._append(fresh, fresh_sides, [None] * len(fresh))
        return len(fresh)

    def add_weighted_rows(self, rows: list[StretchRow]) -> int:
        """Add rows ``Σ_k w_k x_{a_k} >= side`` given as (arcs, weights, side) (the stretch rows
        of :func:`~taopt.models.sop_stretch.stretch_rows`); new ones only; returns how many."""
        fresh = []
        for arcs, weights, side in rows:
            key = row_key(arcs, side, weights)
            if key not in self._keys and len(arcs):
                self._keys.add(key)
                fresh.append((arcs.astype(np.int32), weights.astype(float), float(side)))
        if fresh:
            self._append(
                [arcs for arcs, _, _ in fresh],
                [side for _, _, side in fresh],
                [weights for _, weights, _ in fresh],
            )
        return len(fresh)

    def _append(
        self, rows: list[np.ndarray], sides: list[float], weights: list[np.ndarray | None]
    ) -> None:
        """Add the rows ``Σ_k w_k x_{a_k} >= side`` (arcs, sides, weights; None: all 1) to the
        LP and to ``cut_rows``, ``cut_sides`` and ``cut_weights``, in their order, unchecked."""
        values = [
            np.ones(len(row)) if w is None else np.asarray(w, dtype=float)
            for row, w in zip(rows, weights, strict=True)
        ]
        self.highs.addRows(
            len(rows),
            np.asarray(sides, dtype=float),
            np.full(len(rows), highspy.kHighsInf),
            sum(len(row) for row in rows),
            np.cumsum([0] + [len(row) for row in rows[:-1]]).astype(np.int32),
            np.concatenate(rows).astype(np.int32),
            np.concatenate(values),
        )
        self.cut_rows += list(rows)
        self.cut_sides += list(sides)
        self.cut_weights += list(weights)

    def add_pool_rows(
        self,
        starts: np.ndarray,
        index: np.ndarray,
        values: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
    ) -> int:
        """Add general rows ``lower <= a x <= upper`` (HiGHS's cut pool, CSR by row: row k
        holds ``index[starts[k]:starts[k + 1]]``); new ones only; returns how many."""
        count = len(lower)
        bounds = np.append(np.asarray(starts[:count], dtype=np.int64), len(index))
        if len(starts) > count:  # CSR with its closing entry
            bounds[count] = int(starts[count])
        keep, rows_index, rows_value, rows_start, at = [], [], [], [], 0
        for k in range(count):
            lo, hi = int(bounds[k]), int(bounds[k + 1])
            key = (
                b"p"
                + np.concatenate(
                    [index[lo:hi].astype(float), np.round(values[lo:hi], 9), [lower[k], upper[k]]]
                ).tobytes()
            )
            if key in self._keys or hi <= lo:
                continue
            self._keys.add(key)
            keep.append(k)
            rows_start.append(at)
            rows_index.append(index[lo:hi])
            rows_value.append(values[lo:hi])
            at += hi - lo
        if not keep:
            return 0
        flat_index = np.concatenate(rows_index).astype(np.int32)
        self.highs.addRows(
            len(keep),
            np.asarray(lower, dtype=float)[keep],
            np.asarray(upper, dtype=float)[keep],
            len(flat_index),
            np.asarray(rows_start, dtype=np.int32),
            flat_index,
            np.concatenate(rows_value).astype(float),
        )
        self.pool_rows += len(keep)
        return len(keep)

    def separate(
        self,
        values: np.ndarray,
        limit: int = CUTS_PER_ROUND,
        every: bool = False,
        deadline: Deadline | None = None,
        among: np.ndarray | None = None,
    ) -> list[np.ndarray]:
        """Violated precedence path cuts at the point ``values`` (exact: one maximum flow
        per closure pair), most violated first, at most ``limit``.

        The pairs ``(start, k)`` (the strengthened subtour rows) are tried first; the other
        pairs only when those give no row (most LP rounds of the root loop need only them),
        or always with ``every``. ``among`` (a mask over ``pairs``) restricts the other pairs
        (then a heuristic: the tree of :mod:`taopt.models.sop_bc` tries the pairs nearly tight
        at an earlier point). Stops early (with the rows found so far) when ``deadline``
        passes.
        """
        first = self.pairs[:, 0] == self.problem.start
        rest = ~first if among is None else ~first & among
        found = self._separate(values, self.pairs[first], deadline)
        if every:
            found += self._separate(values, self.pairs[rest], deadline)
        elif not found:
            found = self._separate(values, self.pairs[rest], deadline)
        found.sort(key=lambda item: item[0])
        return [arcs for _, arcs in found[:limit]]

    def _separate(
        self, values: np.ndarray, pairs: np.ndarray, deadline: Deadline | None = None
    ) -> list[tuple[float, np.ndarray]]:
        """(left-hand side, arcs) of the violated rows of ``pairs`` at ``values``.

        Per pair, a minimum cut of the point's support inside ``W(i, j)`` (a maximum flow)
        gives the plain path cut; when :data:`LIFT` is set, its two liftings
        (:meth:`~taopt.models.sop_cuts.SopCutModel.lifted`) are tried as well, also when the plain
        row holds (a flow below :data:`LIFT_TRY`), and the smallest left-hand side is kept.
        """
        n = self.n
        support = values > 1e-9
        tails, heads = self.tails[support], self.heads[support]
        caps = np.floor(values[support] * FLOW_SCALE).astype(np.int32)
        before = self.before
        found: list[tuple[float, np.ndarray]] = []
        seen: set[bytes] = set()
        for first in range(0, len(pairs), PAIR_BATCH):
            if deadline is not None and deadline.expired(MARGIN):
                break
            batch = pairs[first : first + PAIR_BATCH]
            # W(i, j) per pair (a batch at a time: the dense closures have thousands of pairs)
            inside = ~before[:, batch[:, 0]].T & ~before[batch[:, 1], :]
            has_arcs = (inside[:, tails] & inside[:, heads]).any(axis=1)
            batch, inside = batch[has_arcs], inside[has_arcs]
            if not len(batch):
                continue
            flows, sides = pair_flows(n, tails, heads, caps, batch, inside)
            self.flows[batch[:, 0], batch[:, 1]] = flows / FLOW_SCALE
            near = self._near(values[support], tails, heads, batch, inside, flows, sides)
            for k in np.flatnonzero(near):
                i, j = batch[k]
                found += self._pair_cut(values, int(i), int(j), inside[k], flows[k], sides[k], seen)
        return found

    def _near(
        self,
        weights: np.ndarray,
        tails: np.ndarray,
        heads: np.ndarray,
        pairs: np.ndarray,
        inside: np.ndarray,
        flows: np.ndarray,
        sides: np.ndarray,
    ) -> np.ndarray:
        """A mask over ``pairs``: False where :meth:`_pair_cut` is sure to return no row
        (its flow at or above its threshold, or every candidate row's left-hand side at
        least ``1 - CUT_TOLERANCE + NEAR_MARGIN``), worked out for all pairs at once.

        The point's support arcs ``tails -> heads`` carry ``weights``; a candidate row's
        left-hand side is summed over them here (a matrix product) where :meth:`_pair_cut`
        sums over every arc of the row: the two differ by rounding only (far below
        :data:`NEAR_MARGIN`), so a pair left out would have given no row there, and the
        pairs kept go through :meth:`_pair_cut` itself (the same rows, in the same order).
        """
        start, end = self.problem.start, self.problem.end
        plain = (1 - CUT_TOLERANCE) * FLOW_SCALE
        wide = (LIFT_TRY if LIFT else 1 - CUT_TOLERANCE) * FLOW_SCALE
        ends = (pairs[:, 0] == start) | (pairs[:, 1] == end)
        near = flows < np.where(LIFT_ALL | ends, wide, plain)
        if not near.any():
            return near
        rows = np.flatnonzero(near)
        source = sides[rows] & inside[rows]
        sink = inside[rows] & ~sides[rows]
        sets = [(source, sink)]
        if LIFT:
            before = self.before
            lifted_a = (sink & before[pairs[rows, 0]]) @ before  # σ(T ∩ σ(i))
            lifted_b = (source & before[:, pairs[rows, 1]].T) @ before.T  # π(S ∩ π(j))
            sets += [(source & ~lifted_a, sink & ~lifted_a), (source & ~lifted_b, sink & ~lifted_b)]
        lhs = np.min(
            [(tail_set[:, tails] & head_set[:, heads]) @ weights for tail_set, head_set in sets],
            axis=0,
        )
        near[rows] = lhs < 1 - CUT_TOLERANCE + NEAR_MARGIN
        return near

    def _pair_cut(
        self,
        values: np.ndarray,
        i: int,
        j: int,
        inside: np.ndarray,
        flow: float,
        side: np.ndarray,
        seen: set[bytes],
    ) -> list[tuple[float, np.ndarray]]:
        """The row of the pair ``i ≺ j`` (W = ``inside``) given its scaled maximum ``flow``
        and the source ``side`` of its minimum cut: [] when it holds, else [(left-hand side,
        arcs)] of the plain path cut or a lifting of it, the smallest (new ones only: ``seen``
        keeps their keys)."""
        start, end = self.problem.start, self.problem.end
        plain = (1 - CUT_TOLERANCE) * FLOW_SCALE
        wide = (LIFT_TRY if LIFT else 1 - CUT_TOLERANCE) * FLOW_SCALE
        # a cut that holds is lifted only on the pairs of the start or the end (the σ- and
        # π-inequalities proper: 2n pairs at most, where the dense closures have thousands of
        # pairs)
        if flow >= (wide if LIFT_ALL or i == start or j == end else plain):
            return []
        candidates = [(side & inside, inside & ~side)]
        if LIFT:
            candidates += self.lifted(i, j, side & inside, inside & ~side)
        best: tuple[float, np.ndarray] | None = None
        for tail_set, head_set in candidates:
            arcs = np.flatnonzero(tail_set[self.tails] & head_set[self.heads])
            lhs = float(values[arcs].sum())
            if best is None or lhs < best[0] - 1e-12:
                best = (lhs, arcs)
        assert best is not None
        lhs, arcs = best
        key = arcs.tobytes()
        if lhs >= 1 - CUT_TOLERANCE or key in seen:
            return []
        seen.add(key)
        return [(lhs, arcs)]

    def lifted(
        self, i: int, j: int, source: np.ndarray, sink: np.ndarray
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """The two liftings of the path cut of ``i ≺ j`` with sides ``S = source`` (holding
        i) and ``T = sink`` (holding j), ``S ∪ T = W(i, j)``, as (tail set, head set).

        * σ-lifting: with ``A = σ(T ∩ σ(i))`` (the successors of the nodes of T that follow
          i), ``x(S \\ A : T \\ A) >= 1``. The first node h of T on the stretch from i to j
          and the node u before it are not in A: a node of ``T ∩ σ(i)`` preceding either
          would lie on the stretch before h.
        * π-lifting: with ``B = π(S ∩ π(j))``, ``x(S \\ B : T \\ B) >= 1``, by the mirror
          argument on the last node of S on the stretch and the node after it.

        With ``i = start`` the first is the σ-inequality of Balas, Fischetti & Pulleyblank
        (1995) on ``T``, ``x(V \\ T \\ σ(T) : T \\ σ(T)) >= 1`` (restricted to W); with
        ``j = end`` the second is their π-inequality on S.
        """
        before = self.before
        late = sink & before[i]  # T ∩ σ(i)
        lifted_a = before[late].any(axis=0)  # σ(T ∩ σ(i))
        early = source & before[:, j]  # S ∩ π(j)
        lifted_b = before[:, early].any(axis=1)  # π(S ∩ π(j))
        return [
            (source & ~lifted_a, sink & ~lifted_a),
            (source & ~lifted_b, sink & ~lifted_b),
        ]

    def set_candidates(self) -> list[tuple[tuple[int, ...], tuple[int, ...], int]]:
        """The (sources, sinks, side) tried by
        :meth:`~taopt.models.sop_cuts.SopCutModel.separate_sets`, at most
        :data:`SET_CANDIDATES`, in a fixed order: chains ``i ≺ t ≺ s ≺ j`` (sources ``{i, s}``,
        sinks ``{t, j}``, side 2), then two incomparable inner predecessors of one node (sources,
        the node the sink) and two incomparable inner successors of one node, the inner nodes
        first, then the end and the start."""
        if self._candidates is not None:
            return self._candidates
        before, n = self.before, self.n
        start, end = self.problem.start, self.problem.end
        inner = np.ones(n, dtype=bool)
        inner[[start, end]] = False
        found: list[tuple[tuple[int, ...], tuple[int, ...], int]] = []
        for i, j in self.pairs:
            between = np.flatnonzero(before[i] & before[:, j])
            for t in between:
                for s in between[before[t, between]]:
                    found.append(((int(i), int(s)), (int(t), int(j)), 2))
                    if len(found) >= SET_CANDIDATES:
                        self._candidates = found
                        return found
        for v in [*np.flatnonzero(inner), end, start]:
            for a, b in ((before[:, v] & inner, True), (before[v] & inner, False)):
                ends = np.flatnonzero(a)
                # a pair whose W is that of one of its pair cuts gives a sub-family of that
                # pair's cuts: only pairs each with a predecessor (successor) of its own
                own = before.T[ends] & ~before[v] if b else before[ends] & ~before[:, v]
                for k, x in enumerate(ends):
                    for m, y in enumerate(ends[k + 1 :], start=k + 1):
                        if before[x, y] or before[y, x]:
                            continue
                        if not (own[k] & ~own[m]).any() or not (own[m] & ~own[k]).any():
                            continue
                        pair = (int(x), int(y))
                        found.append((pair, (int(v),), 1) if b else ((int(v),), pair, 1))
                        if len(found) >= SET_CANDIDATES:
                            self._candidates = found
                            return found
        self._candidates = found
        return found

    def _set_arrays(self) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """For the candidates of :meth:`set_candidates` (cached, as they are): their node
        sets W (a boolean row of ``n`` each: the chain's own ``W(i, j)``, else V minus π(X)
        and σ(Y)) and the pairs whose flows decide whether one is tried, as (x, y, side):
        ``x[k], y[k]`` the two pairs (x, y) of X × Y of a candidate of side 1 (it has two
        sources or two sinks), the pair (i, j) twice for a chain."""
        if self._set_cache is None:
            before, n = self.before, self.n
            candidates = self.set_candidates()
            within = np.array(
                [
                    ~before[:, xs[0]] & ~before[ys[1], :]
                    if side == 2
                    else ~before[:, list(xs)].any(axis=1) & ~before[list(ys), :].any(axis=0)
                    for xs, ys, side in candidates
                ],
                dtype=bool,
            ).reshape(len(candidates), n)
            pairs = [
                [(xs[0], ys[1])] * 2 if side == 2 else [(x, y) for x in xs for y in ys]
                for xs, ys, side in candidates
            ]
            probe = np.array(pairs, dtype=np.int64).reshape(len(candidates), 2, 2)
            sides = np.array([side for _, _, side in candidates], dtype=float)
            self._set_cache = (within, (probe[:, :, 0], probe[:, :, 1], sides))
        return self._set_cache

    def separate_sets(
        self, values: np.ndarray, limit: int = CUTS_PER_ROUND, deadline: Deadline | None = None
    ) -> tuple[list[np.ndarray], list[float]]:
        """Violated *set path cuts* at the point ``values`` (rows and their sides), most
        violated first, at most ``limit``; a heuristic over the candidates of
        :meth:`~taopt.models.sop_cuts.SopCutModel.set_candidates` (exact for each: one
        maximum flow from its sources to its sinks).

        For node sets X and Y with every node of X preceding every node of Y, let
        ``W = V \\ (π(X) ∪ σ(Y))``; for every ``S ⊂ W`` holding ``X ∩ W`` and disjoint from Y::

            Σ_{a = (u, v): u ∈ S, v ∈ W \\ S} x_a  >=  1.

        Proof: in an order, let x be the last node of X and y the first of Y (x comes before
        y). A node between them comes after every node of X, so it precedes none (it is not
        in π(X)), and before every node of Y (not in σ(Y)); x itself is in no π(X) (it would
        precede a later node of X) and y in no σ(Y). So the stretch from x to y lies in W and
        goes from S to ``W \\ S``. With ``X = {i}``, ``Y = {j}`` this is the path cut; two
        sources or two sinks shrink W.

        *Alternation rows*: for a chain ``i ≺ t ≺ s ≺ j`` and ``W = W(i, j)``, every
        ``S ⊂ W`` holding i and s, not t or j, is crossed twice::

            Σ_{a = (u, v): u ∈ S, v ∈ W \\ S} x_a  >=  2,

        as the stretch from i to j (inside W) visits i, t, s, j in this order and leaves S on
        its way from i to t and again from s to j.
        """
        n = self.n
        support = values > 1e-9
        tails, heads = self.tails[support], self.heads[support]
        caps = np.floor(values[support] * FLOW_SCALE).astype(np.int64)
        found: list[tuple[float, np.ndarray, float]] = []
        seen: set[bytes] = set()
        candidates = self.set_candidates()
        within, probes = self._set_arrays()
        # tried only where the pair cuts it is made of are nearly tight
        tried = np.flatnonzero(self.flows[probes[0], probes[1]].max(axis=1) < probes[2] + SET_TIGHT)
        for first in range(0, len(tried), PAIR_BATCH):
            if deadline is not None and deadline.expired(MARGIN):
                break
            batch = [candidates[k] for k in tried[first : first + PAIR_BATCH]]
            inside = within[tried[first : first + PAIR_BATCH]]
            starts = np.array(
                [(k, x) for k, (xs, _, _) in enumerate(batch) for x in xs if inside[k, x]],
                dtype=np.int64,
            ).reshape(-1, 2)
            stops = np.array(
                [(k, y) for k, (_, ys, _) in enumerate(batch) for y in ys if inside[k, y]],
                dtype=np.int64,
            ).reshape(-1, 2)
            values_of, sides = copy_flows(
                n,
                tails,
                heads,
                caps,
                inside,
                (starts[:, 0], starts[:, 1]),
                (stops[:, 0], stops[:, 1]),
            )
            for (_, _, side), mask, value, near in zip(
                batch, inside, values_of, sides, strict=True
            ):
                if value >= (side - CUT_TOLERANCE) * FLOW_SCALE:
                    continue
                near = near & mask
                arcs = np.flatnonzero(near[self.tails] & (mask & ~near)[self.heads])
                lhs = float(values[arcs].sum())
                key = arcs.tobytes() + bytes([side])
                if lhs >= side - CUT_TOLERANCE or key in seen:
                    continue
                seen.add(key)
                found.append((lhs - side, arcs, float(side)))
        found.sort(key=lambda item: item[0])
        found = found[:limit]
        return [arcs for _, arcs, _ in found], [side for _, _, side in found]

    # ------------------------------------------------------------------ solves
    def _run(self, deadline: Deadline | None, stop: Any = None, brief: bool = False) -> None:
        """One HiGHS run within the deadline; ``stop()`` true interrupts it too.

        ``brief``: an LP run capped by a small ``simplex_iteration_limit`` (the strong
        branching of :mod:`taopt.models.sop_bc`, some milliseconds): a plain ``highs.run()``
        under HiGHS's own ``time_limit``, without the helper thread and the interrupt hooks of
        :func:`~taopt.runtime.highs.run_interruptibly` (about 3 ms of a 5 ms child LP, measured
        on ft53.1's root LP); a Ctrl-C is raised when the run returns. ``stop`` is then unused.
        """
        if deadline is not None and deadline.limited:
            left = deadline.remaining() or 0.0
            # HiGHS compares its time_limit with its run time summed over every run of this
            # object (getRunTime), not with this run's: the limit is that sum plus the time left
            # (a plain ``left`` stopped the later LP loops and MIP rounds at once)
            spent = float(self.highs.getRunTime())
            if self.is_mip:  # HiGHS looks at its clock only between phases of its root node
                left -= min(MIP_RESERVE * left, MIP_RESERVE_MAX)
            self.highs.setOptionValue("time_limit", spent + max(left - MARGIN, 0.01))
        if brief and not self.is_mip:
            self.highs.run()
            return
        expired = (lambda: False) if deadline is None else (lambda: deadline.expired(MARGIN))
        give_up = None
        if self.is_mip and deadline is not None and deadline.limited:
            # a MIP round still going at the deadline is left to end on its own
            give_up = time.perf_counter() + (deadline.remaining() or 0.0)
        with interrupt_when(self.highs, lambda: expired() or (stop is not None and stop())):
            if run_interruptibly(self.highs, give_up=give_up) == DETACHED:
                self.detached = True

    def lp_values(self) -> np.ndarray:
        """Column values of the last solve."""
        return np.asarray(self.highs.getSolution().col_value, dtype=float)

    def dual_bound(self) -> float:
        """A proven lower bound from the last LP's row duals (clipped to their signs):
        ``Σ_rows y_r b_r + Σ_a min(0, c_a - A_a^T y)`` over the arcs not fixed to 0 (columns
        in [0, 1]; ``b_r`` the row's lower side for ``y_r > 0``, its upper side for
        ``y_r < 0``); rounded up to a multiple of ``step``. ``-inf`` without duals.

        With no arc fixed it bounds the SOP; after
        :meth:`~taopt.models.sop_cuts.SopCutModel.fix_by_reduced_cost` (or with rows of
        ``conditional`` validity) it bounds the orders better than the incumbent, so ``min(bound,
        incumbent)`` bounds the SOP."""
        raw, _ = self._lagrangian()
        return self.round_up(raw)

    def round_up(self, bound: float) -> float:
        """``bound`` raised to the next multiple of ``step`` (every order's cost is
        one), with a 1e-6 tolerance; unchanged when the costs are not integers."""
        if not self.step or not math.isfinite(bound):
            return bound
        return float(self.step * math.ceil((bound - 1e-6) / self.step))

    def _lagrangian(self, saved: bool = False) -> tuple[float, np.ndarray]:
        """(The unrounded bound of :meth:`~taopt.models.sop_cuts.SopCutModel.dual_bound`, the arcs'
        reduced costs ``c - A^T y``); ``(-inf, empty)`` without duals.

        ``saved``: without the last LP's duals, those of the root loop's last optimal LP
        (:attr:`root_duals`), 0 on the rows added since. Rows are only appended and a row of
        dual 0 adds nothing, so this is that LP's own Lagrangian bound, valid for every order
        while no arc is fixed (weak duality, :func:`~taopt.models.sop_statelp.clipped_duals`)."""
        solution = self.highs.getSolution()
        lp = self.highs.getLp()
        if solution.dual_valid:
            duals = np.asarray(solution.row_dual, dtype=float)
        elif saved and self.root_duals is not None and not self.fixed.any():
            duals = np.zeros(lp.num_row_)
            duals[: len(self.root_duals)] = self.root_duals
        else:
            return -math.inf, np.zeros(0)
        lower = np.asarray(lp.row_lower_, dtype=float)
        upper = np.asarray(lp.row_upper_, dtype=float)
        y, constant = clipped_duals(duals, lower, upper)
        matrix = constraint_matrix(lp)
        reduced = self.costs - matrix.T @ y
        free = ~self.fixed
        bound = float(constant.sum() + np.minimum(reduced[free], 0.0).sum())
        self._last_duals = (y, float(constant.sum()))
        return bound, reduced

    def lagrangian_prices(self, saved: bool = False) -> tuple[float, np.ndarray] | None:
        """The last LP's Lagrangian bound for the DP (:func:`taopt.models.sop_dp.solve_sop_dp`'s
        ``lagrange``): ``(L, d)`` with ``d = c - A^T y`` on the usable arcs as an ``n x n``
        matrix (``inf`` elsewhere) and ``L = y^T b + Σ_a min(0, d_a)`` over every arc (fixed or
        not), so that every order ``x`` satisfying the rows costs at least
        ``L + Σ_{a ∈ x} max(d_a, 0)`` (:meth:`~taopt.models.sop_cuts.SopCutModel.dual_bound`'s
        argument). With ``conditional`` rows it holds for the orders better than the
        incumbent. None without duals; ``saved``: then the root loop's last optimal LP's (its
        rows added since priced at 0: that LP's own bound, valid while no arc is fixed)."""
        raw, reduced = self._lagrangian(saved)
        if not math.isfinite(raw):
            return None
        constant = raw - float(np.minimum(reduced[~self.fixed], 0.0).sum())  # y^T b
        matrix = np.full((self.n, self.n), np.inf)
        matrix[self.tails, self.heads] = reduced
        return constant + float(np.minimum(reduced, 0.0).sum()), matrix

    def row_credit(self, rows: int = CREDIT_ROWS, saved: bool = False) -> RowCredit | None:
        """The last LP's prices in the form of the DP's prefix bound with row credit
        (:class:`~taopt.models.sop_dp.RowCredit`, ``credit=`` of
        :func:`~taopt.models.sop_dp.solve_sop_dp`): ``y^T b``, the signed reduced costs ``d``,
        the ``rows`` cut rows of largest positive dual as bits of each arc, and the arcs of
        negative ``d``. None without duals, or when an arc is fixed or a row other than the
        degree and path-cut rows is in (the credit is then not worked out).

        Every row priced here is a path cut ``Σ_{a ∈ C_r} x_a >= 1`` with 0/1 coefficients,
        valid for every order, so an order crossing it ``k`` times pays ``y_r k`` in
        ``y^T A x``, ``y_r (k - 1)`` more than ``y^T b`` counts (the proof is in
        :mod:`taopt.models.sop_dp`, "Row credit"). ``saved``: as
        :meth:`~taopt.models.sop_cuts.SopCutModel.lagrangian_prices`.
        """
        raw, reduced = self._lagrangian(saved)
        if not math.isfinite(raw) or self.fixed.any() or self.pool_rows:
            return None
        y, constant = self._last_duals
        priced = y[self.degree_rows :]
        count = min(len(self.cut_rows), len(priced))
        ranked = [
            k
            for k in np.argsort(-priced[:count], kind="stable")
            # rows of side 2 and weighted rows: no credit
            if priced[k] > 1e-9 and self.cut_sides[k] == 1.0 and self.cut_weights[k] is None
        ]
        ranked = ranked[:rows]
        bits = np.zeros((self.n, self.n), dtype=np.uint64)
        weights = np.zeros(len(ranked))
        for r, k in enumerate(ranked):
            arcs = self.cut_rows[k]
            bits[self.tails[arcs], self.heads[arcs]] |= np.uint64(1) << np.uint64(r)
            weights[r] = priced[k]
        signed = np.full((self.n, self.n), np.inf)
        signed[self.tails, self.heads] = reduced
        negative = np.flatnonzero(reduced < 0)
        negative = negative[np.argsort(reduced[negative], kind="stable")]
        # past CREDIT_NEGATIVE, the negative arcs are counted as usable by every rest (in
        # the constant): a lower bound still, only not raised when they can no longer be used
        constant += float(reduced[negative[CREDIT_NEGATIVE:]].sum())
        negative = negative[:CREDIT_NEGATIVE]
        return RowCredit(
            constant=constant,
            reduced=signed,
            bits=bits,
            weights=weights,
            negative=(self.tails[negative], self.heads[negative], reduced[negative]),
        )

    def fix_by_reduced_cost(self, incumbent: float) -> int:
        """Fix to 0 every arc that no order better than ``incumbent`` can use, by the last
        LP's reduced costs; returns how many arcs were newly fixed.

        For duals y of the right signs and ``d = c - A^T y``, every order x with
        ``x_a = 1`` costs at least ``L + d_a`` when ``d_a > 0`` (``L`` the bound of
        :meth:`~taopt.models.sop_cuts.SopCutModel.dual_bound` before rounding: the Lagrangian
        argument,
        ``c x = y^T A x + d x >= y^T b + Σ_{b ≠ a} min(0, d_b) + d_a``). An arc with
        ``L + d_a`` above ``incumbent - step`` (integral costs, ``step`` their gcd;
        ``incumbent`` otherwise) is in
        no better order, so the fixed model keeps every order better than ``incumbent``
        (with integral costs the best order itself may lose an arc; the MIP rounds then run
        with a cutoff below it, not from it).
        """
        raw, reduced = self._lagrangian()
        if not math.isfinite(raw) or not math.isfinite(incumbent):
            return 0
        if self.step:  # a better order costs incumbent - step at most
            limit = incumbent - self.step + 1e-6
        else:
            limit = incumbent + 1e-9 * max(1.0, abs(incumbent))
        drop = ~self.fixed & (reduced > 0) & (raw + reduced > limit)
        count = int(drop.sum())
        if count:
            self._fix(np.flatnonzero(drop))
            self.conditional = True
        return count

    def _fix(self, arcs: np.ndarray) -> None:
        """Fix the arcs ``arcs`` (indices) to 0, in the LP and in ``fixed``."""
        index = np.asarray(arcs, dtype=np.int32)
        self.highs.changeColsBounds(len(index), index, np.zeros(len(index)), np.zeros(len(index)))
        self.fixed[index] = True

    def install(
        self,
        rows: list[np.ndarray],
        sides: list[float],
        weights: list[np.ndarray | None],
        fixed: np.ndarray,
        conditional: bool,
    ) -> None:
        """Take in another model's rows ``Σ_k w_k x_{a_k} >= side`` (arcs, side and weights
        (None: all 1) as in ``cut_rows``, ``cut_sides`` and ``cut_weights``: the same
        rows in the same order, not checked against the rows known here, each known by its
        key after) and its arcs fixed to 0 (``fixed``, indices; ``conditional`` as there):
        the tree's peer process (:mod:`taopt.models.sop_split`) starts from its main side's
        model."""
        if rows:
            self._append(rows, sides, weights)
            self._keys.update(map(row_key, rows, sides, weights))
        if len(fixed):
            self._fix(fixed)
        self.conditional = conditional

    def root(
        self, deadline: Deadline | None = None, rounds: int = ROOT_ROUNDS, stretch: bool = False
    ) -> RootCuts:
        """The LP cut loop: solve, separate, add, until no row is violated, the value
        stalls, ``rounds`` LPs were solved or the deadline passes. ``stretch``: once no path
        or set row is violated, the stretch rows of an extended LP are tried too
        (:meth:`~taopt.models.sop_cuts.SopCutModel._stretch`; :func:`solve_sop_cuts` asks for
        them, the portfolio's root stage before the DP does not: measured at 60 s, they took
        that stage's share without raising the DP's bound, and delayed p43.1's proof from 11.9 s
        to 18.2 s)."""
        value, bound, done, complete = -math.inf, -math.inf, 0, False
        values = None
        stall, every = 0, ALL_PAIRS_FIRST
        while done < rounds:
            if deadline is not None and deadline.expired(MARGIN):
                break
            self._run(deadline)
            self.last_status = self.highs.getModelStatus()
            if self.last_status != highspy.HighsModelStatus.kOptimal:
                break
            done += 1
            self.root_duals = np.asarray(self.highs.getSolution().row_dual, dtype=float)
            new_value = float(self.highs.getInfo().objective_function_value)
            bound = max(bound, self.dual_bound())
            values = self.lp_values()
            stall = stall + 1 if new_value - value <= ROOT_STALL * max(abs(value), 1.0) else 0
            value = new_value
            if stall >= ROOT_STALL_ROUNDS:
                if every:
                    break
                every, stall = True, 0  # the subtour rows stall: every pair from now on
            cuts = self.separate(values, every=every, deadline=deadline)
            sides = None
            if not cuts and SET_CUTS:  # the pairs hold: the set path cuts
                cuts, sides = self.separate_sets(values, deadline=deadline)
            if not cuts:  # none violated, unless the deadline cut the separation short
                complete = deadline is None or not deadline.expired(MARGIN)
                if complete and stretch and self._stretch(new_value, deadline):
                    stall, stretch = 0, STRETCH_BACK_TO_BACK
                    continue
                break
            self.add_cuts(cuts, sides)
        return RootCuts(value, bound, done, len(self.cut_rows), complete, values)

    def _stretch(self, value: float, deadline: Deadline | None) -> bool:
        """Once the path and set rows hold: the stretch rows of one extended LP
        (:func:`~taopt.models.sop_stretch.stretch_rows`), at most :data:`STRETCH_ROUNDS` such LPs
        started per model; true when rows were added. An LP not
        started for lack of time is tried again when a later loop (a MIP round's) completes."""
        if self.stretch_solves >= STRETCH_ROUNDS:
            return False
        began = time.perf_counter()
        rows = stretch_rows(self, value, deadline)
        self.stretch_seconds += time.perf_counter() - began
        if rows is None:  # not started (no inner pair, or too little time): a later loop may
            return False
        self.stretch_solves += 1
        return self.add_weighted_rows(rows) > 0

    def make_integral(self, integral: bool = True) -> None:
        """Declare every arc binary (the MIP of the rows found so far), or continuous again."""
        if self.is_mip != integral:
            kind = highspy.HighsVarType.kInteger if integral else highspy.HighsVarType.kContinuous
            self.highs.changeColsIntegrality(
                self.n_arcs, np.arange(self.n_arcs, dtype=np.int32), np.full(self.n_arcs, kind)
            )
            self.is_mip = integral

    def path(self, values: np.ndarray) -> list[int] | None:
        """The order the integral point ``values`` describes, or None when its arcs are not
        one path start -> end through every node."""
        chosen = values > 0.5
        successor = dict(zip(self.tails[chosen].tolist(), self.heads[chosen].tolist(), strict=True))
        order = [self.problem.start]
        while order[-1] in successor and len(order) <= self.n:
            order.append(successor[order[-1]])
        if len(order) != self.n or order[-1] != self.problem.end:
            return None
        return order


def cut_bound(problem: SopProblem, time_limit: float | None = None) -> RootCuts:
    """The root bound of the precedence path cuts (the LP cut loop of :class:`SopCutModel`)."""
    return SopCutModel(problem).root(Deadline(time_limit))


#: Whether HiGHS runs its sub-MIP and jump heuristics (RINS, RENS, root reduced cost,
#: feasibility jump: :data:`SUB_HEURISTIC_OPTIONS`) in the MIP rounds. Off, p43.1's rounds
#: took 2.4 s instead of 6.5 s and the proof came in 49-55 s from the warm start (load 4-5),
#: but on prob.42 a round without them ran 16.4 s from 14.5 s before the deadline (ended
#: 4.2 s past it; 10 s past it in another run): HiGHS then looks at its clock and interrupt
#: callback too seldom. On (HiGHS's default) until that is bounded.
MIP_SUB_HEURISTICS = True

#: The HiGHS options switched off when :data:`MIP_SUB_HEURISTICS` is False.
SUB_HEURISTIC_OPTIONS = (
    "mip_heuristic_run_rins",
    "mip_heuristic_run_rens",
    "mip_heuristic_run_root_reduced_cost",
    "mip_heuristic_run_feasibility_jump",
)

#: A MIP round gets the time left less this share of it (at most :data:`MIP_RESERVE_MAX`
#: seconds): HiGHS looks at its clock and its interrupt callback only between the phases of
#: its root node, and MIP rounds ended 1-7 s after the deadline at load 3-12 without it.
MIP_RESERVE = 0.1

#: See :data:`MIP_RESERVE`.
MIP_RESERVE_MAX = 3.0

#: After the root and after each LP loop between MIP rounds, arcs are fixed to 0 by their
#: reduced costs against the best order
#: (:meth:`~taopt.models.sop_cuts.SopCutModel.fix_by_reduced_cost`).
REDUCED_COST_FIXING = True

#: The cuts HiGHS finds at the root of a MIP round (its cut pool, read by the
#: ``kCallbackMipGetCutPool`` callback, the MIP solved without presolve so that they use the
#: model's columns) are kept as rows for the next rounds, when every integral point HiGHS
#: held when it reported them was an order. Such a row holds for every integral point of the
#: rows before it below the round's cutoff and those orders' costs, hence for every order
#: better than the best one.
KEEP_HIGHS_CUTS = True

#: LP rounds of the cut loop between two MIP rounds at most.
ROUND_LP_ROUNDS = 20

#: Integral points that are not orders kept per MIP round for separation.
BAD_POINTS = 20

#: MIP rounds (solve, check, add the violated rows) at most.
MIP_ROUNDS = 200

#: A MIP round is started only while the time left is at least this many times the last
#: round's duration: a round cut short by its time limit ends when HiGHS next looks at its
#: clock, seconds late (prob.42 at 60 s: rounds grew from 1 to 5.5 s, and a last round cut
#: short ended the run at 63.6 s, past the 63 s allowed); the time left then goes to the
#: caller's interruptible stages.
MIP_ROUND_ROOM = 1.5


def solve_sop_cuts(
    problem: SopProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    verbose: bool = False,
    mip_gap: float = 1e-9,
    model: SopCutModel | None = None,
) -> Solution:
    """Exact SOP by the precedence path cuts: the root cut loop, then MIP rounds.

    Each round solves the MIP of the degree rows and the cuts found so far with HiGHS
    (warm-started with the best order), checks its integral point, and adds the cuts the
    point violates. A relaxation's optimum that is an order is optimal; a round stopped by
    the clock leaves its proven bound (HiGHS's dual bound of a relaxation).

    Against the best order known, arcs are fixed to 0 by their reduced costs
    (:meth:`~taopt.models.sop_cuts.SopCutModel.fix_by_reduced_cost`), and the cuts HiGHS finds at
    the root of a round are kept for the next ones (:data:`KEEP_HIGHS_CUTS`); both exclude only
    orders no better than the best, so the bounds then reported are ``min(bound, best)``, and an LP
    of those rows without a point proves the best optimal. Bounds are rounded up to a multiple of
    the costs' gcd (``SopCutModel.step``).

    Parameters
    ----------
    problem : SopProblem
    time_limit : float, optional
        Wall-clock seconds for everything, the model's build included.
    incumbent : Order, list of int or Solution, optional
        A feasible order to start from.
    verbose : bool
    mip_gap : float
        HiGHS's relative gap.
    model : SopCutModel, optional
        A model of ``problem`` whose root cut loop has run already (the SOP portfolio's
        root stage): its rows are kept and the loop goes on from them. It must not have been
        fixed against an order worse than ``incumbent`` (its rows then still hold for every
        order better than the incumbent).

    Returns
    -------
    Solution
        Status "optimal" when proven, else "time_limit" with the best order and the best
        proven bound; ``info`` has ``root_bound``, ``root_rounds``, ``cuts``, ``mip_rounds``,
        ``fixed`` (arcs fixed by reduced cost), ``pool_rows`` (HiGHS's cuts kept) and
        ``detached`` (the last MIP round was left running at the deadline).
    """
    began = time.perf_counter()
    deadline = Deadline(time_limit)
    model, known, bound, info = root_stage(problem, deadline, incumbent, verbose, model)
    stop, rounds = "time_limit", 0
    if known is None or not _closed(model, bound, known[0]):
        stop, rounds, known, bound = _mip_rounds(model, deadline, known, bound, mip_gap)
    else:
        stop = "optimal"
    info.update(
        {
            "cuts": len(model.cut_rows),
            "mip_rounds": rounds,
            "arcs": model.n_arcs,
            "fixed": int(model.fixed.sum()),
            "pool_rows": model.pool_rows,
            "detached": model.detached,
        }
    )
    return cut_solution(problem, known, "exact-sop-cuts", stop, bound, began, info)


def cut_solution(
    problem: SopProblem,
    known: tuple[float, list[int]] | None,
    method: str,
    stop: str,
    bound: float,
    began: float,
    info: dict[str, Any],
) -> Solution:
    """The :class:`~taopt.result.Solution` of a cut engine (:func:`solve_sop_cuts`, and the
    branch-and-cut of :mod:`taopt.models.sop_bc`) that stopped with ``stop``: no order and an
    infinite bound when ``"infeasible"``, else the best order ``known`` and ``bound``; the
    runtime counted from ``began`` (``time.perf_counter()``)."""
    if stop == "infeasible":
        return finish(
            None,
            None,
            method=method,
            stop="infeasible",
            bound=math.inf,
            runtime=time.perf_counter() - began,
            info=info,
        )
    return finish(
        problem,
        None if known is None else Order(known[1]),
        method=method,
        stop=stop,
        bound=bound,
        runtime=time.perf_counter() - began,
        info=info,
    )


def root_stage(
    problem: SopProblem,
    deadline: Deadline,
    incumbent: Any = None,
    verbose: bool = False,
    model: SopCutModel | None = None,
    stretch: bool = True,
) -> tuple[SopCutModel, tuple[float, list[int]] | None, float, dict[str, Any]]:
    """The root of the exact cut engines (:func:`solve_sop_cuts`,
    :func:`taopt.models.sop_bc.solve_sop_bc`): the LP cut loop (stretch rows while
    :func:`_wants_stretch`), the last point rounded to an order, arcs fixed by reduced cost
    against the best order. Returns (model, best order or None, proven bound, info with
    ``root_bound``, ``root_lp``, ``root_rounds``, ``root_complete``, ``root_fixed``,
    ``root_stretch_lps`` and ``root_stretch_seconds``: the model's extended LPs and their
    seconds so far, :meth:`~taopt.models.sop_cuts.SopCutModel._stretch`).
    ``model``: as in :func:`solve_sop_cuts`. ``stretch``: False skips the stretch rows (the
    tree with a peer process, :data:`taopt.models.sop_bc.SPLIT_STRETCH`)."""
    known = _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)
    if model is None:
        model = SopCutModel(problem, verbose)
    cheap = _cheap_bound(problem)
    before = model.dual_bound() if model.is_mip is False and model.cut_rows else -math.inf
    root = model.root(deadline, stretch=stretch and _wants_stretch(known, before))
    if root.values is not None:
        rounded = round_point(model, root.values, deadline)
        if rounded is not None and (known is None or rounded[0] < known[0]):
            known = rounded
    bound = max(root.bound, cheap)
    fixed = 0
    if REDUCED_COST_FIXING and known is not None and root.values is not None:
        fixed = model.fix_by_reduced_cost(known[0])
    info: dict[str, Any] = {
        "root_bound": root.bound,
        "root_lp": root.value,
        "root_rounds": root.rounds,
        "root_complete": root.complete,
        "root_fixed": fixed,
        "root_stretch_lps": model.stretch_solves,
        "root_stretch_seconds": model.stretch_seconds,
    }
    return model, known, bound, info


def _wants_stretch(known: tuple[float, list[int]] | None, bound: float) -> bool:
    """Try the stretch rows (:data:`STRETCH_CUTS`) unless the best order is within
    :data:`STRETCH_MIN_GAP` of ``bound``: a gap that small is closed faster by the MIP rounds
    than after an extended LP of a few seconds (p43.1 in the portfolio at 60 s, load 8: proven
    in 7.6 s without the rows, 14.2 s with them)."""
    if not STRETCH_CUTS:
        return False
    if known is None or not math.isfinite(bound):
        return True
    return known[0] - bound > STRETCH_MIN_GAP * max(abs(known[0]), 1.0)


def _cost_step(costs: np.ndarray) -> int:
    """The gcd of the integral ``costs`` (1 when they are all 0 or huge)."""
    values = np.abs(costs[np.isfinite(costs)])
    if not len(values) or values.max() >= 2**62:
        return 1
    step = int(np.gcd.reduce(values.astype(np.int64)))
    return max(step, 1)


def _clipped(model: SopCutModel, bound: float, best: float) -> float:
    """A bound of the model made a bound of the SOP: ``min(bound, best)`` once arcs are
    fixed or rows valid only below the best are in (``SopCutModel.conditional``: the
    orders they exclude cost ``best`` at least), else ``bound``."""
    return min(bound, best) if model.conditional else bound


def _closed(model: SopCutModel, bound: float, value: float) -> bool:
    """The bound proves ``value`` optimal (within 1e-9 relative; integral costs: above
    ``value - step``, ``SopCutModel.step`` the costs' gcd)."""
    if model.step:
        return bound > value - model.step + 1e-6
    return bound >= value - 1e-9 * max(1.0, abs(value))


def _mip_rounds(
    model: SopCutModel,
    deadline: Deadline,
    known: tuple[float, list[int]] | None,
    bound: float,
    mip_gap: float,
) -> tuple[str, int, tuple[float, list[int]] | None, float]:
    """The MIP rounds of :func:`solve_sop_cuts`; returns (stop, rounds, best, bound).

    Every integral point HiGHS accepted in a round that is not an order (at most
    :data:`BAD_POINTS`) gives the rows it violates for the next round, which starts
    warm-started with the best order. (Interrupting a round at its first such point was
    measured worse: the bound of p43.1 stayed at 28,100 over 26 short rounds in 60 s,
    against 28,135 after 4 whole rounds.)
    """
    problem = model.problem
    model.make_integral()
    model.highs.setOptionValue("mip_rel_gap", float(mip_gap))
    for option in () if MIP_SUB_HEURISTICS else SUB_HEURISTIC_OPTIONS:
        model.highs.setOptionValue(option, False)
    if KEEP_HIGHS_CUTS:  # the pool's rows then use the model's own columns
        model.highs.setOptionValue("presolve", "off")
    bad: list[np.ndarray] = []
    seen = [0]  # integral points HiGHS accepted this round that are no order
    found: list[tuple[float, list[int]]] = []  # those that are orders

    pool: list[tuple[np.ndarray, ...]] = []

    def on_improving(event: Any) -> None:
        values = np.asarray(event.data_out.mip_solution, dtype=float)[: model.n_arcs]
        order = _order_of(model, values)
        if order is not None:  # kept even when a later point (no order) replaces it
            found.append((float(problem.cost[order[:-1], order[1:]].sum()), order))
            return
        seen[0] += 1
        if len(bad) < BAD_POINTS:
            bad.append(values.copy())

    def on_pool(event: Any) -> None:
        # kept only while every point HiGHS holds is an order: its cuts then rest on the
        # rows, the bounds, the cutoff and orders (whose cost the best order is at most),
        # never on a point that is no order
        data = event.data_out
        if seen[0] or int(data.cutpool_num_col) != model.n_arcs or not data.cutpool_num_cut:
            return
        pool.append(
            tuple(
                np.array(item, copy=True)
                for item in (
                    data.cutpool_start,
                    data.cutpool_index,
                    data.cutpool_value,
                    data.cutpool_lower,
                    data.cutpool_upper,
                )
            )
        )

    model.highs.cbMipImprovingSolution.subscribe(on_improving)
    if KEEP_HIGHS_CUTS:
        model.highs.cbMipGetCutPool.subscribe(on_pool)
    stop, rounds = "time_limit", 0
    last = 0.0  # the last MIP round's seconds
    try:
        while rounds < MIP_ROUNDS and not deadline.expired(MARGIN):
            if deadline.limited and (deadline.remaining() or 0.0) < MIP_ROUND_ROOM * last:
                break  # no room for a whole round: stop before one is cut short
            if rounds:  # separate the new rows' fractional consequences on the LP first
                model.make_integral(False)
                lp = model.root(deadline, ROUND_LP_ROUNDS, stretch=_wants_stretch(known, bound))
                if (
                    model.last_status == highspy.HighsModelStatus.kInfeasible
                    and known is not None
                    and model.conditional
                ):  # no point of the rows valid below the best: nothing better than it
                    return "optimal", rounds, known, known[0]
                if known is not None:
                    bound = max(bound, _clipped(model, lp.bound, known[0]))
                    if REDUCED_COST_FIXING and lp.rounds:
                        model.fix_by_reduced_cost(known[0])
                model.make_integral()
            # integral costs: an order better than the best costs at most best - step (the
            # costs' gcd), so HiGHS may cut off every node above best - step + 1/2; no point
            # below it proves the best
            cutoff = known[0] - model.step + 0.5 if known is not None and model.step else None
            if known is not None and cutoff is None:
                start = np.zeros(model.n_arcs)
                start[model.arc_index[known[1][:-1], known[1][1:]]] = 1.0
                model.highs.setSolution(_solution(start))
            bad.clear()
            pool.clear()
            found.clear()
            seen[0] = 0
            model.highs.setOptionValue(
                "objective_bound", highspy.kHighsInf if cutoff is None else cutoff
            )
            began = time.perf_counter()
            try:
                model._run(deadline)
            finally:  # the LP loop must not stop at the cutoff
                if not model.detached:
                    model.highs.setOptionValue("objective_bound", highspy.kHighsInf)
            last = time.perf_counter() - began
            rounds += 1
            for value, seen_order in list(found):
                if known is None or value < known[0]:
                    known = (value, seen_order)
            if model.detached:  # past the deadline and still running: keep what is known
                return stop, rounds, known, bound
            # read before the pool's rows go in: changing the model resets HiGHS's status, and
            # a round proved infeasible below the cutoff was then taken for an open one
            status = model.highs.getModelStatus()
            mip_info = model.highs.getInfo()
            for rows in pool:  # HiGHS's root cuts: valid below the cutoff and the orders seen
                if model.add_pool_rows(*rows) and (cutoff is not None or found):
                    model.conditional = True
            if status == highspy.HighsModelStatus.kInfeasible and known is not None:
                if cutoff is None:  # a relaxation without the best order: cannot happen
                    break
                return "optimal", rounds, known, known[0]  # nothing below best - 1/2
            dual = float(mip_info.mip_dual_bound)
            if math.isfinite(dual):  # a bound of a relaxation: a bound of the SOP
                dual = model.round_up(dual)
                bound = max(bound, dual if known is None else _clipped(model, dual, known[0]))
            if status == highspy.HighsModelStatus.kInfeasible and known is None:
                return "infeasible", rounds, None, math.inf
            points = list(bad)
            for point in points:  # each point, rounded and polished, may be a better order
                if deadline.expired(MARGIN):
                    break
                rounded = round_point(model, point, deadline)
                if rounded is not None and (known is None or rounded[0] < known[0]):
                    known = rounded
            if mip_info.primal_solution_status == 2:
                values = model.lp_values()
                order = _order_of(model, values)
                if order is None:
                    points.append(values)
                else:
                    value = float(problem.cost[order[:-1], order[1:]].sum())
                    if known is None or value < known[0]:
                        known = (value, order)
                    if status == highspy.HighsModelStatus.kOptimal:
                        # the relaxation's optimum is an order: optimal
                        return "optimal", rounds, known, max(bound, value)
            if known is not None and _closed(model, bound, known[0]):
                return "optimal", rounds, known, bound
            if not points or deadline.expired(MARGIN):
                break  # stopped by the clock (or a HiGHS limit) with no point to cut
            cuts = [cut for point in points for cut in model.separate(point, deadline=deadline)]
            if not cuts:
                break  # an integral point that is no order violates a row: stay safe
            model.add_cuts(cuts)
    finally:
        if not model.detached:  # a detached run keeps its callbacks until it ends
            model.highs.cbMipImprovingSolution.unsubscribe(on_improving)
            if KEEP_HIGHS_CUTS:
                model.highs.cbMipGetCutPool.unsubscribe(on_pool)
    return stop, rounds, known, bound


def _order_of(model: SopCutModel, values: np.ndarray) -> list[int] | None:
    """The feasible order of the integral point ``values``, or None."""
    order = model.path(values)
    problem = model.problem
    if (
        order is None
        or _known_order(problem.cost, problem.closure, problem.start, problem.end, order) is None
    ):
        return None
    return order


def _solution(values: np.ndarray) -> highspy.HighsSolution:
    """A HiGHS solution holding the column values ``values`` (a MIP start)."""
    solution = highspy.HighsSolution()
    solution.col_value = values.tolist()
    solution.value_valid = True
    return solution


#: Passes of the relocation search that polishes an order rounded from a point.
POLISH_PASSES = 20

#: Runs whose moves :func:`polish` evaluates together (one numpy evaluation of this many runs
#: by every place). Not tuned: large enough that an order of some 50 nodes takes one or two
#: evaluations a pass when nothing moves, small enough that a move on an order of hundreds
#: of nodes does not re-evaluate hundreds of runs.
POLISH_BLOCK = 32


def round_point(
    model: SopCutModel, values: np.ndarray, deadline: Deadline | None = None
) -> tuple[float, list[int]] | None:
    """An order built from the point ``values`` (LP or integral), polished by relocation.

    From start, the next node is the eligible one (unvisited, all its predecessors visited,
    a usable arc from the last node) of the largest ``x[last, v]``, ties by cost; end comes
    last. Returns ``(cost, order)`` or None at a dead end. The polish stops at ``deadline``.
    """
    problem = model.problem
    n, cost, before = model.n, problem.cost, model.before
    weight = np.zeros((n, n))
    weight[model.tails, model.heads] = values
    usable = model.arc_index >= 0
    missing = before.sum(axis=0).astype(np.int64)  # predecessors not yet visited
    visited = np.zeros(n, dtype=bool)
    order = [problem.start]
    visited[problem.start] = True
    missing[before[problem.start]] -= 1
    for _ in range(n - 1):
        last = order[-1]
        eligible = ~visited & (missing == 0) & usable[last]
        if not eligible.any():
            return None
        candidates = np.flatnonzero(eligible)
        best = candidates[np.lexsort((cost[last, candidates], -weight[last, candidates]))[0]]
        order.append(int(best))
        visited[best] = True
        missing[before[best]] -= 1
    if order[-1] != problem.end:
        return None
    return polish(model, order, deadline)


def polish(
    model: SopCutModel, order: list[int], deadline: Deadline | None = None
) -> tuple[float, list[int]]:
    """Or-opt search: move a run of 1, 2 or 3 consecutive nodes to another place while that
    keeps the precedences and lowers the path's cost (first improvement per run, best place;
    :data:`POLISH_PASSES` passes at most, none started after ``deadline``).

    A run may go between ``rest[q - 1]`` and ``rest[q]`` (``rest`` the order without it) when
    no predecessor of a node of the run is at or after q and no successor is before q.

    The runs are visited in the order of their first position p (for each length), each
    moved to its best place when that saves; the moves of the next :data:`POLISH_BLOCK` runs
    from p on are evaluated at once (:func:`_first_move`), so a pass costs one numpy
    evaluation per move made plus one per block, not one per run (the same moves as one run
    at a time: a run that does not move leaves the order as it was). The block bounds an
    evaluation's work (``POLISH_BLOCK`` runs by ``n`` places) where many moves are made on
    a long order.
    """
    cost, before = model.problem.cost, model.before
    current = np.asarray(order, dtype=np.int64)
    n = len(current)
    for _ in range(POLISH_PASSES):
        if deadline is not None and deadline.expired(MARGIN):
            break
        improved = False
        for length in (1, 2, 3):
            p = 1
            while p + length <= n - 1:
                stop = min(p + POLISH_BLOCK, n - length)
                move = _first_move(cost, before, current, length, p, stop)
                if move is None:
                    p = stop
                    continue
                p, place = move
                rest = np.concatenate([current[:p], current[p + length :]])
                current = np.concatenate([rest[:place], current[p : p + length], rest[place:]])
                improved = True
                p += 1
        if not improved:
            break
    return float(cost[current[:-1], current[1:]].sum()), current.tolist()


def _first_move(
    cost: np.ndarray, before: np.ndarray, order: np.ndarray, length: int, first: int, stop: int
) -> tuple[int, int] | None:
    """The first run of ``length`` nodes at a position ``first <= p < stop`` of ``order``
    (``stop <= len(order) - length``) with a saving place, as (p, its best place in the
    order without the run), or None.

    For every such p at once: ``rest`` the order without the run, a place q (between
    ``rest[q - 1]`` and ``rest[q]``, ``1 <= q < len(rest)``) is allowed after the last
    predecessor of the run in ``rest`` and not after its first successor; the saving of q is
    ``cost[rest[q - 1], run[0]] + cost[run[-1], rest[q]] - cost[rest[q - 1], rest[q]]``
    minus the cost the run's removal saves (``inf - inf`` counts as no saving); the best
    place is the first of the least value, a saving when below ``-1e-9``.
    """
    n = len(order)
    starts = np.arange(first, stop)
    size = n - length  # len(rest)
    places = np.arange(size)
    # rest[p, r]: the order without the run at p
    rest = order[places[None, :] + length * (places[None, :] >= starts[:, None])]
    runs = order[starts[:, None] + np.arange(length)[None, :]]
    preds = before[rest[:, :, None], runs[:, None, :]].any(axis=2)
    succs = before[runs[:, None, :], rest[:, :, None]].any(axis=2)
    lo = np.where(preds.any(axis=1), size - np.argmax(preds[:, ::-1], axis=1), 1)
    hi = np.where(succs.any(axis=1), np.argmax(succs, axis=1), size - 1)
    head, tail = runs[:, 0], runs[:, -1]
    q = places[1:]
    prev, nxt = rest[:, :-1], rest[:, 1:]
    added = cost[prev, head[:, None]] + cost[tail[:, None], nxt]
    with np.errstate(invalid="ignore"):  # inf - inf where a forbidden arc meets another
        removed = (
            cost[order[starts - 1], head]
            + cost[tail, order[starts + length]]
            - cost[order[starts - 1], order[starts + length]]
        )
        delta = added - cost[prev, nxt] - removed[:, None]
    delta[np.isnan(delta)] = np.inf
    delta[(q[None, :] < np.maximum(lo, 1)[:, None]) | (q[None, :] > hi[:, None])] = np.inf
    best = np.argmin(delta, axis=1)
    saving = delta[np.arange(len(starts)), best] < -1e-9
    if not saving.any():
        return None
    k = int(np.argmax(saving))
    return int(starts[k]), int(q[best[k]])
