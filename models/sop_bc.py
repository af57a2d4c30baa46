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

* **The cut pool** (:class:`CutPool`) takes separated rows out of the LP and puts them back;
  every row holds for every order (or every better one), in the LP or not, so the node bound
  of an LP with fewer rows is still a bound of the node's orders: the pool changes the LP's
  size and the bounds' strength, never their validity. A stored basis whose tight rows left
  the LP gets them back from the pool before it is set (rows added since enter basic); a
  basis only costs or saves iterations, never changes a bound.

Which branching a node takes (reliability branching, ``BranchCut._branch``: strong
branching on the candidates whose pseudo-costs are not yet :data:`RELIABLE`, the pseudo-costs
of the others) changes the search, never a bound: every candidate partitions the node's
orders, and a child's bound is its parent's or the node bound of its strong-branching LP's
duals on the child's box (weak duality holds for any duals: the LP solved to its end, or
stopped at the iteration limit or at the cutoff, ``BranchCut._strong``). A node one of whose
strong-branched children holds no better order (infeasible, or bound above the limit) takes
the other child in place (strong-branching fixing, :data:`STRONG_FIXING`): the two children
partition its orders.

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

from taopt.models.highs import add_csr_rows
from taopt.models.sop_cuts import (
    SET_CUTS,
    SopCutModel,
    _order_of,
    _wants_stretch,
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
    "LOOKAHEAD",
    "NODE_ROUNDS",
    "NODE_FULL",
    "NODE_SETS",
    "NODE_STALL",
    "NODE_TIGHT",
    "POOL",
    "POOL_AGE",
    "POOL_BACKOFF",
    "POOL_BACKOFF_CAP",
    "POOL_DEAD",
    "POOL_REPAIR",
    "POOL_SLACK",
    "PSEUDO_CANDIDATES",
    "RELIABLE",
    "ROUND_EVERY",
    "STRONG_BASES",
    "STRONG_CANDIDATES",
    "STRONG_CUTOFF",
    "STRONG_FIXING",
    "STRONG_FLOOR",
    "STRONG_ITERATIONS",
    "STRONG_STOPPED",
    "SPLIT_STRETCH",
    "TREE_MIN_GAP",
    "BranchCut",
    "CutPool",
    "PseudoCosts",
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

#: Whether a node round that found precedence path cuts also separates the set path cuts
#: (off: only when no path cut is violated, as the root loop does). Off: on, the nodes to
#: proof fell by a fifth or a quarter (prob.42 331 against 415, ftv33-0.02-1 107 against 143,
#: the optimum as incumbent), but each node costs more (``separate_sets`` every round), and
#: at 60 s the bound was lower on ry48p.1 (15,204 against 15,250, 15,264 against 15,289)
#: and level on ft53.1 (docs/benchmarks.md, issue 33, branch b14).
NODE_SETS = False

#: The node's last LP point is rounded to an order (:func:`~taopt.models.sop_cuts.round_point`)
#: at every this-many-th node (and at every node while no order is known).
ROUND_EVERY = 4

#: Strong branching: the child LPs of this many candidate branchings at most are solved and
#: the one whose two children gain most (product) is taken; 1 takes the first candidate
#: (nearest 1/2) without scoring (reliability branching, ``BranchCut._branch``).
STRONG_CANDIDATES = 8

#: Reliability branching: a candidate branching whose key (the node and side of an out/in-arc
#: split, or the arc) has this many observed gains in each of its two children is scored by
#: its pseudo-costs (:class:`PseudoCosts`), not strong-branched. 4, below SCIP's default 5 (its
#: ``reliability``), by reasoning not measurement: a split's F changes from node to node, so an
#: older observation says less; each strong-branched candidate adds one per child, a child
#: node's first LP another; the keys are 2n (about 100), so the first 25-50 nodes strong-branch
#: as before and the later ones mostly do not.
RELIABLE = 4

#: Strong branching stops after this many strong-branched candidates in a row that did not
#: improve the best score (SCIP's lookahead, 8 there over longer lists; ours hold 8).
LOOKAHEAD = 4

#: The candidate branchings scored per node (the splits nearest 1/2; the pseudo-costs make the
#: ones beyond :data:`STRONG_CANDIDATES` free to score).
PSEUDO_CANDIDATES = 32

#: Simplex iterations of a strong-branching child LP at most.
STRONG_ITERATIONS = 200

#: Whether a strong-branching child LP that did not end optimal (stopped at
#: :data:`STRONG_ITERATIONS`, or at the cutoff: :data:`STRONG_CUTOFF`) still gives its child a
#: proven bound: :func:`node_bound` of its duals on the child's box (weak duality holds for
#: any duals, clipped to their signs; a stopped dual simplex only gives weaker ones). Off: such
#: a child gets its parent's bound.
STRONG_STOPPED = True

#: Whether strong branching stops a child LP at the cutoff: HiGHS's ``objective_bound`` is the
#: best order's limit (``BranchCut._limit``) while strong branching runs, so its dual simplex
#: stops once its (dual) objective passes it (status ``kObjectiveBound``); the child is pruned
#: only when its own :func:`node_bound` passes the limit (:data:`STRONG_STOPPED`), never on
#: HiGHS's word.
STRONG_CUTOFF = True

#: Strong-branching fixing (SCIP's): when one child of a strong-branched candidate holds no
#: better order (its LP infeasible or its proven bound above the limit), every better order of
#: the node lies in the other child, so the node takes that child's box in place and solves
#: its LP again (rounds and separation) instead of branching; when both hold none the node is
#: pruned. Off: the node branches and pushes the one child left.
STRONG_FIXING = True

#: Whether a strong-branching child LP's final basis (HiGHS's ``getBasis``, a copy in C++;
#: packed only if the LP's rows change before it is used) is kept for that child's node: its
#: first LP then starts at the child LP's end (an optimal child: 0 iterations) rather than at
#: the parent's basis. A basis only costs or saves iterations, never changes a bound.
STRONG_BASES = True

#: Whether strong branching raises the node's bound, hence its children's: every
#: strong-branched candidate partitions the node's orders into its two children, so each
#: better order of the node costs at least the smaller of that candidate's two children's
#: proven bounds, and the node (with each child of the branching taken, a subset of its
#: orders) at least the largest such minimum over the candidates strong-branched (SCIP raises
#: a node's lower bound from its strong branching likewise). Off: a child's bound is its own.
STRONG_FLOOR = True

#: HiGHS's default ``simplex_iteration_limit`` (none), restored after strong branching.
ITERATIONS_UNLIMITED = 2**31 - 1

#: A value this close to 0 or 1 is integral.
INTEGRAL = 1e-6

#: Whether the tree keeps a cut pool (:class:`CutPool`): rows slack for :data:`POOL_AGE`
#: node LPs in a row leave the LP and come back when violated.
POOL = True

#: A separated row leaves the LP after this many consecutive node LPs at which it was slack
#: (SCIP's ``lp/rowagelimit``, 10, by reference, not measured here).
POOL_AGE = 10

#: A row is slack at an LP point when its activity is above its lower side (below its upper
#: side) by this much times ``max(1, |side|)``: such a row's slack is basic (nonbasic slacks
#: sit at a side), so removing it keeps HiGHS's basis valid and the LP's optimum optimal.
POOL_SLACK = 1e-3

#: A pooled row comes back when the node's point violates it by more than this (times
#: ``max(1, |side|)``).
POOL_VIOLATED = 1e-6

#: Whether a row that came back violated retires later: after ``POOL_AGE * 2**k`` slack node
#: LPs, k the times it came back (at most :data:`POOL_BACKOFF_CAP` doublings). Off: tried
#: because 91-96 % of the retired rows came back (docs/benchmarks.md, "a cut pool"), it
#: cut the returns by half or more but kept 1.5-2 times the rows in the LP and solved fewer
#: LPs a second (ft53.1, ry48p.1, prob.42 at 60 s; docs/benchmarks.md, "the cut pool's
#: churn"): a return costs one mat-vec and one ``addRows``, and once :data:`POOL_REPAIR`
#: brings back the tight rows of a stored basis it no longer costs that basis. Our rule
#: (exponential backoff), not SCIP's: SCIP ages its LP rows by one limit
#: (``lp/rowagelimit``, 10, as :data:`POOL_AGE`).
POOL_BACKOFF = False

#: See :data:`POOL_BACKOFF`: at most 2**4 = 16 times :data:`POOL_AGE` (160 node LPs, some
#: 20-50 nodes).
POOL_BACKOFF_CAP = 4

#: The pool's arrays drop the rows put back once these are more than this share of the rows
#: still pooled (:attr:`CutPool.alive`): mechanics only (which rows are pooled, and their
#: order, is the same), by reasoning not measurement: a compaction copies the pool once, a
#: pool product (:meth:`CutPool.violated`) at most 1.25 times the rows it needs; most
#: returns move a few rows of hundreds to thousands pooled.
POOL_DEAD = 0.25

#: Whether a stored basis whose tight (nonbasic) rows have left the LP gets them back from
#: the pool before it is set (:meth:`CutPool.missing`), rather than being dropped (HiGHS then
#: starts from the last node's basis, far from the node's optimum: 87-147 simplex
#: iterations for such a node's first LP against 33-56 once repaired, ft53.1 and
#: ry48p.1 to 200-250 nodes). The rows come back at age 0 and leave again when slack for
#: :data:`POOL_AGE` LPs. Rows added since the basis was stored enter basic (their slacks), as
#: before; this is the exact basis of the parent's last LP on its rows, so dual feasible for
#: the child, which only changes column bounds.
POOL_REPAIR = True


#: HiGHS's basis statuses by their values (a basis is kept per open node as int8 arrays).
_STATUSES = {int(status): status for status in highspy.HighsBasisStatus.__members__.values()}

#: The same by value as a list (a list's index is cheaper than a dict's lookup).
_BY_VALUE = [_STATUSES.get(value) for value in range(max(_STATUSES) + 1)]

#: The value of ``kBasic``.
_BASIC = int(highspy.HighsBasisStatus.kBasic)


def _info(highs: highspy.Highs, name: str) -> Any:
    """HiGHS's info value ``name`` of the last run (``getInfoValue``: 0.5 µs, where
    ``getInfo()`` copies the whole record into Python, 45 µs on prob.42's root LP, at each
    of the tree's LPs); the record's field when HiGHS has no valid info."""
    status, value = highs.getInfoValue(name)
    if status != highspy.HighsStatus.kOk:
        return getattr(highs.getInfo(), name)
    return value


def _packed(statuses: Any) -> np.ndarray:
    """Basis statuses as an int8 array (a node's basis in 1 byte per column and row; the
    enums' ``value``, half the time of ``int()`` on each)."""
    return np.array([status.value for status in statuses], dtype=np.int8)


#: :meth:`CsrRows.tdot` takes the rows of nonzero duals alone below this share of the rows
#: (mechanics only: the same values; 1/2 by reasoning, a row taken costs about a row
#: multiplied).
TDOT_SPARSE = 0.5


#: :meth:`CsrRows.take` copies the rows of a mask run by run (slices) when they lie in this
#: many runs at most (mechanics only: the same arrays; 32 by reasoning, a slice costs about
#: a microsecond where an entry-by-entry copy of the rows costs some hundreds).
TAKE_RUNS = 32


@dataclass
class CsrRows:
    """Rows of a sparse matrix over ``n`` columns as plain CSR arrays (``indptr``, ``indices``,
    ``data``): the tree's LP rows (:class:`Rows`) and its pooled rows (:class:`CutPool`).

    Appending rows (:meth:`append`) and selecting rows (:meth:`take`) are a few numpy calls on
    these arrays, where ``scipy.sparse``'s ``vstack`` and row indexing built matrices through
    their constructors' checks at each step (15,959 constructions, some 1.5-2 s, for the
    2,053 LPs of prob.42's tree, cProfile). The two products (:meth:`dot`, ``A x``;
    :meth:`tdot`, ``A^T y``) are scipy's own kernels (``csr_matvec``, ``csc_matvec``) on
    these arrays, through one scipy matrix of each kind made on first use and kept while the
    rows are these: the same sums in the same order as the scipy matrices the tree kept
    before, so the same values to the bit, hence the same bounds and the same search.
    """

    indptr: np.ndarray
    indices: np.ndarray
    data: np.ndarray
    n: int
    _csr: Any = field(default=None, repr=False, compare=False)
    _csc: Any = field(default=None, repr=False, compare=False)
    #: The growable arrays ``indices`` and ``data`` are the first ``nnz`` entries of, when
    #: made by :meth:`append` (:class:`_Entries`); None for arrays of their own.
    _store: _Entries | None = field(default=None, repr=False, compare=False)

    @classmethod
    def of(cls, matrix: Any) -> CsrRows:
        """The rows of a scipy sparse matrix (its CSR form's arrays, entry order kept)."""
        csr = sp.csr_matrix(matrix)
        return cls(
            csr.indptr.astype(np.int32), csr.indices.astype(np.int32), csr.data, int(csr.shape[1])
        )

    @classmethod
    def entries(cls, starts: np.ndarray, index: np.ndarray, value: np.ndarray, n: int) -> CsrRows:
        """The rows of HiGHS's row-wise entries (``getRowsEntries``: row starts, column
        indices, values) over ``n`` columns."""
        indptr = np.append(np.asarray(starts, dtype=np.int32), np.int32(len(index)))
        return cls(indptr, np.asarray(index, dtype=np.int32), np.asarray(value, dtype=float), n)

    @classmethod
    def lists(cls, rows: list[np.ndarray], weights: list[Any], n: int) -> CsrRows:
        """Rows given as column lists, each with its weights (None: all 1)."""
        indptr = np.zeros(len(rows) + 1, dtype=np.int32)
        np.cumsum([len(row) for row in rows], out=indptr[1:])
        data = [
            np.ones(len(row)) if w is None else np.asarray(w, dtype=float)
            for row, w in zip(rows, weights, strict=True)
        ]
        return cls(indptr, np.concatenate(rows).astype(np.int32), np.concatenate(data), n)

    @property
    def count(self) -> int:
        """Rows."""
        return len(self.indptr) - 1

    @property
    def nnz(self) -> int:
        """Stored entries."""
        return int(self.indptr[-1])

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns)."""
        return self.count, self.n

    def matrix(self) -> sp.csr_matrix:
        """The rows as a scipy CSR matrix (kept; on these arrays, not a copy)."""
        if self._csr is None:
            self._csr = sp.csr_matrix((self.data, self.indices, self.indptr), shape=self.shape)
        return self._csr

    def dot(self, x: np.ndarray) -> np.ndarray:
        """``A x``."""
        return self.matrix() @ x

    def tdot(self, y: np.ndarray) -> np.ndarray:
        """``A^T y``; over the rows of nonzero ``y`` alone when they are fewer than half
        (:data:`TDOT_SPARSE`; an LP's duals are zero on its slack rows, most of the cut rows).

        The same values to the bit: each output adds the same nonzero terms in the same
        order, and a skipped term is ``a y_r = ±0``, which leaves a sum unchanged: ``s + (±0)
        = s`` for ``s ≠ 0``, and a sum that starts at ``+0`` is ``+0`` or nonzero, never
        ``-0`` (``+0 + (-0) = +0``, an exact cancellation gives ``+0``)."""
        nonzero = np.flatnonzero(y)
        if len(nonzero) < TDOT_SPARSE * self.count:  # those rows' transpose, made once
            part = self.take(nonzero)
            shape = (self.n, len(nonzero))
            return sp.csc_matrix((part.data, part.indices, part.indptr), shape=shape) @ y[nonzero]
        if self._csc is None:  # the transpose's arrays are these (scipy's ``.T``)
            self._csc = sp.csc_matrix(
                (self.data, self.indices, self.indptr), shape=(self.n, self.count)
            )
        return self._csc @ y

    def take(self, which: np.ndarray) -> CsrRows:
        """The rows at positions ``which`` (indices, in their order, or a mask). A mask of
        a few runs of rows (the rows left after the pool retires a few: :data:`TAKE_RUNS`)
        copies each run's entries as one slice, not entry by entry; the same arrays."""
        if which.dtype == bool:  # entries by a mask, in their order
            lengths = np.diff(self.indptr)
            indptr = np.zeros(int(which.sum()) + 1, dtype=np.int32)
            np.cumsum(lengths[which], out=indptr[1:])
            edges = np.flatnonzero(np.diff(which, prepend=False, append=False))
            if len(edges) <= 2 * TAKE_RUNS:  # runs [edges[0], edges[1]), [edges[2], ...)
                spans = self.indptr[edges].reshape(-1, 2).tolist()
                indices = np.concatenate(
                    [self.indices[a:b] for a, b in spans] or [self.indices[:0]]
                )
                data = np.concatenate([self.data[a:b] for a, b in spans] or [self.data[:0]])
                return CsrRows(indptr, indices, data, self.n)
            entries = np.repeat(which, lengths)
            return CsrRows(indptr, self.indices[entries], self.data[entries], self.n)
        starts = self.indptr[which]
        lengths = self.indptr[which + 1] - starts
        indptr = np.zeros(len(which) + 1, dtype=np.int32)
        np.cumsum(lengths, out=indptr[1:])
        where = np.repeat(starts - indptr[:-1], lengths) + np.arange(indptr[-1])
        return CsrRows(indptr, self.indices[where], self.data[where], self.n)

    def append(self, other: CsrRows) -> CsrRows:
        """These rows, then ``other``'s: their entries written after these in place when
        these are the last rows appended to a growable store (:class:`_Entries`, which then
        copies only ``other``'s entries), else into a new store of twice the room. The
        same arrays as a concatenation; rows made before keep theirs (a store is only ever
        written past the entries in use)."""
        nnz, more = self.nnz, other.nnz
        indptr = np.concatenate([self.indptr, other.indptr[1:] + np.int32(nnz)]).astype(np.int32)
        store = self._store
        if store is None or store.used != nnz or store.room < nnz + more:
            store = _Entries.of(self.indices, self.data, 2 * (nnz + more))
        store.indices[nnz : nnz + more] = other.indices
        store.data[nnz : nnz + more] = other.data
        store.used = nnz + more
        return CsrRows(
            indptr,
            store.indices[: nnz + more],
            store.data[: nnz + more],
            self.n,
            _store=store,
        )


@dataclass
class _Entries:
    """Growable column indices and values of CSR rows (:meth:`CsrRows.append`): ``used``
    entries written, room for ``room``. Rows made on the first ``k <= used`` entries view
    them; only entries past ``used`` are ever written, so those rows never change."""

    indices: np.ndarray
    data: np.ndarray
    used: int

    @property
    def room(self) -> int:
        """Entries the arrays hold."""
        return len(self.indices)

    @classmethod
    def of(cls, indices: np.ndarray, data: np.ndarray, room: int) -> _Entries:
        """A store of ``room`` entries holding ``indices`` and ``data`` first."""
        store = cls(np.empty(room, dtype=np.int32), np.empty(room, dtype=float), len(indices))
        store.indices[: len(indices)] = indices
        store.data[: len(data)] = data
        return store


@dataclass
class Rows:
    """The model's rows as of ``count`` rows: ``csr`` (rows x columns, :class:`CsrRows`) and
    the row sides, read once from HiGHS (:func:`~taopt.models.sop_statelp.constraint_matrix`)
    and kept while no row is added (the tree's LPs between two separations), then grown by the
    rows added (:meth:`now`)."""

    count: int
    csr: CsrRows
    lower: np.ndarray
    upper: np.ndarray

    @property
    def matrix(self) -> sp.csr_matrix:
        """The rows as a scipy CSR matrix (:meth:`CsrRows.matrix`)."""
        return self.csr.matrix()

    @classmethod
    def of(cls, model: SopCutModel) -> Rows:
        """The rows of ``model``'s HiGHS object now."""
        lp = model.highs.getLp()
        return cls(
            int(lp.num_row_),
            CsrRows.of(constraint_matrix(lp)),
            np.asarray(lp.row_lower_, dtype=float),
            np.asarray(lp.row_upper_, dtype=float),
        )

    def now(self, model: SopCutModel) -> Rows:
        """The rows of ``model``'s HiGHS object now, these kept and only the rows past
        ``count`` read (``getRows``; the cut model only appends rows): a whole ``getLp`` copy
        cost 15 ms a node on ft53.1 (load 3.8), most of :func:`node_bound`'s time. Read whole
        (:meth:`of`) when fewer rows are there; the tree's cut pool deletes rows itself and
        keeps its ``Rows`` in step (:meth:`CutPool.retire` returns them without the rows it
        took out), so a count that came back equal after a deletion and an addition is never
        read here as unchanged."""
        highs = model.highs
        total = int(highs.getNumRow())
        if total == self.count:
            return self
        if total < self.count:
            return Rows.of(model)
        fresh = np.arange(self.count, total, dtype=np.int32)
        _, _, lower, upper, _ = highs.getRows(len(fresh), fresh)
        _, starts, index, value = highs.getRowsEntries(len(fresh), fresh)
        block = CsrRows.entries(starts, index, value, model.n_arcs)
        return self.plus(Rows(len(fresh), block, np.asarray(lower), np.asarray(upper)))

    def plus(self, more: Rows) -> Rows:
        """These rows, then ``more``."""
        return Rows(
            self.count + more.count,
            self.csr.append(more.csr),
            np.concatenate([self.lower, more.lower]),
            np.concatenate([self.upper, more.upper]),
        )


def _margin(sides: np.ndarray, share: float) -> np.ndarray:
    """``share * max(1, |side|)`` for each finite row side (0 for an infinite one)."""
    return share * np.maximum(1.0, np.where(np.isfinite(sides), np.abs(sides), 0.0))


@dataclass
class CutPool:
    """The rows taken out of the tree's LP, and the age of each row in it.

    Every row of the LP has an identity (``ids``: its position in the LP when the tree began
    for the rows then, the next number for each row added since; a row keeps its identity
    out of the LP and back). After each optimal node LP (:meth:`observe`) the age of a row
    slack at the LP's point (:data:`POOL_SLACK`) grows by one, of the others goes back to 0;
    :meth:`retire` moves the rows of age :meth:`limits` or more (:data:`POOL_AGE`, doubled
    per return: :data:`POOL_BACKOFF`) out of the LP into the pool (the first ``kept`` rows,
    the degree rows of the model, never), :meth:`violated` / :meth:`restore` put back the
    pooled rows a node's point violates (one sparse mat-vec), which the node's separation
    would otherwise skip as known (``SopCutModel``'s keys); :meth:`missing` names the pooled
    rows a stored basis holds tight, put back before it is set (:data:`POOL_REPAIR`).

    Validity: every row, in the LP or not, holds for every order (or for every order better
    than the best known, module doc), so the node bound (weak duality on the rows in the LP)
    is valid whatever rows the LP holds; the pool only changes which rows that is. The stored
    bases carry the ``ids`` they were taken with (``BranchCut._apply`` maps them by
    identity): a basis only costs or saves simplex iterations.
    """

    kept: int
    ids: np.ndarray
    age: np.ndarray
    next_id: int
    pooled: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    matrix: CsrRows | None = None
    lower: np.ndarray = field(default_factory=lambda: np.zeros(0))
    upper: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: Per LP row (as ``ids``) and per pooled row (as ``pooled``): the times it came back
    #: violated (:data:`POOL_BACKOFF`).
    returns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    pooled_returns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    retired: int = 0
    restored: int = 0
    stale: int = 0
    repaired: int = 0
    #: Per pooled row: still in the pool (a row put back stays in the pool's arrays, not
    #: alive, until the dead rows are more than :data:`POOL_DEAD` of the alive ones: then the
    #: arrays are compacted, not at each :meth:`restore`).
    alive: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    #: The rows the last :meth:`restore` appended to the LP (the tree's :class:`Rows` take
    #: them from here, not read back from HiGHS: ``BranchCut._added``).
    back: Rows | None = None

    @classmethod
    def of(cls, model: SopCutModel, rows: Rows) -> CutPool:
        """The pool of ``model``'s LP with ``rows`` (none pooled yet)."""
        return cls(
            model.degree_rows,
            np.arange(rows.count, dtype=np.int64),
            np.zeros(rows.count, dtype=np.int64),
            rows.count,
        )

    def _grow(self, count: int) -> None:
        """Identities and age 0 for the rows appended to the LP since (up to ``count``)."""
        extra = count - len(self.ids)
        if extra > 0:
            fresh = np.arange(self.next_id, self.next_id + extra, dtype=np.int64)
            self.ids = np.concatenate([self.ids, fresh])
            self.age = np.concatenate([self.age, np.zeros(extra, dtype=np.int64)])
            self.next_id += extra
        short = len(self.ids) - len(self.returns)
        if short > 0:
            self.returns = np.concatenate([self.returns, np.zeros(short, dtype=np.int64)])

    def observe(self, rows: Rows, values: np.ndarray) -> None:
        """Age the LP's rows at its optimal point ``values``."""
        self._grow(rows.count)
        activity = rows.csr.dot(values)
        slack = (activity - rows.lower > _margin(rows.lower, POOL_SLACK)) & (
            rows.upper - activity > _margin(rows.upper, POOL_SLACK)
        )
        self.age = np.where(slack, self.age + 1, 0)

    def limits(self) -> np.ndarray:
        """The age at which each LP row retires: :data:`POOL_AGE`, doubled per return
        (:data:`POOL_BACKOFF`)."""
        if not POOL_BACKOFF:
            return np.full(len(self.ids), POOL_AGE, dtype=np.int64)
        return POOL_AGE * np.left_shift(1, np.minimum(self.returns, POOL_BACKOFF_CAP))

    def retire(self, model: SopCutModel, rows: Rows) -> Rows:
        """Move the rows of age :meth:`limits` or more (past the first ``kept``) out of the
        LP; returns ``rows`` without them. Called right after :meth:`observe` on an LP, so
        their slacks are basic and HiGHS keeps its basis."""
        self._grow(rows.count)
        old = np.flatnonzero(self.age >= self.limits())
        old = old[old >= self.kept]
        if not len(old):
            return rows
        model.highs.deleteRows(len(old), old.astype(np.int32))
        keep = np.ones(rows.count, dtype=bool)
        keep[old] = False
        block = rows.csr.take(old)
        self.matrix = block if self.matrix is None else self.matrix.append(block)
        self.pooled = np.concatenate([self.pooled, self.ids[old]])
        self.pooled_returns = np.concatenate([self.pooled_returns, self.returns[old]])
        self.alive = np.concatenate([self.alive, np.ones(len(old), dtype=bool)])
        self.lower = np.concatenate([self.lower, rows.lower[old]])
        self.upper = np.concatenate([self.upper, rows.upper[old]])
        self.ids, self.age, self.returns = self.ids[keep], self.age[keep], self.returns[keep]
        self.retired += len(old)
        return Rows(int(keep.sum()), rows.csr.take(keep), rows.lower[keep], rows.upper[keep])

    def violated(self, values: np.ndarray) -> np.ndarray:
        """The positions in the pool of the rows ``values`` violates (:data:`POOL_VIOLATED`)."""
        if self.matrix is None or not self.alive.any():
            return np.zeros(0, dtype=np.int64)
        activity = self.matrix.dot(values)
        return np.flatnonzero(
            (
                (activity < self.lower - _margin(self.lower, POOL_VIOLATED))
                | (activity > self.upper + _margin(self.upper, POOL_VIOLATED))
            )
            & self.alive
        )

    def missing(self, basis: tuple[np.ndarray | None, np.ndarray, np.ndarray]) -> np.ndarray:
        """The positions in the pool of the rows nonbasic in a stored basis (tight at its
        LP): with them back in the LP (:meth:`restore`) the basis maps (:meth:`statuses`)."""
        _, row_status, ids = basis
        if not self.alive.any():
            return np.zeros(0, dtype=np.int64)
        size = max(self.next_id, int(ids.max(initial=-1)) + 1, int(self.pooled.max()) + 1)
        tight = np.zeros(size, dtype=bool)  # by identity (``isin`` sorted both)
        tight[ids[row_status != _BASIC]] = True
        return np.flatnonzero(tight[self.pooled] & self.alive)

    def restore(
        self, model: SopCutModel, which: np.ndarray | None = None, returned: bool = True
    ) -> int:
        """Append the pooled rows at positions ``which`` (every pooled row when None) to the
        LP, with their identities and age 0; returns how many. ``returned``: a return of
        each (a violated row: :data:`POOL_BACKOFF`; not a row back for a basis). The tree's
        :class:`Rows` take them as rows appended (:attr:`back`)."""
        if self.matrix is None or not self.alive.any():
            return 0
        if which is None:
            which = np.flatnonzero(self.alive)
        if not len(which):
            return 0
        self._grow(int(model.highs.getNumRow()))  # rows the model appended keep their place
        self.back = Rows(len(which), self.matrix.take(which), self.lower[which], self.upper[which])
        add_csr_rows(model.highs, self.back.csr, self.back.lower, self.back.upper)
        self.ids = np.concatenate([self.ids, self.pooled[which]])
        self.age = np.concatenate([self.age, np.zeros(len(which), dtype=np.int64)])
        self.returns = np.concatenate([self.returns, self.pooled_returns[which] + returned])
        self.alive[which] = False
        dead = len(self.alive) - int(self.alive.sum())
        if dead > POOL_DEAD * (len(self.alive) - dead):
            rest = self.alive
            self.matrix = self.matrix.take(rest)
            self.pooled, self.pooled_returns, self.lower, self.upper, self.alive = (
                self.pooled[rest],
                self.pooled_returns[rest],
                self.lower[rest],
                self.upper[rest],
                self.alive[rest],
            )
        if returned:
            self.restored += len(which)
        else:
            self.repaired += len(which)
        return len(which)

    def statuses(
        self,
        basis: tuple[np.ndarray | None, np.ndarray, np.ndarray],
        basic_columns: int | None = None,
    ) -> np.ndarray | None:
        """A stored basis's row statuses for the LP's rows now, by identity (rows it does not
        know: basic); None when that basis no longer has one basic variable per row (a row
        nonbasic in it has left the LP), and counts it in ``stale``. ``basic_columns``: its
        basic columns when known (:meth:`_ChildBasis.basic_columns`; its column statuses are
        then not read)."""
        col_status, row_status, ids = basis
        basic = int(highspy.HighsBasisStatus.kBasic)
        if len(ids) == len(self.ids) and ids is self.ids:
            mapped = row_status
        else:
            order = np.argsort(ids, kind="stable")
            place = np.searchsorted(ids[order], self.ids)
            place = np.minimum(place, max(len(ids) - 1, 0))
            known = (ids[order][place] == self.ids) if len(ids) else np.zeros(len(self.ids), bool)
            mapped = np.where(known, row_status[order[place]] if len(ids) else basic, basic)
            mapped = mapped.astype(np.int8)
        if basic_columns is None:
            assert col_status is not None
            basic_columns = int((col_status == basic).sum())
        count = basic_columns + int((mapped == basic).sum())
        if count != len(self.ids):
            self.stale += 1
            return None
        return mapped


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
    reduced = model.costs - rows.csr.tdot(y)
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
    #: Its parent's final basis (:class:`_ChildBasis`), set when another node was solved
    #: since the parent.
    basis: _ChildBasis | None = field(compare=False, default=None)
    parent: int = field(compare=False, default=-1)
    #: (branching key, child 0 or 1, the LP mass the branching removed, the parent's LP
    #: value): the child's first LP is a pseudo-cost observation.
    origin: tuple[Any, int, float, float] | None = field(compare=False, default=None)
    #: The basis its strong-branching child LP ended at (:data:`STRONG_BASES`), set before
    #: the node's first LP even when the parent was the last node solved.
    own: _ChildBasis | None = field(compare=False, default=None)


@dataclass
class _ChildBasis:
    """An LP's final basis kept for a node: a strong-branching child LP's (the node's own,
    :data:`STRONG_BASES`) or its parent's last LP's, as HiGHS's own object (``raw``, a copy
    in C++) and the pool's row identities when it was taken (``ids``, the same array while
    no row has changed). Packed into int8 statuses (:meth:`packed`) only when a node uses it
    on other rows, not at every branching (most children never need their parent's)."""

    raw: Any
    ids: np.ndarray
    _rows: np.ndarray | None = field(default=None, repr=False)

    def row_status(self) -> np.ndarray:
        """Its row statuses as int8 (read from ``raw`` once: reading a status list from
        HiGHS makes a Python object per entry, some 0.2 µs each)."""
        if self._rows is None:
            self._rows = _packed(self.raw.row_status)
        return self._rows

    def packed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The basis as int8 statuses and the row identities."""
        return _packed(self.raw.col_status), self.row_status(), self.ids

    def basic_columns(self) -> int:
        """Its basic columns, without reading the column statuses: HiGHS's bases (``getBasis``
        of a solved LP, ``valid``) have one basic variable per row, so the rows (``ids``)
        less the basic rows; counted from the column statuses for any other."""
        if not self.raw.valid:
            return int((self.packed()[0] == _BASIC).sum())
        return len(self.ids) - int((self.row_status() == _BASIC).sum())

    def set(self, highs: highspy.Highs, row_status: np.ndarray) -> None:
        """Set this basis in ``highs`` with the row statuses ``row_status`` (the LP's rows
        now, :meth:`CutPool.statuses`): ``raw`` itself with its rows replaced, marked as a
        basis set by hand (``alien``: HiGHS checks and factors it, as it does a new
        ``HighsBasis``); its column statuses stay in HiGHS's object, never read into Python.
        :meth:`row_status` was read before, so later uses of this basis map from it."""
        self.row_status()
        raw = self.raw
        raw.row_status = [_BY_VALUE[k] for k in row_status.tolist()]
        raw.valid, raw.alien, raw.was_alien = True, True, True
        highs.setBasis(raw)


def _union(n: int, *parts: Any) -> np.ndarray:
    """The sorted union of index arrays over ``range(n)`` (``np.union1d``'s result) by a
    mask: ``union1d``'s sort or hash on each of 64 children per node was a fifth of the
    tree's time on ft53.1 (cProfile, 10.6 of 55 s)."""
    mask = np.zeros(n, dtype=bool)
    for part in parts:
        mask[part] = True
    return np.flatnonzero(mask)


@dataclass
class _Branching:
    """A candidate branching: its pseudo-cost key, the node's ``ones`` and ``zeros``, what
    each of its two children adds to them (``adds[k]``: ones, zeros), and the LP mass each
    child cuts off (``x(F)`` and ``x(R)`` of a split, ``1 - x_a`` and ``x_a`` of an arc).
    The children's arrays are built (:meth:`child`) only for the candidates strong-branched
    and the one taken."""

    key: tuple[str, int]
    ones: np.ndarray
    zeros: np.ndarray
    adds: tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
    shares: tuple[float, float]

    def child(self, k: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Child ``k``'s (ones, zeros) over ``n`` arcs."""
        more_ones, more_zeros = self.adds[k]
        ones = _union(n, self.ones, more_ones) if len(more_ones) else self.ones
        zeros = _union(n, self.zeros, more_zeros) if len(more_zeros) else self.zeros
        return ones, zeros


@dataclass
class PseudoCosts:
    """Per branching key and child, the LP gains observed per unit of the mass the child cuts
    off (strong-branching child LPs and children's first LPs): the estimate of a child's gain
    is its key's mean times its share, the mean over every key where its key has none yet
    (1 with none at all). Only the choice of the branching reads them, never a bound."""

    sums: dict[tuple[str, int], np.ndarray] = field(default_factory=dict)
    counts: dict[tuple[str, int], np.ndarray] = field(default_factory=dict)
    total: np.ndarray = field(default_factory=lambda: np.zeros(2))
    seen: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def observe(self, key: tuple[str, int], child: int, gain: float, share: float) -> None:
        """One observed LP gain of ``key``'s child ``child`` (0 or 1) cutting off ``share``."""
        if share <= INTEGRAL or not math.isfinite(gain):
            return
        unit = max(gain, 0.0) / share
        if key not in self.sums:
            self.sums[key], self.counts[key] = np.zeros(2), np.zeros(2)
        self.sums[key][child] += unit
        self.counts[key][child] += 1
        self.total[child] += unit
        self.seen[child] += 1

    def reliable(self, key: tuple[str, int]) -> bool:
        """Whether each child of ``key`` has :data:`RELIABLE` observations."""
        counts = self.counts.get(key)
        return bool((0 if counts is None else counts.min()) >= RELIABLE)

    def estimate(self, key: tuple[str, int], shares: tuple[float, float]) -> np.ndarray:
        """The two children's estimated gains (in Python floats: the same IEEE operations as
        on the 2-element arrays, a fifth of the time, at each of 32 candidates a node)."""
        counts, sums = self.counts.get(key), self.sums.get(key)
        gains = []
        for child in (0, 1):
            if counts is not None and sums is not None and counts[child] > 0:
                mean = float(sums[child]) / float(counts[child])
            elif self.seen[child] > 0:
                mean = float(self.total[child]) / float(self.seen[child])
            else:
                mean = 1.0
            gains.append(mean * shares[child])
        return np.array(gains)


def _score(gains: Any, value: float) -> float:
    """A branching's score: the product of its two children's gains (each capped at 1e12 for
    an infeasible child, plus ``1e-6 |value|`` so that one gain of 0 does not tie all)."""
    tiny = 1e-6 * max(abs(value), 1.0)
    return math.prod(min(max(float(g), 0.0), 1e12) + tiny for g in gains)


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
    pseudo: PseudoCosts = field(default_factory=PseudoCosts)
    strong_lps: int = 0
    pseudo_branchings: int = 0
    #: Simplex iterations of the strong-branching child LPs, and of the nodes' first LPs.
    strong_iterations: int = 0
    first_iterations: int = 0
    #: Strong-branching child LPs that stopped early and gave their child a node bound
    #: (:data:`STRONG_STOPPED`); nodes that took a child in place (:data:`STRONG_FIXING`).
    strong_stopped: int = 0
    strong_fixings: int = 0
    #: Children pushed with a bound raised by :data:`STRONG_FLOOR`.
    strong_floors: int = 0
    _open: list[_Node] = field(default_factory=list)
    _count: int = 0
    _last: int = -1  # the node whose LP HiGHS holds
    _changed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    _rows: Rows | None = None
    #: The cut pool (:class:`CutPool`; made by :meth:`run`).
    pool: CutPool | None = None
    #: The LP's rows when the search stopped (before the pool's rows went back).
    rows_end: int = 0
    #: The peer process (:class:`taopt.models.sop_split.Peer`) to share the nodes with, once
    #: it is ready; its pipe's end (:class:`taopt.models.sop_split.Link`) once loaded, or this
    #: side's link in the peer process.
    peer: Any = None
    link: Any = None
    #: The peer's counts (nodes, LPs, nodes taken and given), from its last answer.
    peer_counts: dict[str, int] | None = None

    def _added(self, before: int, more: Rows) -> None:
        """The rows ``more`` were just appended to the LP, which had ``before`` rows: the
        tree's :class:`Rows` take them as they are (no ``getRows``/``getRowsEntries`` read of
        rows known here) when they held the LP's ``before`` rows; else :meth:`Rows.now` reads
        them later. The same arrays as read back: the rows are appended as given, each
        row's columns in increasing order (the model's rows, and so the pool's, are), and
        a test compares them with HiGHS's at every LP."""
        rows = self._rows
        if rows is not None and rows.count == before:
            if int(self.model.highs.getNumRow()) == before + more.count:
                self._rows = rows.plus(more)

    def _restore(self, which: np.ndarray | None, returned: bool = True) -> int:
        """:meth:`CutPool.restore`, the tree's :class:`Rows` kept in step (:meth:`_added`)."""
        pool = self._pool()
        before = int(self.model.highs.getNumRow())
        count = pool.restore(self.model, which, returned)
        if count and pool.back is not None:
            self._added(before, pool.back)
        return count

    def _add_cuts(self, cuts: list[np.ndarray], sides: list[float] | None) -> None:
        """The model's ``add_cuts``, the tree's :class:`Rows` kept in step (:meth:`_added`:
        the model's newest ``cut_rows``, ``cut_sides`` and ``cut_weights``)."""
        model = self.model
        before = int(model.highs.getNumRow())
        count = model.add_cuts(cuts, sides)
        self.cuts += count
        if count:
            block = CsrRows.lists(model.cut_rows[-count:], model.cut_weights[-count:], model.n_arcs)
            lower = np.asarray(model.cut_sides[-count:], dtype=float)
            self._added(before, Rows(count, block, lower, np.full(count, highspy.kHighsInf)))

    def _add_weighted(self, rows: list[tuple[np.ndarray, np.ndarray, float]]) -> None:
        """The model's ``add_weighted_rows`` (rows given as (arcs, weights, side)), the tree's
        :class:`Rows` kept in step as in :meth:`_add_cuts`."""
        model = self.model
        before = int(model.highs.getNumRow())
        count = model.add_weighted_rows(rows)
        self.cuts += count
        if count:
            block = CsrRows.lists(model.cut_rows[-count:], model.cut_weights[-count:], model.n_arcs)
            lower = np.asarray(model.cut_sides[-count:], dtype=float)
            self._added(before, Rows(count, block, lower, np.full(count, highspy.kHighsInf)))

    def _bound_of(self, lower: np.ndarray, upper: np.ndarray) -> tuple[float, np.ndarray]:
        """:func:`node_bound` of the last LP, the rows read again only when rows were added."""
        self._rows = Rows.of(self.model) if self._rows is None else self._rows.now(self.model)
        return node_bound(self.model, lower, upper, self._rows)

    # ------------------------------------------------------------------ bounds
    def _limit(self) -> float:
        """An order better than the best costs at most this (``inf`` without one)."""
        if self.known is None:
            return math.inf
        z, step = self.known[0], self.model.step
        return z - step + 1e-6 if step else z - 1e-9 * max(1.0, abs(z))

    def bound(self, current: float = math.inf) -> float:
        """The proven bound: ``min(best, open nodes' bounds, current)``, and the nodes in the
        peer process or on their way to it (:meth:`taopt.models.sop_split.Link.outside`)."""
        least = min([node.bound for node in self._open] + [current])
        if self.link is not None and self.link.main:
            least = min(least, self.link.outside())
        return least if self.known is None else min(least, self.known[0])

    def _record(self, value: float) -> None:
        if not self.trace or value > self.trace[-1][1]:
            self.trace.append((time.perf_counter() - self.began, value))

    # ------------------------------------------------------------------ nodes
    def _push(
        self,
        bound: float,
        depth: int,
        ones: np.ndarray,
        zeros: np.ndarray,
        basis: _ChildBasis | None,
        parent: int,
        origin: tuple[Any, int, float, float] | None = None,
        own: _ChildBasis | None = None,
    ) -> None:
        self._count += 1
        heapq.heappush(
            self._open,
            _Node(bound, -depth, self._count, ones, zeros, basis, parent, origin, own),
        )

    def _apply(self, node: _Node) -> tuple[np.ndarray, np.ndarray]:
        """Set the node's column bounds in HiGHS (the previous node's undone) and its basis
        (its strong-branching child LP's when kept, :data:`STRONG_BASES`, as HiGHS's object
        while the rows are those it was taken with, else packed and mapped by row identity as
        a parent's; a parent's only when another node was solved since); returns the box
        (lower, upper)."""
        model = self.model
        highs = model.highs
        lower = np.zeros(model.n_arcs)
        upper = np.where(model.fixed, 0.0, 1.0)
        lower[node.ones] = 1.0
        upper[node.zeros] = 0.0
        changed = _union(model.n_arcs, node.ones, node.zeros).astype(np.int32)
        # the last node's columns back to the root's bounds and this node's set, in one call
        # (:meth:`_undo`'s and this node's: HiGHS keeps a nonbasic column's status through a
        # change of its finite bounds, so the LP and its basis are those of the two calls)
        touched = _union(model.n_arcs, self._changed, changed).astype(np.int32)
        if len(touched):
            highs.changeColsBounds(len(touched), touched, lower[touched], upper[touched])
        self._changed = changed
        stored, own, node.own = node.basis, node.own, None
        if own is not None:  # its strong-branching child LP's basis (STRONG_BASES)
            pool = self._pool()
            pool._grow(int(highs.getNumRow()))  # rows appended since: new identities
            if own.ids is pool.ids:  # the same rows: HiGHS's own object
                highs.setBasis(own.raw)
                self._last = node.number
                return lower, upper
            stored = node.basis = own  # the rows changed: mapped as any basis
        if stored is not None and (own is not None or node.parent != self._last):
            packed = (None, stored.row_status(), stored.ids)
            # by row identity: rows added since basic (their slacks), as HiGHS itself keeps
            # them; the basis's tight rows that left the LP come back (POOL_REPAIR), else a
            # basis that lost a nonbasic row is not set (HiGHS's own is kept)
            pool = self._pool()
            if POOL_REPAIR:
                self._restore(pool.missing(packed), returned=False)
            pool._grow(int(highs.getNumRow()))
            row_status = pool.statuses(packed, stored.basic_columns())
            if row_status is not None:
                stored.set(highs, row_status)
        self._last = node.number
        return lower, upper

    def _new_order(self, candidate: tuple[float, list[int]] | None) -> None:
        if candidate is not None and (self.known is None or candidate[0] < self.known[0]):
            self.known = candidate

    def run(
        self,
        deadline: Deadline,
        node_limit: int | None = None,
        root_bound: float = -math.inf,
        root: bool = True,
    ) -> str:
        """Search from the root node (of bound ``root_bound``); returns ``"optimal"`` (tree
        empty), ``"infeasible"`` (tree empty, no order), or ``"time_limit"`` (deadline or
        ``node_limit`` nodes). ``root``: push the root node first (False in the peer process,
        which is given its nodes)."""
        model = self.model
        model.make_integral(False)
        empty = np.zeros(0, dtype=np.int64)
        if root and not self._open and self.nodes == 0:
            self._push(root_bound, 0, empty, empty, None, -1)
        try:
            return self._search(deadline, node_limit)
        finally:  # the model's LP as before the tree (the portfolio's later stages re-solve it)
            self._undo()
            self._last = -1
            self._unpool()

    def _pool(self) -> CutPool:
        """The cut pool, made on first use with the LP's rows now."""
        if self.pool is None:
            self._rows = Rows.of(self.model) if self._rows is None else self._rows.now(self.model)
            self.pool = CutPool.of(self.model, self._rows)
        return self.pool

    def _unpool(self) -> None:
        """Every pooled row back in the LP, the rows in their order of identity (the order
        without the pool: the model's ``cut_rows`` by position, as the root's prices read)."""
        pool = self.pool
        highs = self.model.highs
        self.rows_end = int(highs.getNumRow())
        if pool is None or not pool.retired:
            return
        counts = pool.restored, pool.repaired
        pool.restore(self.model)
        pool.restored, pool.repaired = counts  # count the rows back at a node only
        rows = Rows.of(self.model)
        pool._grow(rows.count)
        if np.all(np.diff(pool.ids) > 0):
            return
        tail = np.arange(pool.kept, rows.count)
        order = pool.kept + np.argsort(pool.ids[pool.kept :], kind="stable")
        highs.deleteRows(len(tail), tail.astype(np.int32))
        add_csr_rows(highs, rows.csr.take(order), rows.lower[order], rows.upper[order])
        pool.ids = np.concatenate([pool.ids[: pool.kept], pool.ids[order]])
        pool.returns = np.concatenate([pool.returns[: pool.kept], pool.returns[order]])
        pool.age = np.zeros(len(pool.ids), dtype=np.int64)
        self._rows = None

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
        """The loop of :meth:`run`; with a peer (:mod:`taopt.models.sop_split`) the nodes are
        shared at each loop head and an empty list waits for the peer's."""
        while True:
            if self.peer is not None and self.link is None:
                self.link = self.peer.load(self)
            if self.link is not None:
                self.link.poll(self)
                if self.link.stopped:
                    return "time_limit"
                if not self._open:
                    state = self.link.idle(self, deadline, MARGIN)
                    if state == "time_limit":
                        return state
                    if state == "done":
                        break
            if not self._open:
                break
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
        the deadline stopped it before its children were pushed (the node stays open).

        Strong-branching fixing (:data:`STRONG_FIXING`): when a strong-branched candidate
        has a child above the limit (module doc: its better orders, none), the node's better
        orders all lie in the other child (the two partition the node's orders), so the node
        becomes that child (its ones, zeros, bound and basis: ``node`` is changed in place, a
        node still open if the deadline stops it) and its LP rounds run again; both above
        the limit: the node holds no better order and is pruned."""
        model = self.model
        if model.fixed[node.ones].any():
            return True  # an arc no better order uses: no better order here
        lower, upper = self._apply(node)
        self.nodes += 1
        depth = -node.depth_key
        self.max_depth = max(self.max_depth, depth)
        bound, observed = node.bound, node.origin is None
        while True:
            done, solved = self._rounds(node, lower, upper, bound, observed, deadline)
            if solved is None:
                return done
            bound, value, values, raw, reduced = solved
            observed = True
            if deadline.expired(MARGIN):
                return False
            if POOL and self._rows is not None:  # HiGHS holds the last LP, observed: retire
                self._rows = self._pool().retire(model, self._rows)
            if self.known is None or self.nodes % ROUND_EVERY == 1:
                self._new_order(round_point(model, values, deadline))
            limit = self._limit()
            if bound > limit:
                return True
            # node fixing by reduced cost against the best order (the module's proof)
            ones, zeros = node.ones, node.zeros
            if math.isfinite(limit) and len(reduced):
                free = ~model.fixed & (lower < 0.5) & (upper > 0.5)
                n = model.n_arcs
                zeros = _union(
                    n, zeros, np.flatnonzero(free & (reduced > 0) & (raw + reduced > limit))
                )
                ones = _union(
                    n, ones, np.flatnonzero(free & (reduced < 0) & (raw - reduced > limit))
                )
            basis = model.highs.getBasis()
            pool = self._pool()
            pool._grow(int(model.highs.getNumRow()))
            saved = _ChildBasis(basis, pool.ids)
            candidates = self._candidates(values, ones, zeros)
            pick, bounds = candidates[0], [bound, bound]
            bases: list[_ChildBasis | None] = [None, None]
            if STRONG_CANDIDATES > 1 and len(candidates) > 1:
                pick, bounds, bases = self._branch(
                    candidates, lower, upper, basis, value, bound, deadline
                )
            limit = self._limit()
            alive = [child for child in range(2) if bounds[child] <= limit]
            if not alive:
                return True  # neither child holds a better order
            if STRONG_FIXING and len(alive) < 2:
                self.strong_fixings += 1
                node.ones, node.zeros = pick.child(alive[0], model.n_arcs)
                node.bound, node.basis, node.own = bounds[alive[0]], saved, bases[alive[0]]
                lower, upper = self._apply(node)
                bound = node.bound
                continue
            for child in alive:
                child_ones, child_zeros = pick.child(child, model.n_arcs)
                origin = (pick.key, child, pick.shares[child], value)
                self._push(
                    bounds[child],
                    depth + 1,
                    child_ones,
                    child_zeros,
                    saved,
                    node.number,
                    origin,
                    bases[child],
                )
            return True

    def _rounds(
        self,
        node: _Node,
        lower: np.ndarray,
        upper: np.ndarray,
        bound: float,
        observed: bool,
        deadline: Deadline,
    ) -> tuple[bool, tuple[float, float, np.ndarray, float, np.ndarray] | None]:
        """The node's LP rounds (solve, separate, add) in the box ``lower``, ``upper`` of
        proven bound ``bound``: ``(True, None)`` when the node is done (infeasible, above the
        limit, or its point an order), ``(False, None)`` when the deadline stopped them, else
        ``(True, (the proven bound, the last LP's value, point, unrounded node bound, reduced
        costs))`` for branching.
        ``observed``: the node's first LP is no pseudo-cost observation (already made)."""
        model = self.model
        value, raw = -math.inf, -math.inf
        new_value = -math.inf
        values = np.zeros(0)
        reduced = np.zeros(0)
        rounds = 0
        while True:
            if deadline.expired(MARGIN):
                return False, None
            # a plain run under HiGHS's own time limit (``brief``), not in a helper thread
            # waiting for Ctrl-C: a warm node LP takes milliseconds, the thread's start and the
            # interrupt callbacks cost 5-6 ms a run at load 3.5-6 (cProfile, ft53.1 and
            # ry48p.1: 6.2 and 5.5 s in Thread.start of 55 and 51 s); Ctrl-C is raised after it
            model._run(deadline, brief=True)
            status = model.highs.getModelStatus()
            if rounds == 0:
                self.first_iterations += int(_info(model.highs, "simplex_iteration_count"))
            if status == highspy.HighsModelStatus.kInfeasible:
                return True, None  # no point of the rows in the box: no (better) order here
            if status != highspy.HighsModelStatus.kOptimal:
                return False, None  # stopped by the clock
            self.lps += 1
            raw, reduced = self._bound_of(lower, upper)
            bound = max(bound, model.round_up(raw))
            if bound > self._limit():
                return True, None
            values = model.lp_values()
            new_value = float(_info(model.highs, "objective_function_value"))
            if self._rows is not None:
                self._pool().observe(self._rows, values)
            if rounds == 0 and not observed and node.origin is not None:
                key, child, share, parent_value = node.origin  # a pseudo-cost observation
                self.pseudo.observe(key, child, new_value - parent_value, share)
            integral = not ((values > INTEGRAL) & (values < 1 - INTEGRAL)).any()
            if integral:
                order = _order_of(model, values)
                if order is not None:  # the node's optimum (its LP's) is this order
                    self._new_order((float(model.problem.cost[order[:-1], order[1:]].sum()), order))
                    return True, None
            elif rounds >= NODE_ROUNDS or (
                rounds and new_value - value <= NODE_STALL * max(abs(value), 1.0)
            ):
                break
            value, rounds = new_value, rounds + 1
            back = self._pool().violated(values) if POOL else np.zeros(0)
            if len(back):  # pooled rows first: separation would skip them as known
                self._restore(back)
                continue
            among = None
            if not integral and self.nodes % NODE_FULL:  # the nearly tight pairs (heuristic)
                among = model.flows[model.pairs[:, 0], model.pairs[:, 1]] < 1 + NODE_TIGHT
            cuts = model.separate(values, deadline=deadline, among=among)
            sides = None
            if cuts and NODE_SETS and SET_CUTS:  # both families this round
                sides = [1.0] * len(cuts)
                more, more_sides = model.separate_sets(values, deadline=deadline)
                cuts, sides = cuts + more, sides + list(more_sides)
            if not cuts and SET_CUTS:
                cuts, sides = model.separate_sets(values, deadline=deadline)
            if not cuts:
                if integral:  # an integral non-order violates a row (module doc): the
                    return False, None  # deadline cut the separation short
                break
            self._add_cuts(cuts, sides)
        return True, (bound, new_value, values, raw, reduced)

    # ------------------------------------------------------------------ branching
    def _candidates(
        self, values: np.ndarray, ones: np.ndarray, zeros: np.ndarray
    ) -> list[_Branching]:
        """Branchings of a node with LP point ``values``, nearest 1/2 first, at most
        :data:`PSEUDO_CANDIDATES` (one at least): each two children (ones, zeros) that
        partition the node's orders (module doc). ``"split"``: the out/in-arc splits nearest
        1/2 (the arcs rule when no node has one); ``"arc"``: the most fractional arcs."""
        count = max(PSEUDO_CANDIDATES if STRONG_CANDIDATES > 1 else 1, 1)
        none = np.zeros(0, dtype=np.int64)
        if self.branching == "split":
            splits = self._splits(values, ones, zeros)[:count]
            if splits:
                return [
                    _Branching(
                        key,
                        ones,
                        zeros,
                        ((none, first), (none, rest)),
                        (float(values[first].sum()), float(values[rest].sum())),
                    )
                    for key, first, rest in splits
                ]
        fractional = np.flatnonzero((values > INTEGRAL) & (values < 1 - INTEGRAL))
        if not len(fractional):  # an integral point cut by no row: cannot happen (module doc)
            raise RuntimeError("an integral point that is no order violates no row")
        ranked = fractional[np.argsort(np.abs(values[fractional] - 0.5), kind="stable")]
        return [
            _Branching(
                ("arc", arc),
                ones,
                zeros,
                ((np.array([arc]), none), (none, np.array([arc]))),
                (1.0 - float(values[arc]), float(values[arc])),
            )
            for arc in ranked[:count].tolist()
        ]

    def _branch(
        self,
        candidates: list[_Branching],
        lower: np.ndarray,
        upper: np.ndarray,
        basis: Any,
        value: float,
        bound: float,
        deadline: Deadline,
    ) -> tuple[_Branching, list[float], list[_ChildBasis | None]]:
        """Reliability branching over ``candidates`` at a node of LP value ``value`` and
        proven bound ``bound``: each is scored (:func:`_score`) by its children's estimated
        gains (:class:`PseudoCosts`); in that order, the ones not :data:`RELIABLE` are
        strong-branched (:meth:`_strong`), at most :data:`STRONG_CANDIDATES` and until
        :data:`LOOKAHEAD` in a row did not raise the best score, and scored by their
        children's measured gains instead. The best score among the strong-branched and the
        reliable ones is taken (the first in that order when none is). Returns it, its
        children's proven bounds (``bound`` each unless strong-branched; each raised to the
        largest of the strong-branched candidates' smaller child bounds: :data:`STRONG_FLOOR`)
        and their final bases (:data:`STRONG_BASES`; None unless strong-branched). With
        :data:`STRONG_FIXING`, the first strong-branched candidate with a child above the
        limit (no better order in it) is returned at once: the caller takes its other child
        in place. With :data:`STRONG_CUTOFF` the child LPs stop at the limit."""
        estimates = [self.pseudo.estimate(c.key, c.shares) for c in candidates]
        ranked = sorted(
            range(len(candidates)), key=lambda k: -_score(estimates[k], value)
        )  # stable: nearest 1/2 first among equal scores
        none: list[_ChildBasis | None] = [None, None]
        best: tuple[float, _Branching, list[float], bool, list[_ChildBasis | None]] = (
            -math.inf,
            candidates[ranked[0]],
            [bound] * 2,
            False,
            none,
        )
        highs = self.model.highs
        highs.setOptionValue("simplex_iteration_limit", STRONG_ITERATIONS)
        limit = self._limit()
        cutoff = STRONG_CUTOFF and math.isfinite(limit)
        if cutoff:
            highs.setOptionValue("objective_bound", limit)
        tried, idle, floor = 0, 0, bound
        try:
            for k in ranked:
                candidate = candidates[k]
                score, bounds, bases = _score(estimates[k], value), [bound, bound], none
                estimated = self.pseudo.reliable(candidate.key)
                if not estimated:
                    if tried >= STRONG_CANDIDATES or idle >= LOOKAHEAD:
                        continue
                    measured = self._strong(candidate, lower, upper, basis, value, bound, deadline)
                    if measured is None:  # the deadline
                        break
                    gains, bounds, bases = measured
                    if STRONG_FLOOR:
                        floor = max(floor, min(bounds))
                    if STRONG_FIXING and max(bounds) > limit:
                        return candidate, [max(b, floor) for b in bounds], bases
                    score, tried = _score(gains, value), tried + 1
                    idle = 0 if score > best[0] else idle + 1
                if score > best[0]:
                    best = (score, candidate, bounds, estimated, bases)
        finally:
            highs.setOptionValue("simplex_iteration_limit", ITERATIONS_UNLIMITED)
            if cutoff:
                highs.setOptionValue("objective_bound", highspy.kHighsInf)
        self.pseudo_branchings += best[3]
        self.strong_floors += sum(floor > b for b in best[2])
        return best[1], [max(b, floor) for b in best[2]], best[4]

    def _strong(
        self,
        candidate: _Branching,
        lower: np.ndarray,
        upper: np.ndarray,
        basis: Any,
        value: float,
        bound: float,
        deadline: Deadline,
    ) -> tuple[list[float], list[float], list[_ChildBasis | None]] | None:
        """Strong branching on one candidate: its two child LPs (warm from the node's basis,
        at most :data:`STRONG_ITERATIONS` simplex iterations and stopped at the limit
        (:data:`STRONG_CUTOFF`), both set by the caller; no separation), each a pseudo-cost
        observation. Returns the children's gains over the node's LP value ``value`` (the LP
        value where it stopped, a dual simplex value that only rises, scores a child stopped
        early; ``inf`` for an infeasible one), their proven bounds and their final bases
        (:data:`STRONG_BASES`, else None). None when the deadline passed first. The node's
        box and basis are restored after each child.

        A child's proven bound is ``inf`` when its LP is infeasible (no point of the rows in
        its box, hence no better order), else ``max(bound, node_bound)`` rounded up, the node
        bound (:func:`node_bound`) of the LP's duals on the child's box: weak duality holds
        for *any* row duals clipped to their signs, so it bounds every better order of the
        child whether the LP ended optimal or stopped at the iteration limit or the cutoff
        (:data:`STRONG_STOPPED`; off, a stopped child keeps ``bound``); without duals
        (``dual_valid`` false) it is ``-inf`` and the child keeps ``bound``."""
        model = self.model
        highs = model.highs
        proven, gains = [], []
        bases: list[_ChildBasis | None] = [None, None]
        for child in range(2):
            if deadline.expired(MARGIN):
                return None
            child_ones, child_zeros = candidate.child(child, model.n_arcs)
            child_lower = np.zeros(model.n_arcs)
            child_lower[child_ones] = 1.0
            child_upper = np.where(model.fixed, 0.0, 1.0)
            child_upper[child_zeros] = 0.0
            changed = np.flatnonzero((child_lower != lower) | (child_upper != upper)).astype(
                np.int32
            )
            highs.changeColsBounds(
                len(changed), changed, child_lower[changed], child_upper[changed]
            )
            model._run(deadline, brief=True)
            self.lps += 1
            self.strong_lps += 1
            self.strong_iterations += int(_info(highs, "simplex_iteration_count"))
            status = highs.getModelStatus()
            limit, gain = bound, math.inf
            if status == highspy.HighsModelStatus.kInfeasible:
                limit = math.inf
            else:
                gain = float(_info(highs, "objective_function_value")) - value
                optimal = status == highspy.HighsModelStatus.kOptimal
                if optimal or STRONG_STOPPED:
                    raw, _ = self._bound_of(child_lower, child_upper)
                    limit = max(bound, model.round_up(raw))
                    self.strong_stopped += not optimal
                self.pseudo.observe(candidate.key, child, gain, candidate.shares[child])
                if STRONG_BASES:
                    bases[child] = _ChildBasis(highs.getBasis(), self._pool().ids)
            proven.append(limit)
            gains.append(gain)
            highs.changeColsBounds(len(changed), changed, lower[changed], upper[changed])
            highs.setBasis(basis)
        return gains, proven, bases

    def _splits(
        self, values: np.ndarray, ones: np.ndarray, zeros: np.ndarray
    ) -> list[tuple[tuple[str, int], np.ndarray, np.ndarray]]:
        """The out- and in-arc splits (key ``("out" or "in", node)``, F, rest of the node's
        open arcs), ``x(F)`` nearest 1/2 first, over the nodes with two open arcs of positive value at least and no arc
        fixed to 1 on that side; F is built greedily from the arcs of largest value."""
        model = self.model
        open_arc = ~model.fixed
        open_arc[zeros] = False
        positive = open_arc & (values > INTEGRAL)
        found: list[tuple[float, tuple[str, int], np.ndarray, np.ndarray]] = []
        for side, ends in (("out", model.tails), ("in", model.heads)):
            counts = np.bincount(ends[positive], minlength=model.n)
            counts[ends[ones]] = 0
            split = counts >= 2
            # the open arcs of the split nodes by node, largest value first, ties by arc
            # (each node's ``argsort(-values, stable)`` over its arcs in increasing order)
            arcs = np.flatnonzero(open_arc & split[ends])
            arcs = arcs[np.lexsort((-values[arcs], ends[arcs]))]
            nodes, firsts = np.unique(ends[arcs], return_index=True)
            if not len(nodes):
                continue
            # each node's running sums x(F) in one row of a padded grid: ``cumsum`` along a
            # row adds in order (an accumulation, never pairwise), the 1-D sums' bits
            lengths = np.diff(np.append(firsts, len(arcs)))
            row = np.repeat(np.arange(len(nodes)), lengths)
            col = np.arange(len(arcs)) - np.repeat(firsts, lengths)
            grid = np.zeros((len(nodes), int(lengths.max())))
            grid[row, col] = values[arcs]
            total = np.cumsum(grid, axis=1)
            inside = np.arange(grid.shape[1]) < lengths[:, None]
            best = np.argmin(np.where(inside, np.abs(total - 0.5), np.inf), axis=1)
            best = np.minimum(best, lengths - 2)  # F and the rest both non-empty
            gaps = np.abs(total[np.arange(len(nodes)), best] - 0.5)
            for v, lo, k, hi, gap in zip(
                nodes.tolist(),
                firsts.tolist(),
                (firsts + best + 1).tolist(),
                (firsts + lengths).tolist(),
                gaps.tolist(),
                strict=True,
            ):
                found.append((gap, (side, v), arcs[lo:k], arcs[k:hi]))
        found.sort(key=lambda item: item[0])
        return [(key, first, rest) for _, key, first, rest in found]


#: The portfolio (:func:`taopt.models.sop.solve_sop_problem`'s last cut stage) runs this tree
#: in place of the MIP rounds of :func:`~taopt.models.sop_cuts.solve_sop_cuts` while the best
#: order is more than this share above the best bound (:func:`wants_tree`).
TREE_MIN_GAP = 0.01

#: Whether the tree's root stage runs the stretch rows
#: (:data:`~taopt.models.sop_cuts.STRETCH_CUTS`) when the tree has a peer process
#: (:mod:`taopt.models.sop_split`). False: the peer runs them, before it takes nodes, and sends
#: them (``Peer.stretch``), while this side starts its nodes. Their extended LP is serial
#: (2.2 s of interior point on prob.42). At 60 s with the split (load 1.4-2.0; docs/benchmarks.md,
#: "The tree in two processes"): at the root, prob.42 10.2-12.1 s, ft53.1 optimal in 42-51 s;
#: in the peer, prob.42 8.8-12.3 s, ft53.1 optimal in 35-38 s, ry48p.1's bound 15,409 against
#: 15,341-15,350.
SPLIT_STRETCH = False


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
    split: bool = False,
    peer: Any = None,
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
    split : bool
        Search the tree in two processes (:mod:`taopt.models.sop_split`): a peer process is
        started at once, builds its model while the root runs and takes nodes once ready.
    peer : taopt.models.sop_split.Peer, optional
        A peer process already started (the portfolio's); stopped and reaped here.

    Returns
    -------
    Solution
        "optimal" when the tree is empty, else "time_limit" with the best order and the proven
        bound; ``info`` has the root's keys, ``nodes``, ``lps``, ``cuts``, ``open``,
        ``max_depth``, ``strong_lps`` (of the ``lps``: strong branching's child LPs),
        ``pseudo_branchings`` (nodes branched on pseudo-costs alone), ``strong_iterations``
        and ``first_iterations`` (simplex iterations of the strong-branching LPs and of the
        nodes' first LPs), ``strong_stopped`` (strong child LPs stopped early that gave a
        node bound), ``strong_fixings`` (nodes that took a child in place),
        ``strong_floors`` (children whose bound :data:`STRONG_FLOOR` raised) and
        ``trace`` (seconds, bound) each time the bound rose.

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
    if split and peer is None:
        from taopt.models.sop_split import Peer

        peer = Peer(problem, time_limit)
    tree: BranchCut | None = None
    stop = "interrupted"  # until the search says otherwise
    try:
        stretch = peer is None or SPLIT_STRETCH  # with a peer, the peer's (SPLIT_STRETCH)
        model, known, bound, info = root_stage(
            problem, deadline, incumbent, verbose, model, stretch=stretch
        )
        if peer is not None and not stretch:
            peer.stretch = _wants_stretch(known, bound)
        tree = BranchCut(model, known, branching, began=began, peer=peer)
        tree._record(bound)
        stop = tree.run(deadline, node_limit, bound)
    finally:
        if peer is not None:  # reaped; its last answer (orders, bound, counts) read first
            # (waited for briefly where the tree closed: it needs nothing more of it)
            peer.close(tree, closed=stop != "time_limit")
    assert tree is not None  # made, or the try raised
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
            "strong_lps": tree.strong_lps,
            "pseudo_branchings": tree.pseudo_branchings,
            "strong_iterations": tree.strong_iterations,
            "first_iterations": tree.first_iterations,
            "strong_stopped": tree.strong_stopped,
            "strong_fixings": tree.strong_fixings,
            "strong_floors": tree.strong_floors,
            "fixed": int(model.fixed.sum()),
            "rows_end": tree.rows_end,
            "pool": None
            if tree.pool is None
            else {
                "retired": tree.pool.retired,
                "restored": tree.pool.restored,
                "stale": tree.pool.stale,
                "repaired": tree.pool.repaired,
            },
            "trace": tree.trace,
        }
    )
    if peer is not None:  # the peer's counts, and this side's of the exchange
        link = tree.link
        info["peer"] = {
            "startup": peer.startup,
            "loaded": link is not None,
            "lost": bool(link is not None and link.lost),
            **(tree.peer_counts or {}),
        }
        if link is not None:
            info["split"] = link.counts()
    return cut_solution(problem, known, "exact-sop-bc", stop, bound, began, info)
