"""A best-first branch-and-cut of our own over the cut model of the SOP, HiGHS as the LP engine.

HiGHS offers no callback through which our rows could enter its own branch-and-bound (its
issues 1837 and 3078), so :func:`~taopt.models.sop_cuts.solve_sop_cuts` solves MIPs of the
rows found so far and restarts them. Here the tree is ours: every node is the LP of
:class:`~taopt.models.sop_cuts.SopCutModel` (the degree rows and every row separated so
far, at any node) with some arcs' bounds changed, re-solved warm by HiGHS's dual simplex
from its parent's basis, and at every node the root's separation (precedence path cuts by
maximum flow, set path cuts, alternation rows, lifting) adds rows to the one model.

Validity
--------
* **Rows are global.** Every row the separation adds holds for every order (the proofs are in
  :mod:`taopt.models.sop_cuts`), so a row found at one node holds at every node; rows valid
  only for the orders better than the best known one (``SopCutModel.conditional``: the root's
  reduced-cost fixing) are handled by the bound's form below.
* **Branching partitions the orders.** A node's orders are those using every arc of its
  ``ones`` and none of its ``zeros``. *Arc branching* on a fractional ``x_a`` gives the
  children ``x_a = 1`` and ``x_a = 0``. *Out-arc split* (the classic ATSP rule): an order
  leaves a node v (not the end) by exactly one arc, so for a split of v's usable out-arcs
  into ``F`` and the rest ``R``, "no arc of F" and "no arc of R" cover every order of the
  node, the children fixing F or R to 0 (likewise for the in-arcs of a node other than the
  start).
* **Node bound.** For the node's LP with row duals ``y`` (clipped to their signs,
  :func:`~taopt.models.sop_statelp.clipped_duals`) and ``d = c - A^T y``, every point x of
  the rows inside the node's box ``l <= x <= u`` has
  ``c x = y^T A x + d x >= y^T b + Σ_a min(d_a l_a, d_a u_a)`` (weak duality; the arcs fixed
  at the root contribute 0), whatever the LP solver's accuracy: :func:`node_bound`. Every
  order of the node better than the best known one satisfies the rows and the box, so it
  costs that much; rounded up to a multiple of ``SopCutModel.step`` for integral costs.
* **Node fixing by reduced cost.** With that bound ``L`` of a node and the best order's cost
  ``z``, an order of the node using an arc a with ``l_a = 0 < d_a`` costs at least
  ``L + d_a``, one not using an arc with ``u_a = 1, d_a < 0`` at least ``L - d_a``; where
  that exceeds ``z - step`` (``z`` for non-integral costs) no better order of the node uses
  (misses) it, and the node's subtree fixes it.
* **The proven bound** is ``min(z, min over open nodes of their bounds)``: every order better
  than z lies in an open node (pruned nodes hold none: their bound is at least z, or their
  LP is infeasible, or their point is an order, hence the cheapest of their orders), so it
  costs at least that minimum. It holds whenever the search stops; with best-first selection
  it is the bound of the node being solved.

An integral node point is either an order (checked with the problem's own test, it is the
node's optimum and the node is closed) or violates a path cut (a cycle apart from the path is
not reached from the start; an inversion of ``i ≺ j`` leaves i with no way to j; exact
separation finds it).

References
----------
N. Ascheuer, M. Jünger, G. Reinelt, "A branch & cut algorithm for the asymmetric traveling
salesman problem with precedence constraints", Comput. Optim. Appl. 17 (2000) (the out-arc
split, their branching of choice). Thesis (5.7), (2.5).
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass, field
from typing import Any

import highspy
import numpy as np
import scipy.sparse as sp

from taopt.models.sop_cuts import (
    SET_CUTS,
    SopCutModel,
    _order_of,
    cut_solution,
    root_stage,
    round_point,
)
from taopt.models.sop_statelp import clipped_duals, constraint_matrix
from taopt.result import Solution
from taopt.runtime import MARGIN, Deadline
from taopt.sop.problem import SopProblem

__all__ = [
    "BRANCHING",
    "NODE_ROUNDS",
    "NODE_FULL",
    "NODE_STALL",
    "NODE_TIGHT",
    "ROUND_EVERY",
    "STRONG_CANDIDATES",
    "STRONG_ITERATIONS",
    "TREE_MIN_GAP",
    "BranchCut",
    "Rows",
    "node_bound",
    "solve_sop_bc",
    "wants_tree",
]

#: The branching rule: ``"split"`` (the out/in-arc split of the node whose split is nearest
#: one half) or ``"arc"`` (the most fractional arc).
BRANCHING = "split"

#: LP rounds (solve, separate, add) per node at most before it branches.
NODE_ROUNDS = 8

#: A node stops separating once a round raises its LP value by less than this fraction.
NODE_STALL = 1e-4

#: At a fractional node point, the pairs other than ``(start, k)`` are separated only where
#: their last maximum flow (``SopCutModel.flows``) was below ``1 + NODE_TIGHT`` (a heuristic:
#: every row found is valid; the integral points, and every :data:`NODE_FULL`-th node, get
#: every pair, so an integral point that is no order is always cut).
NODE_TIGHT = 0.5

#: See :data:`NODE_TIGHT`.
NODE_FULL = 16

#: The node's last LP point is rounded to an order (:func:`~taopt.models.sop_cuts.round_point`)
#: at every this-many-th node (and at every node while no order is known).
ROUND_EVERY = 4

#: Strong branching: the child LPs of this many candidate branchings are solved and the one
#: whose two children gain most (product) is taken; 1 takes the first candidate (nearest 1/2).
STRONG_CANDIDATES = 8

#: Simplex iterations of a strong-branching child LP at most.
STRONG_ITERATIONS = 200

#: HiGHS's default ``simplex_iteration_limit`` (none), restored after strong branching.
ITERATIONS_UNLIMITED = 2**31 - 1

#: A value this close to 0 or 1 is integral.
INTEGRAL = 1e-6


#: HiGHS's basis statuses by their values (a basis is kept per open node as int8 arrays).
_STATUSES = {int(status): status for status in highspy.HighsBasisStatus.__members__.values()}


def _packed(statuses: Any) -> np.ndarray:
    """Basis statuses as an int8 array (a node's basis in 1 byte per column and row)."""
    return np.fromiter((int(status) for status in statuses), dtype=np.int8)


@dataclass
class Rows:
    """The model's rows as of ``count`` rows: ``A^T`` (columns x rows, CSR) and the row
    sides, read once from HiGHS (:func:`~taopt.models.sop_statelp.constraint_matrix`) and kept
    while no row is added (the tree's LPs between two separations)."""

    count: int
    transposed: sp.csr_matrix
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def of(cls, model: SopCutModel) -> Rows:
        """The rows of ``model``'s HiGHS object now."""
        lp = model.highs.getLp()
        return cls(
            int(lp.num_row_),
            constraint_matrix(lp).T.tocsr(),
            np.asarray(lp.row_lower_, dtype=float),
            np.asarray(lp.row_upper_, dtype=float),
        )


def node_bound(
    model: SopCutModel, lower: np.ndarray, upper: np.ndarray, rows: Rows | None = None
) -> tuple[float, np.ndarray]:
    """(The weak-duality bound of the last LP for the box ``lower <= x <= upper``, the arcs'
    reduced costs ``d``); ``(-inf, empty)`` without duals.

    ``y^T b + Σ_a min(d_a lower_a, d_a upper_a)`` over the arcs not fixed at the root (the
    module's "Node bound"), ``y`` the row duals clipped to their signs; unrounded. ``rows``:
    the model's rows now (read from HiGHS when None).
    """
    if rows is None:
        rows = Rows.of(model)
    solution = model.highs.getSolution()
    if not solution.dual_valid:
        return -math.inf, np.zeros(0)
    y, constant = clipped_duals(np.asarray(solution.row_dual, dtype=float), rows.lower, rows.upper)
    reduced = model.costs - rows.transposed @ y
    free = ~model.fixed
    d = reduced[free]
    terms = np.minimum(d * lower[free], d * upper[free])
    return float(constant.sum() + terms.sum()), reduced


@dataclass(order=True)
class _Node:
    """An open node: its bound, then deeper first, then the older first."""

    bound: float
    depth_key: int
    number: int
    ones: np.ndarray = field(compare=False)
    zeros: np.ndarray = field(compare=False)
    basis: Any = field(compare=False, default=None)
    parent: int = field(compare=False, default=-1)


@dataclass
class BranchCut:
    """The tree's state: the model (its root loop run), the best order, the open nodes and
    the counts. :meth:`run` searches until the tree is empty, the deadline or a node limit.

    Attributes
    ----------
    model : SopCutModel
    known : (cost, order) or None
        The best order.
    branching : str
        :data:`BRANCHING`'s values.
    nodes, lps, cuts : int
        Nodes solved, LPs solved, rows added in the tree.
    trace : list of (seconds, bound)
        The proven bound each time it rose (seconds since ``began``).
    """

    model: SopCutModel
    known: tuple[float, list[int]] | None
    branching: str = BRANCHING
    began: float = field(default_factory=time.perf_counter)
    nodes: int = 0
    lps: int = 0
    cuts: int = 0
    max_depth: int = 0
    trace: list[tuple[float, float]] = field(default_factory=list)
    _open: list[_Node] = field(default_factory=list)
    _count: int = 0
    _last: int = -1  # the node whose LP HiGHS holds
    _changed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    _rows: Rows | None = None

    def _bound_of(self, lower: np.ndarray, upper: np.ndarray) -> tuple[float, np.ndarray]:
        """:func:`node_bound` of the last LP, the rows read again only when rows were added."""
        if self._rows is None or self._rows.count != self.model.highs.getNumRow():
            self._rows = Rows.of(self.model)
        return node_bound(self.model, lower, upper, self._rows)

    # ------------------------------------------------------------------ bounds
    def _limit(self) -> float:
        """An order better than the best costs at most this (``inf`` without one)."""
        if self.known is None:
            return math.inf
        z, step = self.known[0], self.model.step
        return z - step + 1e-6 if step else z - 1e-9 * max(1.0, abs(z))

    def bound(self, current: float = math.inf) -> float:
        """The proven bound: ``min(best, open nodes' bounds, current)``."""
        least = min([node.bound for node in self._open] + [current])
        return least if self.known is None else min(least, self.known[0])

    def _record(self, value: float) -> None:
        if not self.trace or value > self.trace[-1][1]:
            self.trace.append((time.perf_counter() - self.began, value))

    # ------------------------------------------------------------------ nodes
    def _push(
        self, bound: float, depth: int, ones: np.ndarray, zeros: np.ndarray, basis: Any, parent: int
    ) -> None:
        self._count += 1
        heapq.heappush(self._open, _Node(bound, -depth, self._count, ones, zeros, basis, parent))

    def _apply(self, node: _Node) -> tuple[np.ndarray, np.ndarray]:
        """Set the node's column bounds in HiGHS (the previous node's undone) and its basis;
        returns the box (lower, upper)."""
        model = self.model
        highs = model.highs
        self._undo()
        lower = np.zeros(model.n_arcs)
        upper = np.where(model.fixed, 0.0, 1.0)
        lower[node.ones] = 1.0
        upper[node.zeros] = 0.0
        changed = np.union1d(node.ones, node.zeros).astype(np.int32)
        if len(changed):
            highs.changeColsBounds(len(changed), changed, lower[changed], upper[changed])
        self._changed = changed
        if node.basis is not None and node.parent != self._last:
            col_status, row_status = node.basis
            basis = highspy.HighsBasis()
            basis.col_status = [_STATUSES[k] for k in col_status.tolist()]
            rows = highs.getNumRow()
            # rows added since: basic (their slacks), as HiGHS itself keeps them
            basis.row_status = [_STATUSES[k] for k in row_status.tolist()] + [
                highspy.HighsBasisStatus.kBasic
            ] * (rows - len(row_status))
            basis.valid = True
            highs.setBasis(basis)
        self._last = node.number
        return lower, upper

    def _new_order(self, candidate: tuple[float, list[int]] | None) -> None:
        if candidate is not None and (self.known is None or candidate[0] < self.known[0]):
            self.known = candidate

    def run(
        self, deadline: Deadline, node_limit: int | None = None, root_bound: float = -math.inf
    ) -> str:
        """Search from the root node (of bound ``root_bound``); returns ``"optimal"`` (tree empty), ``"infeasible"`` (tree
        empty, no order), or ``"time_limit"`` (deadline or ``node_limit`` nodes)."""
        model = self.model
        model.make_integral(False)
        empty = np.zeros(0, dtype=np.int64)
        if not self._open and self.nodes == 0:
            self._push(root_bound, 0, empty, empty, None, -1)
        try:
            return self._search(deadline, node_limit)
        finally:  # the model's LP as before the tree (the portfolio's later stages re-solve it)
            self._undo()
            self._last = -1

    def _undo(self) -> None:
        """Put back the root's bounds of the columns the last node changed (0 or 1; 0 for
        the arcs fixed at the root)."""
        back = self._changed
        if len(back):
            self.model.highs.changeColsBounds(
                len(back), back, np.zeros(len(back)), np.where(self.model.fixed[back], 0.0, 1.0)
            )
        self._changed = np.zeros(0, dtype=np.int32)

    def _search(self, deadline: Deadline, node_limit: int | None) -> str:
        """The loop of :meth:`run`."""
        while self._open:
            if deadline.expired(MARGIN) or (node_limit is not None and self.nodes >= node_limit):
                return "time_limit"
            node = heapq.heappop(self._open)
            if node.bound > self._limit():
                continue
            self._record(self.bound(node.bound))
            if not self._solve(node, deadline):
                heapq.heappush(self._open, node)  # stopped inside: still open
                return "time_limit"
        if self.known is None:
            return "infeasible"
        self._record(self.known[0])
        return "optimal"

    def _solve(self, node: _Node, deadline: Deadline) -> bool:
        """Solve one node: LP rounds with separation, then prune, close or branch. False when
        the deadline stopped it before its children were pushed (the node stays open)."""
        model = self.model
        if model.fixed[node.ones].any():
            return True  # an arc no better order uses: no better order here
        lower, upper = self._apply(node)
        self.nodes += 1
        depth = -node.depth_key
        self.max_depth = max(self.max_depth, depth)
        value, bound, raw = -math.inf, node.bound, -math.inf
        values = np.zeros(0)
        reduced = np.zeros(0)
        rounds = 0
        while True:
            if deadline.expired(MARGIN):
                return False
            model._run(deadline)
            status = model.highs.getModelStatus()
            if status == highspy.HighsModelStatus.kInfeasible:
                return True  # no point of the rows in the box: no (better) order here
            if status != highspy.HighsModelStatus.kOptimal:
                return False  # stopped by the clock
            self.lps += 1
            raw, reduced = self._bound_of(lower, upper)
            bound = max(bound, model.round_up(raw))
            if bound > self._limit():
                return True
            values = model.lp_values()
            new_value = float(model.highs.getInfo().objective_function_value)
            integral = not ((values > INTEGRAL) & (values < 1 - INTEGRAL)).any()
            if integral:
                order = _order_of(model, values)
                if order is not None:  # the node's optimum (its LP's) is this order
                    self._new_order((float(model.problem.cost[order[:-1], order[1:]].sum()), order))
                    return True
            elif rounds >= NODE_ROUNDS or (
                rounds and new_value - value <= NODE_STALL * max(abs(value), 1.0)
            ):
                break
            value, rounds = new_value, rounds + 1
            among = None
            if not integral and self.nodes % NODE_FULL:  # the nearly tight pairs (heuristic)
                among = model.flows[model.pairs[:, 0], model.pairs[:, 1]] < 1 + NODE_TIGHT
            cuts = model.separate(values, deadline=deadline, among=among)
            sides = None
            if not cuts and SET_CUTS:
                cuts, sides = model.separate_sets(values, deadline=deadline)
            if not cuts:
                if integral:  # an integral non-order violates a row (module doc): the
                    return False  # deadline cut the separation short
                break
            self.cuts += model.add_cuts(cuts, sides)
        if deadline.expired(MARGIN):
            return False
        if self.known is None or self.nodes % ROUND_EVERY == 1:
            self._new_order(round_point(model, values, deadline))
        if bound > self._limit():
            return True
        # node fixing by reduced cost against the best order (the module's proof)
        ones, zeros = node.ones, node.zeros
        limit = self._limit()
        if math.isfinite(limit) and len(reduced):
            free = ~model.fixed & (lower < 0.5) & (upper > 0.5)
            zeros = np.union1d(
                zeros, np.flatnonzero(free & (reduced > 0) & (raw + reduced > limit))
            )
            ones = np.union1d(ones, np.flatnonzero(free & (reduced < 0) & (raw - reduced > limit)))
        basis = model.highs.getBasis()
        saved = (_packed(basis.col_status), _packed(basis.row_status))
        candidates = self._candidates(values, ones, zeros)
        pick, bounds = candidates[0], [bound, bound]
        if STRONG_CANDIDATES > 1 and len(candidates) > 1:
            pick, bounds = self._strong(candidates, lower, upper, basis, bound, deadline)
        for (child_ones, child_zeros), child_bound in zip(pick, bounds, strict=True):
            if child_bound <= self._limit():
                self._push(child_bound, depth + 1, child_ones, child_zeros, saved, node.number)
        return True

    # ------------------------------------------------------------------ branching
    def _candidates(
        self, values: np.ndarray, ones: np.ndarray, zeros: np.ndarray
    ) -> list[list[tuple[np.ndarray, np.ndarray]]]:
        """Branchings of a node with LP point ``values``, best first, at most
        :data:`STRONG_CANDIDATES` (one at least): each two children (ones, zeros) that
        partition the node's orders (module doc). ``"split"``: the out/in-arc splits nearest
        1/2 (the arcs rule when no node has one); ``"arc"``: the most fractional arcs."""
        count = max(STRONG_CANDIDATES, 1)
        if self.branching == "split":
            splits = self._splits(values, ones, zeros)[:count]
            if splits:
                return [
                    [(ones, np.union1d(zeros, first)), (ones, np.union1d(zeros, rest))]
                    for first, rest in splits
                ]
        fractional = np.flatnonzero((values > INTEGRAL) & (values < 1 - INTEGRAL))
        if not len(fractional):  # an integral point cut by no row: cannot happen (module doc)
            raise RuntimeError("an integral point that is no order violates no row")
        ranked = fractional[np.argsort(np.abs(values[fractional] - 0.5), kind="stable")]
        return [
            [(np.union1d(ones, [arc]), zeros), (ones, np.union1d(zeros, [arc]))]
            for arc in ranked[:count].tolist()
        ]

    def _strong(
        self,
        candidates: list[list[tuple[np.ndarray, np.ndarray]]],
        lower: np.ndarray,
        upper: np.ndarray,
        basis: Any,
        bound: float,
        deadline: Deadline,
    ) -> tuple[list[tuple[np.ndarray, np.ndarray]], list[float]]:
        """Strong branching: each candidate's two child LPs (warm from the node's basis, at
        most :data:`STRONG_ITERATIONS` simplex iterations, no separation); the candidate of
        the largest product of the two children's gains over ``bound`` is taken. Returns it
        and its children's proven bounds: the node bound of a child LP solved to its end
        (:func:`node_bound` on the child's box; ``inf`` for an infeasible one), else
        ``bound``. The node's box and basis are restored after each child."""
        model = self.model
        highs = model.highs
        highs.setOptionValue("simplex_iteration_limit", STRONG_ITERATIONS)
        best: tuple[float, int, list[float]] = (-math.inf, 0, [bound, bound])
        try:
            for number, children in enumerate(candidates):
                proven, gains = [], []
                for child_ones, child_zeros in children:
                    if deadline.expired(MARGIN):
                        return candidates[best[1]], best[2]
                    child_lower = np.zeros(model.n_arcs)
                    child_lower[child_ones] = 1.0
                    child_upper = np.where(model.fixed, 0.0, 1.0)
                    child_upper[child_zeros] = 0.0
                    changed = np.flatnonzero(
                        (child_lower != lower) | (child_upper != upper)
                    ).astype(np.int32)
                    highs.changeColsBounds(
                        len(changed), changed, child_lower[changed], child_upper[changed]
                    )
                    model._run(deadline)
                    self.lps += 1
                    status = highs.getModelStatus()
                    value = bound
                    if status == highspy.HighsModelStatus.kInfeasible:
                        value = math.inf
                    elif status == highspy.HighsModelStatus.kOptimal:
                        raw, _ = self._bound_of(child_lower, child_upper)
                        value = max(bound, model.round_up(raw))
                    proven.append(value)
                    gain = value
                    if status not in (
                        highspy.HighsModelStatus.kInfeasible,
                        highspy.HighsModelStatus.kOptimal,
                    ):  # stopped by its iteration limit: its value scores it only
                        gain = max(bound, float(highs.getInfo().objective_function_value))
                    gains.append(min(gain - bound, 1e12) + 1e-6 * max(abs(bound), 1.0))
                    highs.changeColsBounds(len(changed), changed, lower[changed], upper[changed])
                    highs.setBasis(basis)
                score = gains[0] * gains[1]
                if score > best[0]:
                    best = (score, number, proven)
        finally:
            highs.setOptionValue("simplex_iteration_limit", ITERATIONS_UNLIMITED)
        return candidates[best[1]], best[2]

    def _splits(
        self, values: np.ndarray, ones: np.ndarray, zeros: np.ndarray
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """The out- and in-arc splits (F, rest of the node's open arcs), ``x(F)`` nearest
        1/2 first, over the nodes with two open arcs of positive value at least and no arc
        fixed to 1 on that side; F is built greedily from the arcs of largest value."""
        model = self.model
        open_arc = ~model.fixed
        open_arc[zeros] = False
        found: list[tuple[float, np.ndarray, np.ndarray]] = []
        for ends in (model.tails, model.heads):
            positive = open_arc & (values > INTEGRAL)
            counts = np.bincount(ends[positive], minlength=model.n)
            counts[ends[ones]] = 0
            for v in np.flatnonzero(counts >= 2):
                arcs = np.flatnonzero(open_arc & (ends == v))
                ranked = arcs[np.argsort(-values[arcs], kind="stable")]
                total = np.cumsum(values[ranked])
                k = int(np.argmin(np.abs(total - 0.5)))
                k = min(k, len(ranked) - 2)  # F and the rest both non-empty
                found.append((abs(float(total[k]) - 0.5), ranked[: k + 1], ranked[k + 1 :]))
        found.sort(key=lambda item: item[0])
        return [(first, rest) for _, first, rest in found]


#: The portfolio (:func:`taopt.models.sop.solve_sop_problem`'s last cut stage) runs this tree
#: in place of the MIP rounds of :func:`~taopt.models.sop_cuts.solve_sop_cuts` while the best
#: order is more than this share above the best bound (:func:`wants_tree`).
TREE_MIN_GAP = 0.01


def wants_tree(value: float, bound: float) -> bool:
    """The tree, not the MIP rounds, for a gap above :data:`TREE_MIN_GAP` (of ``value``).

    Measured at 60 s from no order, load 3.4-6 (``bench_sop.py --tree 60``, docs/benchmarks.md
    "A branch-and-cut of our own"): where the gap left by the root is 3 % or more the tree
    ends higher or level (ft53.1 7,404 against 7,370, ry48p-0.15 19,555 against 19,244,
    ftv70-0.15 2,700 against 2,685; ry48p.1 15,095 against 15,093; prob.42 239 against 240),
    where it is 0.1 % or less HiGHS's search below the best order's cutoff closes it sooner
    (p43.1 proven in 4.7 s against 11.6 s; p43-0.15 11,024 against 11,021). 1 % lies between,
    the threshold below which the stretch rows are skipped for the same reason
    (:data:`~taopt.models.sop_cuts.STRETCH_MIN_GAP`). Not tuned on a file: no measured gap
    lies between 0.1 % and 3 %.
    """
    if not (math.isfinite(value) and math.isfinite(bound)):  # no order or no bound yet
        return True
    return value - bound > TREE_MIN_GAP * max(abs(value), 1.0)


def solve_sop_bc(
    problem: SopProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    verbose: bool = False,
    node_limit: int | None = None,
    branching: str = BRANCHING,
    model: SopCutModel | None = None,
) -> Solution:
    """Exact SOP by our own branch-and-cut over the cut model (module doc).

    The root is :func:`~taopt.models.sop_cuts.root_stage` (the cut loop, stretch rows,
    rounding, reduced-cost fixing); then the best-first tree.

    Parameters
    ----------
    problem : SopProblem
    time_limit : float, optional
        Wall-clock seconds for everything, the model's build included.
    incumbent : Order, list of int or Solution, optional
        A feasible order to start from.
    verbose : bool
        HiGHS's log.
    node_limit : int, optional
        Nodes solved at most (a stop with the proven bound, as the clock's).
    branching : str
        ``"split"`` or ``"arc"`` (:data:`BRANCHING`).
    model : SopCutModel, optional
        As in :func:`~taopt.models.sop_cuts.solve_sop_cuts`.

    Returns
    -------
    Solution
        "optimal" when the tree is empty, else "time_limit" with the best order and the proven
        bound; ``info`` has the root's keys, ``nodes``, ``lps``, ``cuts``, ``open``,
        ``max_depth`` and ``trace`` (seconds, bound) each time the bound rose.

    Examples
    --------
    >>> from taopt.sop.problem import SopProblem
    >>> import numpy as np
    >>> cost = np.array([[0, 1, 5, 9], [9, 0, 1, 5], [1, 9, 0, 1], [9, 9, 9, 0]], float)
    >>> result = solve_sop_bc(SopProblem(cost, [(2, 1)], 0, 3))  # 2 before 1
    >>> result.objective, list(result.order)
    (19.0, [0, 2, 1, 3])
    """
    began = time.perf_counter()
    deadline = Deadline(time_limit)
    model, known, bound, info = root_stage(problem, deadline, incumbent, verbose, model)
    tree = BranchCut(model, known, branching, began=began)
    tree._record(bound)
    stop = tree.run(deadline, node_limit, bound)
    known = tree.known
    if stop == "time_limit":
        bound = (
            max(bound, tree.bound()) if known is None else min(max(bound, tree.bound()), known[0])
        )
    elif stop == "optimal":
        bound = known[0] if known is not None else math.inf
    info.update(
        {
            "nodes": tree.nodes,
            "lps": tree.lps,
            "cuts": len(model.cut_rows),
            "tree_cuts": tree.cuts,
            "open": len(tree._open),
            "max_depth": tree.max_depth,
            "fixed": int(model.fixed.sum()),
            "trace": tree.trace,
        }
    )
    return cut_solution(problem, known, "exact-sop-bc", stop, bound, began, info)
