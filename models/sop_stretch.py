"""Stretch-partition cuts: the three stretches of an order split by a precedence pair.

For a pair ``i ≺ j`` of inner nodes, every feasible order is the concatenation of three
paths, its *stretches*: ``start → i``, ``i → j`` and ``j → end``. Each arc of the order lies
on exactly one of them, and each stretch stays inside a known arc set:

* ``D_1``: arcs ``(u, v)`` with ``u, v ∉ σ(i)``, ``u ≠ i``, ``v ≠ start`` (the nodes before i);
* ``D_2``: arcs inside ``W(i, j) = V \\ (π(i) ∪ σ(j))`` with ``u ≠ j``, ``v ≠ i``;
* ``D_3``: arcs ``(u, v)`` with ``u, v ∉ π(j)``, ``v ≠ j``, ``u ≠ end``.

The extended formulation ``x = f_1 + f_2 + f_3``, ``f_k >= 0`` on ``D_k`` a unit flow from
the stretch's first node ``s_k`` to its last ``t_k``, holds for every order and is stronger
than the precedence path cut of the pair (which asks only for the unit flow ``f_2`` under
``x``): the three flows share the arcs' capacity and each is conserved on its own, so the
LP can no longer let the stretch from i to j reuse the fractional arcs the stretches before
i and after j pass along. Measured at the root of the cut loop with every path and set row
holding (:mod:`taopt.models.sop_cuts`, load 3-4): ft53.1 7,189 → 7,286, ry48p.1 14,775 →
14,834 (the optima are 7,531 and 15,805; the precedence-free path LP on the same matrices
is 6,905 and 14,290, so the rest of the gap is the precedences').

**The cut.** For node potentials ``p_k`` on each stretch and arc weights ``c`` with
``c_a >= p_k(head a) - p_k(tail a)`` for every ``k`` with ``a ∈ D_k``::

    Σ_a c_a x_a  >=  Σ_k ( p_k(t_k) - p_k(s_k) ).

Proof: an order's arcs are the disjoint union of its stretches, stretch k a path from
``s_k`` to ``t_k`` inside ``D_k``, so ``Σ_a c_a x_a = Σ_k Σ_{a ∈ stretch k} c_a >=
Σ_k Σ_{a ∈ stretch k} (p_k(head) - p_k(tail)) = Σ_k (p_k(t_k) - p_k(s_k))`` (the sum
telescopes along the path). Arcs in no ``D_k`` are used by no order and get weight 0.

**Separation** (:func:`stretch_rows`): the extended LP of a few pairs is solved beside the
cut model's rows, over the arcs of the LP point's support and those whose reduced cost is at
most :data:`STRETCH_REDUCED` times the LP's mean arc cost (the rest priced afterwards, below);
each pair's coupling rows ``x_a - Σ_k f_{k,a} = 0`` give ``c`` (their duals) and its
conservation rows give ``p_k`` (minus their duals). The weights are then set to
``c_a = max(dual_a, max_k p_k(head) - p_k(tail))`` over the stretches holding ``a`` (every arc,
in the LP or not), so the condition of the proof holds by construction whatever the LP's
tolerances; the right-hand side is lowered by ``n · 1e-9 · (1 + max |p|)`` for the floating
point of the telescoping sum. At the extended LP's optimum these rows together give the x-LP
that LP's value (LP duality), so one solve carries the extended formulation's bound into the
cut model, whose MIP rounds then hold them.

References
----------
E. Balas, M. Fischetti, W. Pulleyblank, "The precedence-constrained asymmetric traveling
salesman polytope", Math. Programming 68 (1995) (precedence inequalities). L. Gouveia,
M. Ruthmair, "Load-dependent and precedence-based models for pickup and delivery
problems", Computers & Operations Research 63 (2015) (flow formulations per precedence
pair).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import highspy
import numpy as np
import scipy.sparse as sp

from taopt.models.highs import new_highs, thread_options
from taopt.models.sop_statelp import constraint_matrix
from taopt.runtime import MARGIN, Deadline
from taopt.runtime.highs import interrupt_when, run_interruptibly

if TYPE_CHECKING:
    from taopt.models.sop_cuts import SopCutModel

__all__ = [
    "STRETCH_COLUMNS",
    "STRETCH_REDUCED",
    "STRETCH_ROUNDS",
    "STRETCH_SECONDS",
    "STRETCH_SHARE",
    "StretchRow",
    "stretch_domains",
    "stretch_rows",
]

#: Arcs of the extended LP: the LP point's support and those of reduced cost at most this
#: times the LP's mean arc cost (its value over ``n - 1``). A scale-free choice, not fitted: the
#: extended LP of ft53.1 over 722 such arcs of 2,722 reached the value of the one over all of
#: them (7,284.75) in 2.8 s instead of 18 s.
STRETCH_REDUCED = 1.0

#: At most this many (pair, arc) columns per stretch in one extended LP: pairs are taken, the
#: tightest path cut first (smallest maximum flow at the last point), while ``pairs × arcs``
#: stays below it. 12 pairs × 750 arcs solved in 2-4 s at load 4 (ry48p.1, ft53.1); at 20,000,
#: 26 pairs of ``p43-0.02-1`` did not solve in 40 s at load 8 (6 pairs: 6.4 s).
STRETCH_COLUMNS = 10_000

#: An extended LP gets at most this share of the time left (its own ``time_limit``).
STRETCH_SHARE = 0.25

#: Extended LPs solved per cut model at most (each one a few seconds; the first gives most).
STRETCH_ROUNDS = 2

#: Seconds per column of the extended LP that must be left before one is started: twice the
#: 1e-4 measured (25,000 columns in 2-4 s at load 4).
STRETCH_SECONDS = 2e-4

#: One stretch-partition row: (arcs, their weights, right-hand side), ``Σ w x >= rhs``.
StretchRow = tuple[np.ndarray, np.ndarray, float]


def stretch_domains(model: SopCutModel, i: int, j: int) -> list[tuple[np.ndarray, int, int]]:
    """The three stretches of the pair ``i ≺ j`` as (arc mask ``D_k``, first node, last node)
    (module docstring)."""
    before, tails, heads = model.before, model.tails, model.heads
    start, end = model.problem.start, model.problem.end
    first = ~before[i]  # not after i
    middle = ~before[:, i] & ~before[j]  # W(i, j)
    last = ~before[:, j]  # not before j
    return [
        (first[tails] & first[heads] & (tails != i) & (heads != start), start, i),
        (middle[tails] & middle[heads] & (tails != j) & (heads != i), i, j),
        (last[tails] & last[heads] & (heads != j) & (tails != end), j, end),
    ]


def _chosen_pairs(model: SopCutModel, arcs: int) -> list[tuple[int, int]]:
    """The inner closure pairs for one extended LP, the tightest path cut first."""
    start, end = model.problem.start, model.problem.end
    inner = [(int(i), int(j)) for i, j in model.pairs if i != start and j != end]
    inner.sort(key=lambda pair: float(model.flows[pair]))
    return inner[: max(1, STRETCH_COLUMNS // max(arcs, 1))]


def stretch_rows(
    model: SopCutModel, value: float, deadline: Deadline | None = None
) -> list[StretchRow] | None:
    """Stretch-partition rows violated at the cut model's last LP point (value ``value``),
    from one extended LP (module docstring). None when no extended LP was started: the model
    has no inner precedence pair, the LP has no duals, or the time left is below
    :data:`STRETCH_SECONDS` per column; empty when that LP found none or did not reach its
    optimum in the time left."""
    n = model.n
    reduced = model._lagrangian()[1]
    if reduced.size == 0:
        return None
    x = model.lp_values()
    keep = ~model.fixed & ((x > 1e-9) | (reduced <= STRETCH_REDUCED * max(value, 0.0) / (n - 1)))
    kept = np.flatnonzero(keep)
    pairs = _chosen_pairs(model, len(kept))
    if not pairs:
        return None
    domains = [stretch_domains(model, i, j) for i, j in pairs]
    columns = sum(int((mask & keep).sum()) for blocks in domains for mask, _, _ in blocks)
    if deadline is not None and deadline.limited:
        left = (deadline.remaining() or 0.0) - MARGIN
        if STRETCH_SHARE * left < STRETCH_SECONDS * (columns + len(kept)):
            return None
    lp = model.highs.getLp()
    base = constraint_matrix(lp).tocsc()[:, kept].tocsr()
    at = -np.ones(model.n_arcs, dtype=np.int64)
    at[kept] = np.arange(len(kept))
    rows, cols, vals, lower = [], [], [], []
    row, col = 0, len(kept)
    layout = []  # per pair: its coupling rows' first index, per stretch (mask, s, t, node rows)
    for blocks in domains:
        coupling = row
        row += len(kept)
        rows.append(coupling + np.arange(len(kept)))
        cols.append(np.arange(len(kept)))
        vals.append(np.ones(len(kept)))
        lower.append(np.zeros(len(kept)))
        stretches = []
        for mask, first, last in blocks:
            arcs = np.flatnonzero(mask & keep)
            flow = col + np.arange(len(arcs))
            col += len(arcs)
            node_row = np.full(n, -1, dtype=np.int64)
            nodes = np.union1d(model.tails[mask], model.heads[mask])
            nodes = np.union1d(nodes, [first, last]).astype(np.int64)
            node_row[nodes] = row + np.arange(len(nodes))
            row += len(nodes)
            rows += [coupling + at[arcs], node_row[model.tails[arcs]], node_row[model.heads[arcs]]]
            cols += [flow, flow, flow]
            vals += [-np.ones(len(arcs)), np.ones(len(arcs)), -np.ones(len(arcs))]
            supply = np.zeros(len(nodes))
            supply[nodes == first] += 1.0
            supply[nodes == last] -= 1.0
            lower.append(supply)
            stretches.append((mask, first, last, node_row))
        layout.append((coupling, stretches))
    extra = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(row, col)
    )
    matrix = sp.vstack(
        [sp.hstack([base, sp.csr_matrix((base.shape[0], col - len(kept)))]), extra]
    ).tocsc()
    sides = np.concatenate(lower)
    highs = _extended_lp(
        matrix,
        np.concatenate([model.costs[kept], np.zeros(col - len(kept))]),
        np.concatenate([np.ones(len(kept)), np.full(col - len(kept), highspy.kHighsInf)]),
        np.concatenate([np.asarray(lp.row_lower_, dtype=float), sides]),
        np.concatenate([np.asarray(lp.row_upper_, dtype=float), sides]),
    )
    if not _solved(highs, deadline):
        return []
    duals = np.asarray(highs.getSolution().row_dual, dtype=float)[base.shape[0] :]
    found = []
    for coupling, stretches in layout:
        weights = np.full(model.n_arcs, -np.inf)
        weights[kept] = duals[coupling : coupling + len(kept)]
        used = np.zeros(model.n_arcs, dtype=bool)
        side, largest = 0.0, 0.0
        for mask, first, last, node_row in stretches:
            potential = np.zeros(n)  # p_k = minus the conservation rows' duals
            inside = node_row >= 0
            potential[inside] = -duals[node_row[inside]]
            step = potential[model.heads] - potential[model.tails]
            weights = np.where(mask, np.maximum(weights, step), weights)
            used |= mask
            side += potential[last] - potential[first]
            largest = max(largest, float(np.abs(potential).max()))
        weights = np.where(used, weights, 0.0)
        side -= n * 1e-9 * (1.0 + largest)
        arcs = np.flatnonzero(weights != 0.0)
        if float(weights[arcs] @ x[arcs]) < side - 1e-6 * (1.0 + abs(side)):
            found.append((arcs, weights[arcs], float(side)))
    return found


def _extended_lp(
    matrix: sp.csc_matrix,
    costs: np.ndarray,
    upper: np.ndarray,
    row_lower: np.ndarray,
    row_upper: np.ndarray,
) -> highspy.Highs:
    """A HiGHS object holding the extended LP (columns in ``[0, upper]``), interior point."""
    highs = new_highs()
    for key, option in thread_options().items():
        highs.setOptionValue(key, option)
    highs.setOptionValue("solver", "ipm")
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = matrix.shape[1], matrix.shape[0]
    lp.col_cost_ = costs
    lp.col_lower_ = np.zeros(matrix.shape[1])
    lp.col_upper_ = upper
    lp.row_lower_ = row_lower
    lp.row_upper_ = row_upper
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = matrix.indptr.astype(np.int32)
    lp.a_matrix_.index_ = matrix.indices.astype(np.int32)
    lp.a_matrix_.value_ = matrix.data.astype(float)
    lp.a_matrix_.num_col_, lp.a_matrix_.num_row_ = matrix.shape[1], matrix.shape[0]
    highs.passModel(lp)
    return highs


def _solved(highs: highspy.Highs, deadline: Deadline | None) -> bool:
    """Run the extended LP within :data:`STRETCH_SHARE` of the time left; true when it reached
    its optimum."""
    if deadline is not None and deadline.limited:
        left = (deadline.remaining() or 0.0) - MARGIN
        highs.setOptionValue("time_limit", max(STRETCH_SHARE * left, 0.01))
    stop = (lambda: False) if deadline is None else (lambda: deadline.expired(MARGIN))
    with interrupt_when(highs, stop):
        run_interruptibly(highs)
    return bool(
        highs.getModelStatus() == highspy.HighsModelStatus.kOptimal
        and highs.getSolution().dual_valid
    )
