"""Exact sequential ordering problem (SOP) in cvxpy + HiGHS.

Problem: on an asymmetric cost matrix ``cost`` (n × n, ``inf`` = forbidden
arc), find the cheapest Hamiltonian PATH ``start -> ... -> end`` visiting every
node once such that every precedence pair ``(r, j)`` has r before j. It is the
ordering core of chapter 5: with the drone cost matrix t* (5.11) and the
precedences of (5.7) it is the problem NIA, MMA and SMMA (§5.4) solve
heuristically; TSPLIB's .sop instances (:mod:`taopt.sop.problem`) certify it.

Sets and data: nodes ``V = {0..n-1}``; ``P`` the transitive closure of the
precedence pairs with ``start ≺ v ≺ end`` for every inner v; ``pred(v)`` /
``succ(v)`` the nodes that must come before / after v.

Arc reduction (safe, proved by the precedences alone): arc ``i -> j`` exists
only if ``i ≠ j``, ``cost[i, j]`` is finite, and no node k has ``i ≼ ... ``
``i ≺ k ≺ j`` (k would have to lie between i and j, so they cannot be
consecutive) and not ``j ≺ i``. This removes every arc into start, out of end,
start -> j for j with a predecessor, i -> end for i with a successor.

Variables: binary ``x_a`` per remaining arc a = (i, j): i is directly followed
by j.

* objective: ``min Σ_a cost_a x_a``
* degree: every node except end is left once, every node except start is
  entered once.
* connectivity and precedence, one of two ways (``formulation``):

  - ``"flow"`` (default) — multi-commodity flow: for every node k ≠ start one
    unit of commodity k flows from start to k along chosen arcs
    (``0 ≤ f^k_a ≤ x_a``, conservation). Every node is then reachable from
    start on the chosen arcs, so the degree-feasible x has no subtour and is a
    single path start -> end. Precedence r ≺ k: commodity k's path (which is
    the chosen path's prefix up to k) passes through r: ``Σ_{a into r} f^k_a
    = 1``; and commodity k never touches a successor of k nor leaves k (those
    f are not created). O(n·|A|) variables; the LP bound is at least the DFJ
    subtour bound and is strengthened by the precedence rows.
  - ``"mtz"`` — Miller–Tucker–Zemlin positions ``u_v`` with the
    Desrochers–Laporte lifting, ``u_start = 0``, ``u_end = n − 1`` and
    ``u_r + 1 ≤ u_j`` per precedence. Compact but weak (see
    ``benchmarks/bench_sop.py``: br17.x are very slow with it).

Measured on the TSPLIB files (``benchmarks/bench_sop.py``, 2 shared cores): the
flow model proves ESC07, ESC11, ESC12 in < 0.2 s, br17.10 in 3.5–5 s, br17.12
in 9–13 s and ESC25 in ~52 s; MTZ proves ESC07/11/12 but stops at bound 38
(br17.10) and 45 (br17.12) after 60 s. The nesting rows are what closes
br17.x: without them the flow LP bound of br17.10 is 39.7 and a 120 s run
ended at bound 47; with them the LP bound is the optimum 55. "flow" is therefore the default.

The portfolio (:func:`solve_sop_problem`) no longer uses this model by default: its MILP
stage is the arc model with precedence path cuts of :mod:`taopt.models.sop_cuts`, built as
arrays straight into HiGHS (root bound 28,098 on p43.1, optimum 28,140, where this flow
model's LP is not solved within 30 s on a loaded machine and the portfolio proved 2,720).

Example
-------
>>> from taopt.sop.problem import load_sop
>>> cost, precedences, start, end, name = load_sop("ESC07")
>>> solve_sop(cost, precedences, start, end).objective
2125.0
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment

from taopt.errors import InstanceError, SolverError
from taopt.models.highs import HighsModel, solve_highs
from taopt.models.sop_lns import large_neighbourhood_search
from taopt.models.sop_statelp import StateLp
from taopt.models.sop_window import start_prices, window_prices, windows
from taopt.result import (
    FEASIBLE,
    INFEASIBLE,
    OPTIMAL,
    TIME_LIMIT,
    Order,
    Solution,
    finish,
)
from taopt.runtime import MARGIN, CancelToken, Deadline, cancel_scope, register_footprint
from taopt.runtime.workers import Background
from taopt.sop.problem import (
    SopProblem,
    check_sop,
    evaluate_order,
    path_cost,
    sop_arborescence_bound,
    usable_arcs,
)
from taopt.status import decide

logger = logging.getLogger(__name__)  # a child of the "taopt" logger

FORMULATIONS = ("flow", "mtz")

__all__ = [
    "CUTS_SECOND_STAGE_GAP",
    "FORMULATIONS",
    "PORTFOLIO_FORMULATION",
    "SopModel",
    "build",
    "decode",
    "assignment_bound",
    "column_count",
    "nonzero_count",
    "describe",
    "solve_sop",
    "solve_sop_problem",
    "check_sop",
]


# ----------------------------------------------------------------------------- model
@dataclass
class SopModel:
    """A built SOP model: the cvxpy problem and handles to its variables.

    Attributes
    ----------
    problem : cvxpy.Problem
    arc_use : cvxpy.Variable
        x over the arc list ``tails[a] -> heads[a]``.
    tails, heads : numpy arrays
    cost : numpy array
        The validated cost matrix.
    start, end : int
    formulation : str
    flow : cvxpy.Variable or None
        Multi-commodity flow over the allowed (commodity, arc) pairs.
    position : cvxpy.Variable or None
        MTZ positions.
    """

    problem: cp.Problem
    arc_use: cp.Variable
    tails: np.ndarray
    heads: np.ndarray
    cost: np.ndarray
    start: int
    end: int
    formulation: str
    flow: cp.Variable | None = None
    position: cp.Variable | None = None


def build(
    cost: Any,
    precedences: Any,
    start: int,
    end: int,
    formulation: str = "flow",
    relax: bool = False,
    deadline: Deadline | None = None,
) -> SopModel:
    """Build the SOP model (see the module docstring for the formulation).

    Parameters
    ----------
    cost : (n, n) array_like
        Arc costs, ``inf`` for a forbidden arc; the diagonal is ignored.
    precedences : iterable of (r, j)
        r before j.
    start, end : int
        First and last node of the path.
    formulation : {"flow", "mtz"}
    relax : bool
        Continuous ``0 ≤ x ≤ 1``: the LP relaxation.
    deadline : taopt.runtime.Deadline, optional
        Checked while the rows are built: :class:`BuildStopped` when it passes.

    Returns
    -------
    SopModel
    """
    if formulation not in FORMULATIONS:
        raise InstanceError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
    cost, closure = check_sop(cost, precedences, start, end)
    n = cost.shape[0]
    tails, heads = usable_arcs(cost, closure)
    n_arcs = len(tails)
    arcs = np.arange(n_arcs)
    arc_use = cp.Variable(n_arcs, boolean=not relax, name="x")
    # node-arc incidence: out_of[v, a] = 1 if a leaves v, into[v, a] = 1 if a enters v
    out_of = sp.csr_matrix((np.ones(n_arcs), (tails, arcs)), shape=(n, n_arcs))
    into = sp.csr_matrix((np.ones(n_arcs), (heads, arcs)), shape=(n, n_arcs))
    inner_out = np.array([v for v in range(n) if v != end])
    inner_in = np.array([v for v in range(n) if v != start])
    constraints = [
        (out_of[inner_out] @ arc_use == 1).set_label("degree: every node but end is left once"),
        (into[inner_in] @ arc_use == 1).set_label("degree: every node but start is entered once"),
    ]
    if relax:
        constraints.append((arc_use <= 1).set_label("0 <= x <= 1 (LP relaxation)"))
        constraints.append((arc_use >= 0).set_label("0 <= x <= 1 (LP relaxation)"))
    # ignore: the problem (None for now) is set below, once the row builders added their rows
    model = SopModel(None, arc_use, tails, heads, cost, start, end, formulation)  # type: ignore[arg-type]
    if formulation == "flow":
        constraints += _flow_rows(model, closure, deadline)
    else:
        constraints += _mtz_rows(model, closure)
    objective = cp.Minimize(cost[tails, heads] @ arc_use)
    model.problem = cp.Problem(objective, constraints)
    return model


class BuildStopped(Exception):
    """The deadline passed while :func:`build` made the rows (internal: the caller returns
    its incumbent with status ``time_limit``)."""


def _check(deadline: Deadline | None) -> None:
    if deadline is not None and deadline.expired(MARGIN):
        raise BuildStopped


def _flow_rows(model: SopModel, closure: nx.DiGraph, deadline: Deadline | None = None) -> list:
    """Multi-commodity flow rows: connectivity and precedence (see module docstring)."""
    tails, heads, start, n = model.tails, model.heads, model.start, model.cost.shape[0]
    commodities = np.array([k for k in range(n) if k != start])
    before = nx.to_numpy_array(closure, nodelist=range(n), dtype=bool, weight=None)
    # commodity k may use arc (i, j) only if neither end is a successor of k and i != k
    usable = ~before[commodities][:, tails] & ~before[commodities][:, heads]
    usable &= tails[None, :] != commodities[:, None]
    pair_k, pair_a = np.nonzero(usable)  # pair p = (commodity index, arc)
    n_pairs = len(pair_k)
    flow = cp.Variable(n_pairs, nonneg=True, name="f")
    model.flow = flow
    pairs = np.arange(n_pairs)
    n_com = len(commodities)
    # conservation: row (k, v): out - in = [v == start] - [v == k]
    node_rows_out = pair_k * n + tails[pair_a]
    node_rows_in = pair_k * n + heads[pair_a]
    balance = sp.csr_matrix(
        (
            np.concatenate([np.ones(n_pairs), -np.ones(n_pairs)]),
            (np.concatenate([node_rows_out, node_rows_in]), np.concatenate([pairs, pairs])),
        ),
        shape=(n_com * n, n_pairs),
    )
    supply: np.ndarray = np.zeros((n_com, n))
    supply[:, start] = 1.0
    supply[np.arange(n_com), commodities] = -1.0
    supply = supply.ravel()
    # rows whose node is untouched by commodity k are 0 = 0 (or infeasible if supply != 0)
    touched = np.zeros(n_com * n, dtype=bool)
    touched[node_rows_out] = True
    touched[node_rows_in] = True
    if (supply[~touched] != 0).any():
        row = int(np.flatnonzero(~touched & (supply != 0))[0])
        raise InstanceError(
            f"node {commodities[row // n]} cannot be reached from start {start} "
            "by any usable arc (forbidden arcs and precedences leave no path)"
        )
    keep = np.flatnonzero(touched)
    _check(deadline)
    capacity = sp.csr_matrix((np.ones(n_pairs), (pairs, pair_a)), shape=(n_pairs, len(tails)))
    rows = [
        (balance[keep] @ flow == supply[keep]).set_label(
            "flow conservation: commodity k sends one unit from start to k"
        ),
        (flow <= capacity @ model.arc_use).set_label("flow capacity: f^k_ij <= x_ij"),
    ]
    # precedence r ≺ k (r ≠ start): commodity k enters r exactly once
    prec_r, prec_k = [], []
    for r, k in closure.edges():
        if r != start and k != start:
            prec_r.append(r)
            prec_k.append(int(np.searchsorted(commodities, k)))
    if prec_r:
        # keys (commodity, node): numpy integers find them as Python ints do
        row_of: dict[tuple[Any, Any], int] = {
            (k, r): i for i, (k, r) in enumerate(zip(prec_k, prec_r, strict=True))
        }
        entries = [
            (row_of[(k, heads[a])], p)
            for p, (k, a) in enumerate(zip(pair_k, pair_a, strict=True))
            if (k, heads[a]) in row_of
        ]
        r_idx, c_idx = zip(*entries, strict=True) if entries else ((), ())
        through = sp.csr_matrix((np.ones(len(r_idx)), (r_idx, c_idx)), shape=(len(prec_r), n_pairs))
        rows.append(
            (through @ flow == 1).set_label(
                "(5.7) precedence r before k: commodity k's path enters r"
            )
        )
        # nesting r ≺ k: in an integral solution f^v is exactly the path's prefix up to v
        # (the chosen arcs form one path, which has no cycle), and the prefix up to r
        # lies inside the prefix up to k, so f^r_a <= f^k_a on every arc r may use
        # (arcs usable by r are usable by k: k's successors are r's successors).
        # These rows lift the LP bound of br17.10 from 39.7 to the optimum 55.
        pair_of = -np.ones((n_com, len(tails)), dtype=np.int64)
        pair_of[pair_k, pair_a] = pairs
        nest_row, nest_col, nest_val = [], [], []
        count = 0
        for number, (r, k) in enumerate(closure.edges()):
            if number % 256 == 0:
                _check(deadline)
            if r == start:
                continue
            r_pairs = pair_of[np.searchsorted(commodities, r)]
            k_pairs = pair_of[np.searchsorted(commodities, k)]
            arcs_r = np.flatnonzero(r_pairs >= 0)
            rows_here = count + np.arange(len(arcs_r))
            nest_row += [rows_here, rows_here]
            nest_col += [r_pairs[arcs_r], k_pairs[arcs_r]]
            nest_val += [np.ones(len(arcs_r)), -np.ones(len(arcs_r))]
            count += len(arcs_r)
        nesting = sp.csr_matrix(
            (np.concatenate(nest_val), (np.concatenate(nest_row), np.concatenate(nest_col))),
            shape=(count, n_pairs),
        )
        rows.append(
            (nesting @ flow <= 0).set_label(
                "(5.7) precedence nesting r before k: f^r_ij <= f^k_ij (prefix inside prefix)"
            )
        )
    return rows


def _mtz_rows(model: SopModel, closure: nx.DiGraph) -> list:
    """MTZ positions (Desrochers–Laporte lifted) and precedence ``u_r + 1 <= u_j``."""
    tails, heads, start, end = model.tails, model.heads, model.start, model.end
    n = model.cost.shape[0]
    position = cp.Variable(n, name="u")
    model.position = position
    n_pred = np.array([closure.in_degree(v) for v in range(n)])
    n_succ = np.array([closure.out_degree(v) for v in range(n)])
    # a node with p predecessors and s successors sits at a position in [p, n-1-s]
    rows = [
        (position >= n_pred).set_label("MTZ: u_v >= number of predecessors"),
        (position <= n - 1 - n_succ).set_label("MTZ: u_v <= n - 1 - number of successors"),
    ]
    # u_j >= u_i + 1 - (n-1)(1 - x_ij) - (n-3) x_ji  (lifted; x_ji only if that arc exists)
    index = {(int(i), int(j)): a for a, (i, j) in enumerate(zip(tails, heads, strict=True))}
    n_arcs = len(tails)
    reverse = np.array([index.get((int(j), int(i)), -1) for i, j in zip(tails, heads, strict=True)])
    has_rev = reverse >= 0
    lift = sp.csr_matrix(
        (np.full(has_rev.sum(), n - 3.0), (np.flatnonzero(has_rev), reverse[has_rev])),
        shape=(n_arcs, n_arcs),
    )
    tail_of = sp.csr_matrix((np.ones(n_arcs), (np.arange(n_arcs), tails)), shape=(n_arcs, n))
    head_of = sp.csr_matrix((np.ones(n_arcs), (np.arange(n_arcs), heads)), shape=(n_arcs, n))
    rows.append(
        (
            tail_of @ position - head_of @ position + (n - 1) * model.arc_use + lift @ model.arc_use
            <= n - 2
        ).set_label("MTZ (lifted): u_i - u_j + (n-1) x_ij + (n-3) x_ji <= n - 2")
    )
    edges = [(r, j) for r, j in closure.edges() if r != start and j != end]
    if edges:
        r_arr, j_arr = np.array(edges).T
        rows.append(
            (position[r_arr] + 1 <= position[j_arr]).set_label("(5.7) precedence: u_r + 1 <= u_j")
        )
    return rows


def describe(
    cost: Any,
    precedences: Any,
    start: int,
    end: int,
    formulation: str = "flow",
    show: bool = True,
) -> list[dict]:
    """Constraint families of the built model, with their row counts.

    Returns a list of ``{"label", "rows"}``; logs a table at INFO on the ``taopt`` logger
    when ``show``.
    """
    model = build(cost, precedences, start, end, formulation)
    families: dict[str, int] = {}
    for constraint in model.problem.constraints:
        families[constraint.label] = families.get(constraint.label, 0) + constraint.size
    table = [{"label": k, "rows": v} for k, v in families.items()]
    if show:
        n_vars = sum(v.size for v in model.problem.variables())
        lines = [f"SOP ({formulation}): {len(model.tails)} arcs, {n_vars} variables"]
        lines += [f"  {row['rows']:>7}  {row['label']}" for row in table]
        logger.info("\n".join(lines))
    return table


def decode(model: SopModel, values: np.ndarray | None = None) -> list[int]:
    """The path ``start -> ... -> end`` chosen by ``x`` (values > 0.5).

    Raises
    ------
    SolverError
        The chosen arcs are not one Hamiltonian path from start to end.
    """
    values = model.arc_use.value if values is None else values
    if values is None:
        raise SolverError("the model has no solution to decode")
    chosen = np.asarray(values) > 0.5
    successor = dict(zip(model.tails[chosen].tolist(), model.heads[chosen].tolist(), strict=True))
    order = [model.start]
    while order[-1] in successor and len(order) <= len(model.cost):
        order.append(successor[order[-1]])
    if len(order) != len(model.cost) or order[-1] != model.end:
        raise SolverError(f"decoded arcs do not form one path start -> end: {order}")
    return order


# ----------------------------------------------------------------------------- solve
def _check_path(model: SopModel, order: list[int], precedences: Any, model_value: float) -> float:
    """Re-cost the decoded path from the data and check it without trusting the solver.

    Checks every precedence ``(r, j)`` (r before j) on the decoded order, and
    that the path's cost from ``model.cost`` equals the model's objective
    within 1e-6 relative. Returns the re-costed value.

    Raises
    ------
    SolverError
        A precedence is violated, the path uses a forbidden arc, or the costs differ.
    """
    where = np.empty(len(order), dtype=np.int64)
    where[order] = np.arange(len(order))
    for pair in precedences:
        r, j = (int(v) for v in pair)
        if where[r] > where[j]:
            raise SolverError(
                f"decoded order visits {j} (position {where[j]}) before {r} "
                f"(position {where[r]}): precedence ({r}, {j}) violated"
            )
    legs = model.cost[order[:-1], order[1:]]
    if not np.isfinite(legs).all():
        leg = int(np.flatnonzero(~np.isfinite(legs))[0])
        raise SolverError(f"decoded order uses forbidden arc {order[leg]} -> {order[leg + 1]}")
    objective = float(legs.sum())
    if abs(objective - model_value) > 1e-6 * max(abs(objective), abs(model_value), 1e-12):
        raise SolverError(
            f"decoded path costs {objective!r} but the model's objective is {model_value!r}"
        )
    return objective


#: Seconds per column to build the flow model and compile it with cvxpy for HiGHS (measured
#: 2.4e-5 on ESC47, 100,611 columns: 0.45 s to build, 2.0 s to compile; up to 8e-5 on
#: rbg048a on a loaded machine). A run whose estimate exceeds its time limit does not build.
SECONDS_PER_COLUMN = 3e-5

#: Share of the build estimate spent compiling inside cvxpy's solve (outside HiGHS's clock).
COMPILE_SHARE = 0.8

#: cvxpy's compile for HiGHS takes 4-9 times as long as building the model (ESC47 0.45 s ->
#: 2.0 s, ry48p.4 0.40 -> 1.65, prob.42 0.20 -> 1.39, rbg048a 0.53 -> 4.84); the measured
#: build time times this is the compile estimate, which follows the machine's load.
COMPILE_PER_BUILD = 8.0


#: The portfolio builds the flow model after its DP stages only when the time left is at
#: least this many times :func:`compile_seconds` (a loaded machine compiles 2-4 times slower
#: than :data:`SECONDS_PER_COLUMN` says, and cvxpy's compile cannot be interrupted).
MILP_SAFETY = 3.0


def compile_seconds(columns: float) -> float:
    """Estimated seconds to build the flow model of ``columns`` columns and compile it for
    HiGHS: :data:`SECONDS_PER_COLUMN` a column to build and :data:`COMPILE_PER_BUILD` times a
    build of about a third of that to compile."""
    return float(columns) * SECONDS_PER_COLUMN * (1.0 + COMPILE_PER_BUILD / 3.0)


def column_count(
    cost: np.ndarray, closure: nx.DiGraph, start: int, formulation: str = "flow"
) -> int:
    """Number of variables of the model :func:`build` would make, without building it."""
    tails, heads = usable_arcs(cost, closure)
    n = cost.shape[0]
    if formulation == "cuts":  # the arc model of taopt.models.sop_cuts: one column per arc
        return len(tails)
    if formulation == "mtz":
        return len(tails) + n
    before = nx.to_numpy_array(closure, nodelist=range(n), dtype=bool, weight=None)
    commodities = np.array([k for k in range(n) if k != start])
    usable = ~before[commodities][:, tails] & ~before[commodities][:, heads]
    usable &= tails[None, :] != commodities[:, None]
    return len(tails) + int(usable.sum())


def nonzero_count(
    cost: np.ndarray, closure: nx.DiGraph, start: int, formulation: str = "flow"
) -> int:
    """About the nonzeros of the constraint matrix :func:`build` would make, without building
    it: three per flow column (conservation twice, capacity) and two per nesting entry (one
    per arc commodity r may use, for every precedence r before k). The memory of the flow
    model follows these, not its columns: the nesting rows dominate under dense precedence
    (rbg, chains)."""
    tails, heads = usable_arcs(cost, closure)
    n = cost.shape[0]
    if formulation == "cuts":
        # the arc model of taopt.models.sop_cuts: two degree rows per arc, and the cut pool
        # (rows added in the loop; not measured: counted as one more entry per arc)
        return 3 * len(tails)
    if formulation == "mtz":
        return 4 * len(tails) + 2 * n + 2 * closure.number_of_edges()
    before = nx.to_numpy_array(closure, nodelist=range(n), dtype=bool, weight=None)
    commodities = np.array([k for k in range(n) if k != start])
    usable = ~before[commodities][:, tails] & ~before[commodities][:, heads]
    usable &= tails[None, :] != commodities[:, None]
    per = usable.sum(axis=1)
    tail_of = np.array([r for r, _k in closure.edges() if r != start], dtype=np.int64)
    nesting = int(per[np.searchsorted(commodities, tail_of)].sum()) if len(tail_of) else 0
    return 3 * int(per.sum()) + 2 * len(tails) + 2 * nesting


# The memory model below is measured, not derived: ``python benchmarks/bench_sop_memory.py
# --stages dp,beam,milp,cpsat --generated --time-limit 5 --out runs.jsonl`` runs each stage
# on each of the 16 TSPLIB SOP files (shipped and ../shared/benchmarks/tsplib) and 6
# generated instances of 100-380 nodes in a fresh interpreter and records its peak RSS
# (``ru_maxrss``); ``--fit runs.jsonl`` prints the constants (minimax of the ratio estimate /
# peak). Re-run both after the flow model changes.

#: Peak resident bytes of a process that has imported taopt, numpy, scipy, cvxpy and highspy
#: and loaded an instance (measured: 154-155 MB over 67 runs, 2026-11; 159-162 MB for the
#: shipped files of 9-18 nodes, closed in under a second, 2026-11-27, ``bench_sop.py
#: --resources 60``).
BASE_BYTES = 160e6

#: Bytes per DP state kept, one-word masks (the state arrays, 32 bytes, and the work arrays
#: of the largest layer's extensions, merge and completion bound); 8 more per extra word.
#: The state caps count a state at this (:func:`dp_state_cap`), so it is the largest measured
#: per state of a stage that filled many states: prob.42, 1.11 million states at 927 MB
#: (695 B a state; p43.1 1.78 million at 949 MB, 446 B; 2026-11, ``bench_sop.py --resources
#: 60``). Per state alone the peaks of short runs spread from 94 B (p43.4, dense precedence:
#: few extensions per state) to 1.5 KB (ESC47, ft53.1: a setup of 50-100 MB the base
#: absorbs); the reported estimate (:func:`predicted_peak`) scales it by
#: :func:`dp_state_share` (squared), the guard does not. Since the layers' extensions are
#: merged per node as they are made (``taopt.models.sop_dp._Search.grow``, 2026-11-27) the
#: measured peaks are 150-1,070 B per expected state (ry48p.1 at 10 s: 442-556 MB before,
#: 247-264 MB after): the guard and the state caps kept at 700 B stay above them.
DP_BYTES_PER_STATE = 700.0


#: Peak bytes per nonzero (:func:`nonzero_count`) of the flow MILP built with cvxpy,
#: compiled for HiGHS and solved, above :data:`SOP_MILP_BYTES` (fitted: within 1.16x of 9
#: measured runs, 1,300-471,000 nonzeros; per column the same runs spread from 3 KB (p43.1)
#: to 9 KB (p43.4); the generic :data:`taopt.runtime.memory.MILP_BYTES_PER_COLUMN`, 2 KB,
#: is low here).
SOP_MILP_BYTES_PER_NONZERO = 510.0

#: Fixed peak bytes of a compiled flow MILP (HiGHS's and cvxpy's work space).
SOP_MILP_BYTES = 35e6

#: Peak bytes per nonzero of the flow model built with cvxpy but not compiled (the portfolio
#: stops there when the compile cannot end in time): 65 B within 1.03x of 8 measured runs,
#: 0.56-6.1 million nonzeros (ESC47, ry48p.x, rbg048a, rbg050c, ft53.x, a 100-node chain SOP).
SOP_BUILD_BYTES_PER_NONZERO = 65.0


def sop_milp_bytes(nonzeros: float, compiled: bool = True) -> float:
    """Estimated peak bytes of the flow MILP of ``nonzeros`` nonzeros (:func:`nonzero_count`)
    beyond the base: compiled for HiGHS and solved, or only built; 0 for no model."""
    if not nonzeros:
        return 0.0
    if not compiled:
        return SOP_BUILD_BYTES_PER_NONZERO * float(nonzeros)
    return SOP_MILP_BYTES + SOP_MILP_BYTES_PER_NONZERO * float(nonzeros)


#: The guard's factor on :func:`dp_states_in` over the whole limit (the registered footprint; the
#: state caps, counted at the full :data:`DP_BYTES_PER_STATE`, bound a stage anyway): the
#: most a DP stage was measured to keep over the expected, 1.4 (ry48p.1 at 60 s, 1.25
#: million states, 2026-11-27).
GUARD_STATE_FACTOR = 1.5

#: States a DP stage is expected to keep per second over a stage of
#: :data:`DP_RATE_SECONDS` (the memory estimate's rate, below the stage's state cap and the
#: states the ideals allow; :func:`dp_states_in`). A stage that cannot close fills its cap at
#: 20,000-80,000 a second on this machine (prob.42: 385,000 states in its 5 s stage, p43.1:
#: 1.78 million in 30 s, quiet; 454,000 in 20 s at load 5); one that closes keeps what it
#: needs and stops (ESC47: 30,000 states in 4 s; ft53.4: 494,000 in 7 s). Nothing known
#: before the run tells the two apart (same size, ideals past the count's cap), so the rate
#: is fitted to keep the most runs within 2x of their peaks (``bench_sop.py --resources``
#: at 10 s and 60 s, CP-SAT on and off; docs/benchmarks.md, SOP memory). Not a limit: the
#: cap (:func:`dp_state_cap`) keeps a DP stage within the memory.
DP_STATES_PER_SECOND = 24_000

#: The stage length (seconds) at which a DP stage is expected to keep
#: :data:`DP_STATES_PER_SECOND` a second.
DP_RATE_SECONDS = 5.0

#: Exponent of a DP stage's expected states in its length (:func:`dp_states_in`): below 1,
#: as a flat rate cannot hold both the 10 s runs that fill their states (prob.42, ry48p.1:
#: 2.0-2.2x above a flat 16,000 a second) and the 60 s runs that close early (ESC47 with
#: CP-SAT beside: 0.46x below a flat 20,000).
DP_RATE_EXPONENT = 0.8


def dp_states_per_second(n: int) -> float:
    """States a DP stage keeps per second on ``n`` nodes over :data:`DP_RATE_SECONDS`:
    :data:`DP_STATES_PER_SECOND` up to 64 nodes, then in proportion to ``64 / n`` (a state's
    bound and extensions cost about ``n`` node steps: the rbg-like stand-ins of 110-175 nodes
    kept 1,200-2,700 a second at load 11, and a flat rate put the estimate 2.3-2.8x above
    their peaks)."""
    return DP_STATES_PER_SECOND * min(1.0, 64.0 / max(n, 1))


def dp_states_in(n: int, seconds: float) -> float:
    """States a DP stage of ``seconds`` on ``n`` nodes is expected to keep (the memory
    estimate's count, before its cap): :func:`dp_states_per_second` times
    :data:`DP_RATE_SECONDS` times ``(seconds / DP_RATE_SECONDS) ** DP_RATE_EXPONENT``;
    increasing in ``seconds``, 0 for none."""
    if seconds <= 0:
        return 0.0
    span = DP_RATE_SECONDS * (seconds / DP_RATE_SECONDS) ** DP_RATE_EXPONENT
    return dp_states_per_second(n) * span


#: A DP stage's setup (outside its clock) over the cheap bounds' time (assignment and arborescence,
#: measured in the portfolio): chains-380-8-x0.01 set up in 3.8-4.2 s after 0.5-0.8 s of
#: cheap bounds at load 7-8 (2026-11-27; its two directions' bounds on both price sets). A
#: first DP stage after the root stage starts only when its share covers this guess.
DP_SETUP_PER_BOUND = 5.0

#: The share of a time limit the MILP stage gets after the warm start and the two DP
#: stages ((1 - WARM_START_SHARE) (1 - DP_SHARE) (1 - SECOND_STAGE_SHARE), about 0.1).
MILP_TIME_SHARE = 0.1


def dp_bytes(n: int, states: float) -> float:
    """Estimated peak bytes of the DP keeping ``states`` states on ``n`` nodes (beyond the
    process's :data:`BASE_BYTES`)."""
    from taopt.ideals import is_wide, words

    extra = 8.0 * (words(n) - 1) if is_wide(n) else 0.0
    return (DP_BYTES_PER_STATE + extra) * float(states)


def dp_state_share(problem: SopProblem) -> float:
    """The share of :data:`DP_BYTES_PER_STATE` a kept state costs on ``problem``'s precedence:
    ``(1 - c) / 0.89`` for a closure holding a share ``c`` of the inner pairs, in
    ``[0.2, 1]``. A state's work arrays follow its extensions, fewer under dense precedence:
    per state the measured peaks spread from 94 B (p43.4, c = 0.58) to 1.5 KB (ESC47,
    c = 0.11), and with the DP alone for a whole 60 s limit the flat constant put p43.4's
    estimate at 2.4x its peak. Used for the estimate only; the state caps keep the full
    constant."""
    return float(min(1.0, max(0.2, (1.0 - closure_share(problem)) / 0.89)))


#: Exponent of :func:`dp_state_share` in the reported estimate's bytes a state
#: (:func:`predicted_peak`). Since a layer's extensions are merged per node as they are made
#: (``taopt.models.sop_dp._Search.grow``) and the bound works in chunks of fixed size, the
#: peak above the base follows the widest layer's merged states, which fall with the
#: extensions a state has, as does the count of states (:func:`fill_states`): measured per
#: expected state at 10 s (2026-11-27, ``bench_sop.py --resources 10``, shipped set and
#: ``--unseen``, load 5-6), 66-157 B at share 0.48-0.50 (p43.4, ry48p.4, ft53.4),
#: 280-390 B at 0.66-0.68 (rbg048a, rbg050c), 240-1,070 B at 1. With the share itself
#: ft53.4's estimate was 1.85x its peak; squared, the shipped and stand-in runs sit at
#: 0.77-1.06 of their peaks.
DP_SHARE_EXPONENT = 2.0


def closure_share(problem: SopProblem) -> float:
    """The share ``c`` of the inner node pairs (start and end left out) that the precedence
    closure orders (0 for none, 1 for a chain)."""
    m = problem.n - 2
    if m < 2:
        return 0.0
    ends = 2 * m + 1  # start before and end after every node
    return float(max(0.0, problem.closure.number_of_edges() - ends) / (m * (m - 1) / 2))


#: Peak bytes per beam slot (width x nodes) of ``taopt.models.sop_dp.beam_order``: its
#: layers kept for the path and the extensions of one layer before the cut (fitted: 37 B
#: within 1.08x of 17 passes of width 4,096 on 9-380 nodes; 50 B kept, as the wider passes
#: cut off by the 5 s limit stopped before their widest layers).
BEAM_BYTES_PER_SLOT = 50.0


def beam_bytes(n: int, width: int) -> float:
    """Estimated peak bytes of a beam pass of ``width`` on ``n`` nodes (beyond the base)."""
    from taopt.ideals import is_wide, words

    extra = 8.0 * (words(n) - 1) if is_wide(n) else 0.0
    return (BEAM_BYTES_PER_SLOT + extra) * float(width) * float(n)


def dp_state_cap(n: int, max_memory_gb: float | None, wanted: int, reserve: float = 0.0) -> int:
    """The most states (at most ``wanted``) the DP may keep within the memory limit, less
    ``reserve`` bytes spent elsewhere (CP-SAT's worker beside the portfolio,
    :func:`cpsat_worker_bytes`). Counted at the full :data:`DP_BYTES_PER_STATE` (the
    largest measured bytes per state), so a stage that fills its cap stays within the
    limit."""
    from taopt.runtime import max_memory_gb as limit_gb

    room = limit_gb(max_memory_gb) * 1e9 - BASE_BYTES - reserve
    return int(max(1_000, min(wanted, room / dp_bytes(n, 1))))


#: Peak resident bytes of CP-SAT's worker process beside the portfolio (a Python with
#: OR-Tools imported; measured 157-165 MB from 9 to 80 nodes, ``ru_maxrss`` of the reaped
#: worker; 157-159 MB on the shipped files of 9-18 nodes, 165 MB on 27-49, 2026-11-27; 158-166
#: MB on 9-54 nodes, 2026-11-27 later: the largest, so the guard stays above the peak).
CPSAT_WORKER_BYTES = 166e6

#: Peak bytes of CP-SAT's worker per node pair (n^2) above :data:`CPSAT_WORKER_BYTES`
#: (fitted on the rbg-like stand-ins of 110-380 nodes beside the portfolio for 60 s: 157,
#: 159, 167, 231, 330 and 367 MB, the model within 1.17x of each; per usable arc or per
#: precedence pair the same runs do not line up: 380 nodes have fewer usable arcs than 340).
#: The worker grows with its search: 5 s runs alone (``bench_sop_memory.py --stages cpsat``,
#: polled) peaked at 102-161 MB on 9-380 nodes, the model within 1.17x of the SOP files'
#: and 2.3x above a 380-node chain's.
CPSAT_BYTES_PER_NODE_PAIR = 1_500.0


def cpsat_worker_bytes(n: int) -> float:
    """Estimated peak bytes of CP-SAT's worker process on ``n`` nodes (a process of its own:
    :data:`CPSAT_WORKER_BYTES` plus :data:`CPSAT_BYTES_PER_NODE_PAIR` per node pair)."""
    return CPSAT_WORKER_BYTES + CPSAT_BYTES_PER_NODE_PAIR * float(n) * float(n)


def milp_fits(
    problem: SopProblem,
    formulation: str,
    max_memory_gb: float | None,
    seconds: float | None = None,
) -> bool:
    """Whether the MILP's estimated memory is within the limit: the flow model's
    (:func:`sop_milp_bytes`), or the cut engine's over ``seconds`` (None: no limit) at the
    guard's :data:`CUT_GUARD_FACTOR` (:func:`cut_engine_bytes`)."""
    from taopt.runtime import max_memory_gb as limit_gb

    nonzeros = nonzero_count(problem.cost, problem.closure, problem.start, formulation)
    if formulation == "cuts":
        need = CUT_GUARD_FACTOR * cut_engine_bytes(nonzeros, seconds)
    else:
        need = sop_milp_bytes(nonzeros)
    return BASE_BYTES + need <= limit_gb(max_memory_gb) * 1e9


#: Peak bytes per usable arc of the cut engine's model, LP and cut rows
#: (:func:`taopt.models.sop_cuts.solve_sop_cuts` before its MIP rounds), above
#: :data:`SOP_MILP_BYTES` (:func:`cut_engine_bytes`; measured alone, 10 s, no MIP round:
#: 2.7 KB an arc on a 300-node random SOP of 73,600 arcs, 2.3 KB on a 340-node rbg-like of
#: 17,400, 3.7 KB on chains-120-3, 6 KB on esc-like-65; 2026-11-27,
#: ``/work/scratch/m34-mem/cutmem.py``, load 5).
CUT_LP_BYTES_PER_ARC = 2_500.0

#: Peak bytes of the cut engine's MIP rounds (HiGHS's search trees and cut pools) over a run
#: of :data:`CUT_RATE_SECONDS`, on :data:`CUT_MIP_ARCS` arcs or more (in proportion below):
#: measured alone on p43.1, prob.42, ry48p.1 and ft53.1 (1,600-2,700 arcs, 2-10 rounds):
#: 75-154 MB above the base at 10 s, 78-291 MB at 60 s (45-53 s used), 2026-11-27, load 1-3.
CUT_MIP_BYTES = 80e6

#: Arcs from which the cut engine's MIP rounds keep :data:`CUT_MIP_BYTES`.
CUT_MIP_ARCS = 1_500.0

#: The run length (seconds) at which the MIP rounds keep :data:`CUT_MIP_BYTES`.
CUT_RATE_SECONDS = 10.0

#: Exponent of the MIP rounds' peak in the run length (ry48p.1: 122 MB at 10 s, 210 MB at
#: 45 s; ft53.1: 149 and 291 MB).
CUT_EXPONENT = 0.4

#: The run length the cut engine's peak is estimated at without a time limit.
CUT_HORIZON = 600.0

#: The guard's factor on :func:`cut_engine_bytes` (the largest measured peak over the
#: estimate: ft53.1 at 60 s, 1.5).
CUT_GUARD_FACTOR = 1.6


def cut_engine_bytes(nonzeros: float, seconds: float | None) -> float:
    """Estimated peak bytes of the cut engine (beyond the base) on the arc model of
    ``nonzeros`` nonzeros (:func:`nonzero_count` with ``formulation="cuts"``, three per usable
    arc) run for ``seconds`` (None: :data:`CUT_HORIZON`): :data:`SOP_MILP_BYTES`, plus
    :data:`CUT_LP_BYTES_PER_ARC` an arc, plus the MIP rounds' :data:`CUT_MIP_BYTES` (times
    ``min(1, arcs / CUT_MIP_ARCS)``) grown as ``(seconds / CUT_RATE_SECONDS) **
    CUT_EXPONENT``; 0 for no model. Increasing in both."""
    if not nonzeros:
        return 0.0
    arcs = float(nonzeros) / 3.0
    span = CUT_HORIZON if seconds is None else max(float(seconds), 0.0)
    grown = (span / CUT_RATE_SECONDS) ** CUT_EXPONENT
    mip = CUT_MIP_BYTES * min(1.0, arcs / CUT_MIP_ARCS) * grown
    return SOP_MILP_BYTES + CUT_LP_BYTES_PER_ARC * arcs + mip


def root_gap(upper: float | None, lower: float) -> float:
    """The root gap ``(upper - lower) / upper`` of the best order known before the stages
    against the best bound then (1 without an order; 0 when closed)."""
    if upper is None or not np.isfinite(upper) or upper <= 0:
        return 1.0
    return float(min(1.0, max(0.0, (upper - lower) / upper)))


#: The probe's share of the time left when the first DP stage starts (:class:`LayerWatch`;
#: a few % of the limit: the estimate is made after it, before the rest of the stages; the
#: probe's layers are the stage's own, so it costs no time of its own).
PROBE_SHARE = 0.05

#: The most seconds the probe's layers get, whatever the limit.
PROBE_MAX_SECONDS = 3.0

#: The probe ends once its layers keep this many states (both directions): at 100,000 the
#: extrapolation of the shipped files' first stages is within 2x of the states they kept
#: (rbg048a 102,000 for 89,000; ry48p.4 294,000 for 422,000; ESC47 exact; rbg050c past its
#: fill), at 20,000 up to 10x above (ft53.4; ``/work/scratch/s35-mem/emu.py`` on the layers
#: of whole runs, 2026-11-27).
PROBE_STATES = 100_000


@dataclass(frozen=True)
class Probe:
    """What :class:`LayerWatch` measured: the kept states of each layer of the forward and
    the backward direction (layer 0 first, after pruning with the incumbent, the completion
    bound and the LP bound), whether a direction finished (every path pruned or completed,
    or the two met), the states kept over both and the seconds it took (setup included)."""

    forward: tuple[int, ...]
    backward: tuple[int, ...]
    finished: bool
    states: int
    seconds: float


class LayerWatch:
    """The memory probe: the first layers of the portfolio's first DP stage, watched
    (``solve_sop_dp(..., watch=...)``, :func:`taopt.models.sop_dp.solve_sop_dp`), so its
    states are the stage's own (none made twice, no extra time).

    From the first layer on, the kept states of each layer of both directions (after pruning
    with the incumbent, the completion bound and the LP bound) are read until ``seconds``
    pass, the states kept reach ``max_states``, a direction finishes or the two meet; then
    ``done(probe)`` is called once with the :class:`Probe`. :meth:`close` calls it with what
    was seen when the stage stopped first.
    """

    def __init__(
        self, seconds: float, done: Callable[[Probe], None], max_states: int = PROBE_STATES
    ) -> None:
        self.seconds = seconds
        self.max_states = max_states
        self.done = done
        self.began: float | None = None
        self.seen: Probe | None = None
        self.closed = False

    def __call__(self, runs: Sequence[Any]) -> None:
        if self.closed:
            return
        now = time.perf_counter()
        if self.began is None:
            self.began = now
        n = runs[0].n
        finished = any(r.finished for r in runs) or (
            len(runs) > 1 and sum(len(r.layers) - 1 for r in runs) >= n - 2
        )
        forward = tuple(len(layer[0]) for layer in runs[0].layers)
        backward = tuple(len(layer[0]) for layer in runs[1].layers) if len(runs) > 1 else (1,)
        kept = sum(r.kept for r in runs)
        self.seen = Probe(forward, backward, finished, kept, now - self.began)
        if finished or kept >= self.max_states or now - self.began >= self.seconds:
            self.close()

    def close(self) -> None:
        """Hand what was seen to ``done`` (once; nothing when no layer was seen)."""
        if not self.closed and self.seen is not None:
            self.closed = True
            self.done(self.seen)


#: Growth damping of the probe's extrapolation (:func:`probe_extrapolation`): the log of a
#: direction's layer-to-layer growth shrinks by this factor a layer, so a layer ends at
#: most ``g ** (d / (1 - d))`` times the last measured one (fitted, :func:`predicted_peak`).
PROBE_DAMPING = 0.8

#: Layers over which the probe's last growth is measured (a geometric mean).
PROBE_GROWTH_LAYERS = 2


def _growth(sizes: tuple[int, ...]) -> float:
    """The last layers' growth of one direction (:data:`PROBE_GROWTH_LAYERS`, geometric)."""
    span = min(PROBE_GROWTH_LAYERS, len(sizes) - 1)
    if span < 1 or sizes[-1] <= 0:
        return 0.0
    return float((sizes[-1] / max(sizes[-1 - span], 1)) ** (1.0 / span))


def probe_extrapolation(n: int, probe: Probe) -> float:
    """The states a DP stage on ``n`` nodes keeps until its directions meet, extrapolated
    from ``probe`` as the DP goes on (:func:`taopt.models.sop_dp.solve_sop_dp`): the layers
    left (``n - 2`` less those measured) are added one at a time to the direction whose last
    layer is smaller, each grown from that direction's last layer by its last growth ``g``
    (:func:`_growth`), the log of the growth shrunk by :data:`PROBE_DAMPING` at each of its
    layers; the total is the states measured plus the layers added. Never below the states
    measured; exactly them when the probe finished or a direction kept nothing."""
    measured = float(probe.states)
    if probe.finished:
        return measured
    left = max(0, n - 2 - (len(probe.forward) - 1) - (len(probe.backward) - 1))
    sides = (probe.forward, probe.backward)
    growth = [_growth(sizes) for sizes in sides]
    if min(growth) <= 0.0:  # a direction kept nothing: the DP ends
        return measured
    logs = [float(np.log(g)) for g in growth]
    size = [float(sizes[-1]) for sizes in sides]
    grown = [0, 0]
    future = 0.0
    for _ in range(left):
        d = 0 if size[0] <= size[1] else 1
        size[d] = min(size[d] * float(np.exp(logs[d] * PROBE_DAMPING ** grown[d])), 1e15)
        grown[d] += 1
        future += size[d]
    return measured + future


#: The share of the cut engine's time (when it goes first) a DP stage after it is expected to
#: fill (:func:`predicted_peak`, path "cuts"; :func:`taopt.models.sop_stages.use_the_rest`):
#: the cut engine's MIP rounds stop at 43-53 s of 60 s, and p43.1's DP after them peaked at
#: 320-701 MB (2026-11-27, 60 s, CP-SAT off, load 6-9).
CUTS_REST_SHARE = 0.25

#: Share of the states its ideals allow (``2 n`` times the ideals, counted) a DP stage is
#: expected to keep after a probe (:func:`probe_states`; fitted: p43.4, ry48p.4 and ft53.4,
#: which close, kept 4.5 %, 6.3 % and 3.0 %; their probes extrapolate 2-6 times that).
PROBE_ALLOWED_SHARE = 0.04

#: States a DP stage that fills its states keeps per second of its share, up to 64 nodes
#: (times ``(64 / n) ** FILL_WIDE_EXPONENT`` above; :func:`fill_states`): fitted on the runs
#: that stop on their time (prob.42, ry48p.1, ft53.1, p43.1, rbg050c at 10 and 60 s, CP-SAT
#: off).
FILL_STATES_PER_SECOND = 31_000.0

#: How the fill rate falls beyond 64 nodes: ``(64 / n) ** FILL_WIDE_EXPONENT``. It was
#: ``64 / n`` while the completion bound searched every node's arcs per ideal; with the
#: band's bound (``taopt.models.sop_dp._Bound._per_ideal_band``) a state's work no
#: longer grows with ``n`` as fast. Measured, the DP alone for 15 s without an incumbent,
#: main then the branch in the same minutes (load 8.6): rbg-atsp-150-0.6 4,939 -> 42,119
#: states a second, ESC47 23,879 -> 68,426; 150 nodes against 49: 0.21 before, 0.62 after,
#: ``(49 / 150) ** 0.43``. With ``64 / n`` the estimate of rbg-atsp-150-0.6 at 60 s was
#: 593 MB against a 1,340 MB peak (2.26).
FILL_WIDE_EXPONENT = 0.5

#: The share of :data:`FILL_STATES_PER_SECOND` left to the DP when CP-SAT's worker runs
#: beside it on this 2-core machine (fitted: the same runs with CP-SAT beside).
FILL_BESIDE_SHARE = 0.7


#: The guard counts a filling DP stage at the fastest fill measured, not the fitted one
#: (:data:`FILL_STATES_PER_SECOND`): rbg050c kept 79,000 states a second in a 25 s stage
#: (load about 5), and ry48p.1 526,170 states in a 10 s run (load 1.7, CP-SAT beside), where
#: the guard at the fitted rate counted 310,000 and the parent's peak passed it (603 MB
#: against 590 MB, 2026-11-27, ``bench_sop.py --resources 10``).
GUARD_FILL_FACTOR = 80_000.0 / FILL_STATES_PER_SECOND


def fill_states(n: int, seconds: float | None, beside: bool, share: float = 1.0) -> float:
    """The states a DP stage of ``seconds`` (None: no limit, infinite) on ``n`` nodes keeps
    when its bound prunes too little to close: :data:`FILL_STATES_PER_SECOND` a second
    (times ``min(1, 64 / n) ** FILL_WIDE_EXPONENT``, times :data:`FILL_BESIDE_SHARE` when CP-SAT runs ``beside``),
    divided by ``share`` (:func:`dp_state_share`: a state of fewer extensions costs less time
    as it costs fewer bytes;
    rbg050c, share 0.6, kept 1.98 million states in a 25 s stage, 79,000 a second);
    increasing in ``seconds``."""
    if seconds is None:
        return float("inf")
    wide = min(1.0, 64.0 / max(n, 1)) ** FILL_WIDE_EXPONENT
    rate = FILL_STATES_PER_SECOND * wide / max(share, 1e-9)
    return rate * max(float(seconds), 0.0) * (FILL_BESIDE_SHARE if beside else 1.0)


def expected_fill(n: int, seconds: float | None, beside: bool, share: float = 1.0) -> float:
    """The states the reported estimate expects a filling DP stage to keep:
    :func:`fill_states` divided by the words of a mask beyond 64 nodes
    (:func:`taopt.ideals.words`), as the DP's own clock counts a state's bound work per node
    and word. Measured at 60 s under load (2026-11-27, ``--resources 60 --unseen --load``): the
    two-word stand-ins of 65-80 nodes (esc-like, ftv70) kept 43,000-261,000 states where
    :func:`fill_states` expected 500,000-690,000, and their estimates were 1.5-2x their
    peaks (peak / estimate 0.50-0.65); recomputed on the recorded rows with the words counted,
    0.67-0.83, the other rows at 10 and 60 s unchanged or closer (0.62-1.07 in all). The
    guard keeps :func:`fill_states` itself."""
    from taopt.ideals import is_wide, words

    fill = fill_states(n, seconds, beside, share)
    return fill / words(n) if is_wide(n) else fill


def probe_states(
    n: int,
    probe: Probe,
    seconds: float | None,
    cap: float,
    allowed: float | None,
    beside: bool,
    share: float = 1.0,
) -> float:
    """The DP states the reported estimate expects of a stage of ``seconds`` after ``probe``:
    the smaller of its extrapolation (:func:`probe_extrapolation`), the states it can fill in
    its time (:func:`expected_fill`) and :data:`PROBE_ALLOWED_SHARE` of the states the ideals
    allow (``allowed``, None: not counted), never below the states the probe measured, and
    at most its ``cap`` and ``allowed``."""
    states = min(probe_extrapolation(n, probe), expected_fill(n, seconds, beside, share))
    if allowed is not None:
        states = min(states, PROBE_ALLOWED_SHARE * float(allowed))
    states = min(max(states, float(probe.states)), float(cap))
    return states if allowed is None else min(states, float(allowed))


#: The reported estimate's DP states without a probe (:func:`predicted_states`: the estimate
#: first recorded, kept only when the first DP stage made no layer) as a share of
#: :func:`dp_states_in`'s rate at :data:`DP_RATE_SECONDS` (fitted before the probe, 2026-11-27).
PREDICTED_RATE_SHARE = 0.5

#: Exponent of the reported estimate's DP states in the stage's length (fitted; below
#: :data:`DP_RATE_EXPONENT`: the longer runs include the instances that close early).
PREDICTED_EXPONENT = 0.6

#: Share of the states its ideals allow (``2 n`` times the ideals) a DP stage is expected to
#: keep when they were counted (fitted: p43.4, ry48p.4, ft53.4 kept 3-8 % of them).
ALLOWED_SHARE = 0.1


def predicted_states(n: int, seconds: float | None, cap: float, allowed: float | None) -> float:
    """The DP states the reported estimate expects of a stage of ``seconds`` (None: no
    limit) on ``n`` nodes: :data:`PREDICTED_RATE_SHARE` of :func:`dp_states_per_second`
    over :data:`DP_RATE_SECONDS`, grown as ``(seconds / DP_RATE_SECONDS) **
    PREDICTED_EXPONENT``, at most the guard's (:data:`GUARD_STATE_FACTOR` times
    :func:`dp_states_in`), the stage's ``cap`` and :data:`ALLOWED_SHARE` of the states the
    ideals allow (``allowed``, None when the count was cut short); increasing in each."""
    states = float(cap)
    if seconds is not None:
        span = max(float(seconds), 0.0) / DP_RATE_SECONDS
        rate = PREDICTED_RATE_SHARE * dp_states_per_second(n) * DP_RATE_SECONDS
        states = min(states, rate * span**PREDICTED_EXPONENT)
        states = min(states, GUARD_STATE_FACTOR * dp_states_in(n, float(seconds)))
    if allowed is not None:
        states = min(states, ALLOWED_SHARE * float(allowed))
    return states


def predicted_peak(
    problem: SopProblem,
    path: str,
    seconds: float | None,
    cap: float,
    allowed: float | None,
    nonzeros: float,
    cut_seconds: float | None = 0.0,
    probe: Probe | None = None,
    beside: bool = False,
) -> tuple[float, dict[str, Any]]:
    """The reported memory estimate (``info["memory_estimate"]``) and its parts, predicted
    before the portfolio's later stages run.

    ``path`` is the rule's choice: "dp" (the DP alone on counted ideals), "root+dp" (the
    root stage, then the DP stages, then the cut engine) or "cuts" (the cut engine first);
    ``seconds`` the first DP stage's time, ``cap`` its state cap, ``allowed`` the states the
    ideals allow (None: too many to count), ``nonzeros`` the root stage's cut model
    (:func:`nonzero_count`, 0 for none), ``cut_seconds`` the time the cut engine may get
    (0: it does not run), ``probe`` what the first DP stage's first layers measured
    (:class:`LayerWatch`; None: no layer yet) and ``beside`` whether CP-SAT's worker runs
    beside. The peak is the base plus the larger of the DP phase (the DP's states at
    :func:`dp_bytes` scaled by :func:`dp_state_share` to the power
    :data:`DP_SHARE_EXPONENT`, beside the root stage's model) and the
    cut engine's phase (:func:`cut_engine_bytes`).

    The DP's states, with a probe (:func:`probe_states`): what its layers measured,
    extrapolated to the middle by their damped growth (:func:`probe_extrapolation`), at most
    what a stage that fills its states keeps in its time (:func:`expected_fill`); the two
    kinds of instance the inputs known before the stages do not tell apart (ESC25 and
    ry48p.1, root gaps 0.12 and 0.11) grow 1.1-2 and 15-36 times a layer in the probe.
    Without one (the estimate first recorded, replaced by the probe's): the old fit,
    :func:`predicted_states`. Measured and fitted with ``python benchmarks/bench_sop.py
    --resources T --cpsat both --record rows.jsonl`` at 10 and 60 s on the shipped files and
    p43.1, prob.42, ry48p.1, ft53.1 (docs/benchmarks.md, "SOP memory: a probe of the DP's
    first layers"; 2026-11-27, this 2-core machine, load 3-6 from other sessions).
    """
    share = dp_state_share(problem)
    if path == "cuts":  # a DP stage after the cut engine (use_the_rest), filling its states
        rest = None if cut_seconds is None else CUTS_REST_SHARE * cut_seconds
        states = min(expected_fill(problem.n, rest, beside, share), float(cap))
    elif probe is not None:
        states = probe_states(problem.n, probe, seconds, cap, allowed, beside, share)
    else:
        states = predicted_states(problem.n, seconds, cap, allowed)
    dp = dp_bytes(problem.n, states) * share**DP_SHARE_EXPONENT
    held = cut_engine_bytes(nonzeros, 0.0)
    cut = cut_engine_bytes(nonzeros, cut_seconds) if cut_seconds != 0 else 0.0
    peak = BASE_BYTES + max(dp + held, cut)
    features: dict[str, Any] = {
        "path": path,
        "seconds": seconds,
        "cap": cap,
        "allowed": allowed,
        "nonzeros": nonzeros,
        "cut_seconds": cut_seconds,
        "n": problem.n,
        "share": dp_state_share(problem),
        "closure": closure_share(problem),
        "states": states,
        "dp": dp,
        "cut": cut,
        "beside": beside,
    }
    if probe is not None:
        features["probe"] = {
            "forward": list(probe.forward),
            "backward": list(probe.backward),
            "finished": probe.finished,
            "states": probe.states,
            "seconds": probe.seconds,
            "extrapolated": probe_extrapolation(problem.n, probe),
            "fill": expected_fill(problem.n, seconds, beside, share),
        }
    return peak, features


#: The ideal count the guard (``_footprint``) just made, by problem identity: ``(problem,
#: cap, (count, capped), seconds)``, taken (once) by the portfolio run that follows it, so a
#: ``taopt.solve`` call counts once (up to :data:`COUNT_SHARE` of its limit, on its clock).
_COUNTED: dict[int, tuple[SopProblem, int, tuple[int, bool], float]] = {}


def _ideal_count(
    problem: SopProblem, cap: int, deadline: Deadline | None
) -> tuple[int, bool, float]:
    """``(ideals, capped, seconds)``: the order ideals of ``problem`` counted up to ``cap``
    (:func:`taopt.models.sop_dp.count_ideals`) and the seconds the count took. The guard's
    count (:func:`_footprint`, run by :func:`taopt.solve` just before) is taken when it was
    made for this problem and cap, so a call counts once; else the count is made now under
    ``deadline``."""
    from taopt.models.sop_dp import count_ideals

    handed = _COUNTED.pop(id(problem), None)
    if handed is not None and handed[0] is problem and handed[1] == cap:
        return handed[2][0], handed[2][1], handed[3]
    began = time.perf_counter()
    ideals, capped = count_ideals(problem, cap, deadline)
    return ideals, capped, time.perf_counter() - began


@register_footprint(SopProblem, "exact")
def _footprint(problem: SopProblem, options: dict) -> tuple[float, str]:
    """The guard: a safe upper estimate of the portfolio's peak before the run (the reported
    estimate, :func:`predicted_peak`, is never above it): the larger of its DP stages (their
    state caps, the states the ideals allow, :data:`GUARD_STATE_FACTOR` times the states it
    can make in the whole limit) beside the root stage's cut model, and the MILP when it fits
    the limit (the cut engine's MIP rounds over the whole limit, :func:`cut_engine_bytes`
    at :data:`CUT_GUARD_FACTOR`);
    above the limit the stage that fits (:func:`taopt.models.sop_stages.memory_plan`: the
    DP with a smaller cap, the beam, the bounds alone), so the estimate fits too (never a
    refusal for size alone). CP-SAT's worker (:func:`cpsat_worker_bytes`) is counted when it
    will run beside (the rule of :func:`solve_sop_problem`), and the stages' room is the limit less it."""
    from taopt.models.sop_dp import IDEAL_CAP, count_ideals
    from taopt.models.sop_stages import beam_width_cap, memory_plan
    from taopt.runtime import max_memory_gb as limit_gb

    formulation = options.get("formulation", PORTFOLIO_FORMULATION)
    given = options.get("max_memory_gb")
    seconds = options.get("time_limit")
    name = f" {problem.name}" if problem.name else ""
    try:  # CP-SAT's worker beside the stages: its own process, counted, the stages' room less
        peer, _ = _cpsat_peer(
            problem, options.get("cpsat"), options.get("engine", "auto"), seconds, given
        )
    except SolverError:  # cpsat=True without OR-Tools: the call itself will say so
        peer = None
    reserve = 0.0 if peer is None else cpsat_worker_bytes(problem.n)
    limit = _stage_limit(given, reserve)
    plan = memory_plan(problem.n, limit)
    if plan != "dp" and options.get("engine") != "milp":
        width = beam_width_cap(problem.n, limit) if plan == "beam" else 0
        total = BASE_BYTES + beam_bytes(problem.n, width)
        # a limit below the process's own base: the stage adds nothing above what is spent
        # already, so it is not refused (the answer is the cheap bounds and the warm start)
        total = min(total + reserve, limit_gb(given) * 1e9)
        return total, f"the SOP portfolio on{name} ({problem.n} nodes, degraded to the {plan})"
    counting = None if seconds is None else Deadline(COUNT_SHARE * seconds)
    cap = options.get("ideal_cap") or IDEAL_CAP
    began = time.perf_counter()
    count, capped = count_ideals(problem, cap, counting)
    # handed to the run that follows this guard (taopt.solve's), which would count again
    _COUNTED.clear()
    _COUNTED[id(problem)] = (problem, int(cap), (count, capped), time.perf_counter() - began)
    if reserve and options.get("cpsat") is None and _dp_alone(capped):  # CP-SAT will not run
        reserve, limit = 0.0, given
    wanted = options.get("max_states", PORTFOLIO_MAX_STATES)
    if options.get("engine") != "dp":  # engine="dp" runs one stage of max_states
        wanted = max(wanted, SECOND_STAGE_MAX_STATES)
    if seconds is not None:  # a DP stage keeps at most about the states it can make in its
        # time (GUARD_STATE_FACTOR times the expected, the whole limit: the stages after the
        # first, use_the_rest's included, may run up to the limit); the caps bound it anyway
        # (at least the states the reported estimate lets a filling stage keep in the limit)
        wanted = int(
            max(
                GUARD_STATE_FACTOR * dp_states_in(problem.n, seconds),
                GUARD_FILL_FACTOR * fill_states(problem.n, seconds, False),
            )
        )
    states = dp_state_cap(
        problem.n, limit, wanted if capped else min(wanted, 2 * problem.n * count)
    )
    # at the full bytes a state (not dp_state_share's): rbg050c's second DP stage peaked at
    # 915 MB at 60 s without CP-SAT, above a guard scaled by its share (804 MB)
    total = BASE_BYTES + dp_bytes(problem.n, states)
    what = f"the SOP portfolio on{name} ({problem.n} nodes, DP up to {states:,} states"
    columns = column_count(problem.cost, problem.closure, problem.start, formulation)
    # the MILP runs only after capped DP stages, and takes its memory when it is compiled for
    # HiGHS: only when its build and its compile (COMPILE_PER_BUILD times a build of about a
    # third of SECONDS_PER_COLUMN a column) fit the time it gets then (solve_sop's rule)
    compiled = (
        seconds is None or MILP_SAFETY * compile_seconds(columns) <= MILP_TIME_SHARE * seconds
    )
    built = seconds is None or columns * SECONDS_PER_COLUMN <= MILP_TIME_SHARE * seconds
    if formulation == "cuts":  # array-built, interruptible: it runs whenever it fits
        built = compiled = True
    if options.get("engine") == "milp" or (
        capped
        and built
        and options.get("engine") != "dp"
        and milp_fits(problem, formulation, limit, seconds)
    ):
        nonzeros = nonzero_count(problem.cost, problem.closure, problem.start, formulation)
        if formulation == "cuts":  # its MIP rounds grow with their time (the whole limit)
            model = CUT_GUARD_FACTOR * cut_engine_bytes(nonzeros, seconds)
            if options.get("engine", "auto") == "auto":
                # the root stage's model (no MIP round yet) stays beside the DP stages
                total += cut_engine_bytes(nonzeros, 0.0)
        else:
            model = sop_milp_bytes(nonzeros, compiled)
        total = max(total, BASE_BYTES + model)
        what += f", {formulation} model of {columns:,} columns"
    if reserve:
        what += f", CP-SAT's worker {reserve / 1e6:,.0f} MB"
    return min(total + reserve, limit_gb(given) * 1e9), what + ")"


def assignment_bound(cost: np.ndarray, closure: nx.DiGraph, start: int, end: int) -> float:
    """Valid lower bound: the assignment relaxation on the usable arcs (milliseconds).

    Every node but ``end`` gets one successor and every node but ``start`` one
    predecessor along a usable arc (:func:`usable_arcs`), subtours allowed: the degree rows
    of the model without connectivity, solved exactly by
    :func:`scipy.optimize.linear_sum_assignment`. 1,199 on ESC47 (optimum 1,288) where the
    arborescence bound is 0. Returns 0 when the relaxation has no finite assignment.
    """
    tails, heads = usable_arcs(cost, closure)
    n = cost.shape[0]
    weights = np.full((n, n), np.inf)
    weights[tails, heads] = cost[tails, heads]
    rows = np.array([v for v in range(n) if v != end])
    cols = np.array([v for v in range(n) if v != start])
    sub = weights[np.ix_(rows, cols)]
    finite = np.isfinite(sub)
    if not finite.any(axis=1).all() or not finite.any(axis=0).all():
        return 0.0
    big = 1.0 + 2.0 * n * float(np.abs(sub[finite]).max(initial=0.0))
    chosen_rows, chosen_cols = linear_sum_assignment(np.where(finite, sub, big))
    if not finite[chosen_rows, chosen_cols].all():
        return 0.0  # no assignment on usable arcs: claim nothing here
    return float(sub[chosen_rows, chosen_cols].sum())


#: The cheap bound of the last few problems (by identity; the problem is kept so its id is
#: not reused): a stopped stage needs it after its deadline, when seconds of Edmonds on 380
#: nodes under load would overrun the limit, so the portfolio computes it once, first.
_CHEAP: dict[int, tuple[SopProblem, float]] = {}


def _cheap_bound(problem: SopProblem) -> float:
    """The larger of the assignment and arborescence bounds (both valid, both fast),
    remembered for the last few problems."""
    known = _CHEAP.get(id(problem))
    if known is not None and known[0] is problem:
        return known[1]
    value = max(
        assignment_bound(problem.cost, problem.closure, problem.start, problem.end),
        sop_arborescence_bound(problem),
    )
    if len(_CHEAP) >= 4:
        _CHEAP.pop(next(iter(_CHEAP)))
    _CHEAP[id(problem)] = (problem, value)
    return value


def proof_record(found: Solution, gap: float, began: float, *keys: str) -> dict[str, Any]:
    """The proof stage's ``info["proof"]``: the gap it started from, the DP's status, bound
    and seconds since ``began``, and the DP's ``info`` entries ``keys``."""
    return {
        "gap": gap,
        "status": str(found.status),
        "bound": found.bound,
        "seconds": time.perf_counter() - began,
        **{key: found.info.get(key) for key in keys},
    }


def _known_order(
    cost: np.ndarray, closure: nx.DiGraph, start: int, end: int, incumbent: Any
) -> tuple[float, list[int]] | None:
    """``(cost, order)`` of a feasible incumbent order, or None (an infeasible one is ignored)."""
    given = incumbent.order if isinstance(incumbent, Solution) else incumbent
    if given is None:  # no incumbent, or a Solution without an order
        return None
    order = [int(v) for v in given]
    n = cost.shape[0]
    if sorted(order) != list(range(n)) or order[0] != start or order[-1] != end:
        return None
    where = np.empty(n, dtype=np.int64)
    where[order] = np.arange(n)
    if any(where[r] > where[j] for r, j in closure.edges()):
        return None
    value = path_cost(cost, order)
    return (value, order) if np.isfinite(value) else None


def _stopped(
    problem: SopProblem,
    known: tuple[float, list[int]] | None,
    bound: float | None,
    began: float,
    formulation: str,
    info: dict,
) -> Solution:
    """Status "time_limit": the incumbent (or no plan, objective inf) and the best valid
    bound of HiGHS's, the assignment bound (:func:`assignment_bound`) and the arborescence
    bound (:func:`sop_arborescence_bound`)."""
    tree = _cheap_bound(problem)
    bound = tree if bound is None or not np.isfinite(bound) else max(bound, tree)
    return finish(
        problem,
        None if known is None else Order(known[1]),
        method=f"exact-sop-{formulation}",
        stop="time_limit",
        bound=bound,
        runtime=time.perf_counter() - began,
        info=info,
    )


def _unreachable(cost: np.ndarray, closure: nx.DiGraph, start: int, end: int) -> str | None:
    """Why no path can exist when a node cannot be entered or left on a usable arc (or no
    usable path runs from start through it to end); None when this cheap test finds none."""
    tails, heads = usable_arcs(cost, closure)
    graph = nx.DiGraph()
    graph.add_nodes_from(range(cost.shape[0]))
    graph.add_edges_from(zip(tails.tolist(), heads.tolist(), strict=True))
    reach = nx.descendants(graph, start) | {start}
    back = nx.ancestors(graph, end) | {end}
    for v in range(cost.shape[0]):
        if v not in reach:
            return f"node {v} cannot be reached from start {start} by any usable arc"
        if v not in back:
            return f"end {end} cannot be reached from node {v} by any usable arc"
    return None


def _infeasible(began: float, formulation: str, proof: str) -> Solution:
    """Status "infeasible" (no path exists), with the reason as ``info["proof"]``."""
    return finish(
        None,  # no payload to score
        None,
        method=f"exact-sop-{formulation}",
        stop="infeasible",
        bound=np.inf,
        runtime=time.perf_counter() - began,
        info={"proof": proof},
    )


def solve_sop(
    cost: Any,
    precedences: Any,
    start: int,
    end: int,
    time_limit: float | None = None,
    formulation: str = "flow",
    mip_gap: float = 1e-9,
    verbose: bool = False,
    incumbent: Any = None,
    problem: SopProblem | None = None,
) -> Solution:
    """Exact sequential ordering: cheapest precedence-respecting Hamiltonian path.

    Parameters
    ----------
    cost : (n, n) array_like
        Arc costs (asymmetric allowed; ``inf`` forbids an arc; diagonal ignored).
    precedences : iterable of (r, j)
        r must be visited before j (as (5.7)).
    start, end : int
        Path endpoints.
    time_limit : float, optional
        Wall-clock seconds for everything (building, compiling, HiGHS, decoding). On the
        limit the best order known (HiGHS's or ``incumbent``) is returned with status
        "time_limit" and the best proven bound (HiGHS's or the arborescence bound); with
        no order, objective ``inf`` and no order. When the model could not be built in
        time (estimated :data:`SECONDS_PER_COLUMN` per column), it is not built
        (``info["model"] == "not built"``).
    formulation : {"flow", "mtz"}
        See the module docstring; "flow" is the stronger one.
    mip_gap : float
        HiGHS relative gap tolerance (default 1e-9). The status is "optimal"
        only when the final gap is at most 1e-6
        (:data:`taopt.models.highs.OPTIMALITY_TOLERANCE`); a run stopped by a
        looser ``mip_gap`` is "feasible" with its proven bound
        (``info["stopped_by"] == "mip_gap"``).
    verbose : bool
        HiGHS log.
    incumbent : Order, list of int or Solution, optional
        A feasible order (e.g. from SMMA), returned when HiGHS finds nothing better in
        time; an infeasible one is ignored.
    problem : SopProblem, optional
        The problem these arrays are (its scorer scores the returned order, once); built
        from the arrays when needed and not given.

    Returns
    -------
    Solution
        ``order`` (start ... end), ``objective`` = its path cost recomputed
        from ``cost`` (never the solver's number; checked against the model's
        value and every precedence), ``status`` "optimal", "feasible" (loose
        ``mip_gap``) or "time_limit", ``bound`` the proven lower bound,
        ``runtime``.

    Raises
    ------
    InstanceError
        Bad data (see :func:`check_sop`). When no feasible path exists the status is
        "infeasible" (objective ``inf``, ``info["proof"]`` says why), not an error.
    SolverError
        HiGHS failed, or the decoded path breaks a precedence or does not cost the
        model's value (a time limit is never an error).

    Example
    -------
    >>> import numpy as np
    >>> cost = np.array([[0, 1, 5, 9], [9, 0, 1, 5], [1, 9, 0, 1], [9, 9, 9, 0.0]])
    >>> solve_sop(cost, [(2, 1)], 0, 3).order
    [0, 2, 1, 3]
    """
    began = time.perf_counter()
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    deadline = Deadline(time_limit)
    checked, closure = check_sop(cost, precedences, start, end)
    unreachable = _unreachable(checked, closure, start, end)
    if unreachable is not None:
        return _infeasible(began, formulation, unreachable)
    known = _known_order(checked, closure, start, end, incumbent)
    if deadline.limited and problem is None:
        problem = SopProblem(checked, tuple(map(tuple, precedences)), start, end)
    left = deadline.remaining()  # None without a limit
    if left is not None:
        assert problem is not None  # built above under a limit
        columns = column_count(checked, closure, start, formulation)
        estimate = columns * SECONDS_PER_COLUMN
        if estimate > left - MARGIN:  # cannot build and compile in time
            info = {"model": "not built", "columns": columns, "build_estimate": estimate}
            return _stopped(problem, known, None, began, formulation, info)
    building = time.perf_counter()
    try:
        model = build(cost, precedences, start, end, formulation, deadline=deadline)
    except BuildStopped:
        assert problem is not None  # built above under a limit
        return _stopped(problem, known, None, began, formulation, {"model": "not built"})
    built_in = time.perf_counter() - building
    if deadline.limited:
        assert problem is not None  # built above under a limit
        run, values, not_run = _solve_limited(model, deadline, built_in, mip_gap, verbose)
        if not_run is not None:
            return _stopped(problem, known, None, began, formulation, not_run)
    else:
        run, values = solve_highs(model.problem, mip_rel_gap=float(mip_gap), verbose=verbose), None
    if run.solver_status == "solver_error":
        raise SolverError(f"HiGHS failed on the SOP model: {run.message}")
    if run.status == INFEASIBLE:
        return _infeasible(began, formulation, "HiGHS proved the model infeasible")
    if run.status not in (OPTIMAL, FEASIBLE, TIME_LIMIT):
        raise SolverError(f"HiGHS returned status {run.solver_status!r} on the SOP model")
    if not run.has_point or (
        run.status == TIME_LIMIT
        and known is not None
        and run.objective is not None
        and known[0] < run.objective
    ):
        if run.status != TIME_LIMIT:
            raise SolverError(f"HiGHS returned status {run.solver_status!r} without a path")
        if problem is None:
            problem = SopProblem(checked, tuple(map(tuple, precedences)), start, end)
        info = {"model": "solved", "solver_status": run.solver_status, "nodes": run.nodes}
        return _stopped(problem, known, run.bound, began, formulation, info)
    order = decode(model, values)
    assert run.objective is not None  # a point was found (has_point)
    _check_path(model, order, precedences, run.objective)  # the path and its value agree
    bound = run.bound
    if run.status == TIME_LIMIT:  # HiGHS may stop before its root bound beats the tree's
        if problem is None:
            problem = SopProblem(checked, tuple(map(tuple, precedences)), start, end)
        tree = _cheap_bound(problem)
        bound = tree if bound is None else max(bound, tree)
    if problem is None:
        problem = SopProblem(checked, tuple(map(tuple, precedences)), start, end)
    return finish(  # the one status rule: optimal only when proven within 1e-6
        problem,
        Order(order),
        method=f"exact-sop-{formulation}",
        stop=run.stopped_by,
        bound=bound,
        runtime=time.perf_counter() - began,
        info={
            "arcs": len(model.tails),
            "variables": sum(v.size for v in model.problem.variables()),
            "solver_objective": run.objective,
            "mip_gap": run.mip_gap,
            "nodes": run.nodes,
            "solver_status": run.solver_status,
        },
    )


def _solve_limited(
    model: Any, deadline: Deadline, built_in: float, mip_gap: float, verbose: bool
) -> tuple[Any, Any, dict[str, Any] | None]:
    """Compile ``model`` apart from solving (:class:`HighsModel`), so that HiGHS gets exactly
    the time left, and solve it. Returns (HiGHS's run, the arc values or None, None), or
    (None, None, info) when the time left cannot pay for the compile or the solve."""
    left = deadline.remaining()
    assert left is not None  # limited
    columns = sum(v.size for v in model.problem.variables())
    compile_estimate = max(
        COMPILE_SHARE * columns * SECONDS_PER_COLUMN, COMPILE_PER_BUILD * built_in
    )
    if left - compile_estimate - MARGIN <= 0:
        return None, None, {"model": "built, not compiled", "columns": columns}
    compiled = HighsModel(model.problem, verbose=verbose)
    if deadline.expired(MARGIN):
        return None, None, {"model": "compiled, not solved", "columns": columns}
    left = deadline.remaining()
    assert left is not None  # limited
    run = compiled.solve(time_limit=left - MARGIN, mip_rel_gap=float(mip_gap))
    values = compiled.values(model.arc_use) if run.has_point else None
    return run, values, None


#: States the DP may keep in all before the portfolio hands over to the MILP (rbg048a: 1.8
#: million states kept peaked at 3.2 GB with the work arrays of the largest layer).
PORTFOLIO_MAX_STATES = 2_000_000

#: Share of a time limit the portfolio gives the DP when the ideals are too many to count
#: (the MILP gets the rest).
DP_SHARE = 0.5

#: States the second DP stage may keep (both directions' bounds on both price sets:
#: rbg050c closed with 2.9 million, 0.7 GB).
SECOND_STAGE_MAX_STATES = 4_000_000

#: Share of the time left after the first DP stage that the second stage gets (the MILP
#: gets the rest).
SECOND_STAGE_SHARE = 0.75

PORTFOLIO_ENGINES = ("auto", "dp", "milp")

#: Share of the time limit the portfolio (and its memory estimate) may spend counting ideals
#: up to :data:`taopt.models.sop_dp.IDEAL_CAP`; a count cut short is "too many ideals" (the
#: DP gets :data:`DP_SHARE`). ESC47 under load at a 1 s limit spent the whole limit counting
#: to 200,000 without it.
COUNT_SHARE = 0.1

#: The portfolio's MILP stage: ``"cuts"``, the arc model with precedence path cuts
#: (:func:`taopt.models.sop_cuts.solve_sop_cuts`; root bound 28,098 on p43.1 against the flow
#: model's 2,720, optimum 28,140), or ``"flow"``/``"mtz"`` (:func:`solve_sop`). With
#: ``"cuts"`` the second DP stage is skipped when the first left a wide gap
#: (:data:`CUTS_SECOND_STAGE_GAP`): the cut engine gets the time after the first.
PORTFOLIO_FORMULATION = "cuts"

#: ``info["model"]`` of a MILP run that stopped before HiGHS ran (the portfolio then gives
#: the time left to the DP).
STOPPED_EARLY = ("not built", "built, not compiled", "compiled, not solved")


def _combine(first: Solution, second: Solution) -> Solution:
    """Two runs on one problem: ``second`` when it finished; else the better order with the
    larger of the two proven bounds (status by the one rule)."""
    if second.status != TIME_LIMIT:
        return second
    best = second if second.objective <= first.objective else first
    bound = min(max(first.bound or 0.0, second.bound or 0.0), best.objective)
    status = TIME_LIMIT
    if np.isfinite(best.objective):
        status, _ = decide("time_limit", best.objective, bound)
    return best.replace(bound=bound, status=status)


def _raised(result: Solution, bound: float) -> Solution:
    """``result`` with its bound raised to ``bound`` (a bound proven elsewhere; never above
    its objective), the status by the one rule."""
    if result.bound is not None and result.bound >= bound:
        return result
    bound = min(bound, result.objective)
    status = result.status
    if np.isfinite(result.objective):
        status, _ = decide("time_limit", result.objective, bound)
    return result.replace(bound=bound, status=status)


#: With the cut engine, the second DP stage runs only when the first one's relative gap is
#: at most this (rbg050c: 468 / 462 after the first stage, closed by the second; p43.1:
#: 28,845 / 2,720, prob.42: 276 / 182, where the DP's bound is far and the cuts' is close).
CUTS_SECOND_STAGE_GAP = 0.05


#: Share of the time limit the portfolio's root stage may spend on the cut engine's root cut
#: loop (:meth:`taopt.models.sop_cuts.SopCutModel.root`) before the DP when the ideals are
#: too many to count: its LP duals prune the DP (``lagrange=`` of
#: :func:`taopt.models.sop_dp.solve_sop_dp`), its rounded point may improve the warm start,
#: and the cut engine goes on from its rows later. Root loops measured 1.0-3.0 s on prob.42,
#: p43.1, ry48p.1, ft53.1 and ESC47 at load 5, 11 s on rbg050c.
ROOT_SHARE = 0.1

#: Share of the time limit the position-window bound's subgradient
#: (:func:`taopt.models.sop_window.window_prices`) may use after the root stage
#: (:func:`_window_stage`).
WINDOW_SHARE = 0.1

#: The cut engine runs first, with the whole limit, when its root bound closes at least this
#: share of the gap between the DP's root bound (the assignment/arborescence bound) and the
#: best order: the DP's completion bound then prunes almost nothing the cut engine needs
#: (p43.1: 0.99, root 28,100 against 2,720 and an order of 28,335; the DP's first stage
#: spent 23 s for a bound of 2,720). Below it (prob.42 0.36, rbg050c 0.41, ry48p.1 0.48,
#: ft53.1 0.49, ESC47 0.15) the DP goes first as before.
CUTS_FIRST_SHARE = 0.9

#: Seconds that must be left after the root stage for the cut engine to go first: its MIP
#: rounds overran a 10 s limit on p43.1 by 3.5 s at load 6 (HiGHS looks at its clock
#: between the phases of a round's root node, seconds apart there); with less time the DP
#: goes first as before.
CUTS_FIRST_MIN_LEFT = 20.0

#: Share of the time limit CP-SAT keeps running beside the portfolio after the portfolio's
#: root stage chose the cut engine first (:data:`CUTS_FIRST_SHARE`): then stopped, keeping
#: its best order and the bound it sent with it. Its circuit model's bound is far below
#: the root's there (p43.1: 910 against 28,100) and the cut engine's HiGHS runs use both
#: cores. Proofs by CP-SAT came within 3-6 s (rbg050c, rbg048a) where the rule does not fire.
CPSAT_PROBE_SHARE = 0.15


#: The root stage's prices reach the DP with their priced rows
#: (:meth:`taopt.models.sop_cuts.SopCutModel.row_credit`): a state is then dropped by its
#: kept prefix's reduced cost plus the duals of the path cuts it crosses more than once
#: (:mod:`taopt.models.sop_dp`, "Row credit"); False: the prefix's reduced cost alone.
ROW_CREDIT = True

#: The proof stage: when the best order is within :data:`PROOF_GAP` of the best bound (after
#: the root stage, or else after the first DP stage and its local search), the DP runs with the
#: root's LP re-solved per state (:class:`taopt.models.sop_statelp.StateLp`, a branch-and-bound
#: whose nodes are the DP's states) for the time left, and gives the time back to the later
#: stages as soon as its next layer's LPs cannot end in it
#: (:func:`taopt.models.sop_dp.solve_sop_dp`'s ``give_up``). With its optimum 243 as the
#: incumbent, prob.42 is proven this way in 29-40 s after a 3-4 s root loop (layers of at most
#: 85 states, 2,424 LPs, load 4-6), where the DP without the LPs kept 2.9 million states in 60 s.
PROOF_STAGE = True

#: The proof stage runs when the best order's relative gap to the best bound
#: (:func:`root_gap`) is at most this (and the root stage closed less than
#: :data:`CUTS_FIRST_SHARE` of the gap: above it the cut engine is the stage that closes it;
#: p43.1 at 10 s under load 6.5 ended 28205 [28090] with the proof stage before its cut engine,
#: 28205 [28135] without). The per-state LPs raise the bound of the first layers'
#: states by 1-2 % of the root's (prob.42 230 -> 234, ry48p.1 14,775 -> 14,873, ft53.1
#: 7,189 -> 7,226, each with its optimum as the incumbent): a state is dropped when its LP
#: reaches the incumbent, so a wider gap leaves the layers growing and the stage giving up.
PROOF_GAP = 0.06

#: Where the gap is wider than :data:`PROOF_GAP`, the proof stage runs trial cutoffs instead
#: (:func:`taopt.models.sop_dp.trial_cutoffs`: the same DP with the per-state LP at cutoffs
#: stepped up from the bound, :data:`taopt.models.sop_dp.TRIAL_STEP`), within
#: :data:`TRIAL_SHARE` of the time left, after the first DP stage and the primal search only
#: (run before the first DP stage, they cost the stand-in p43-0.3 its proof by the DP: 39 s
#: against 13 s at 60 s, load 7.5); a proven cutoff is a bound, a trial that finds an order
#: below its cutoff proves it optimal. Single cutoffs from the root's bounds, no incumbent
#: (load 4-5): prob.42 240 proven in 3.4 s (root 230, optimum 243; at 244 it found and proved
#: 243 in 17 s), ry48p.1 15,030 in 6 s (root 14,775), ft53.1 7,270 in 1.6 s and 7,360 in 19 s
#: (root 7,189); the DP stages' own bounds stay at or near the root's.
TRIAL_CUTOFFS = True

#: Whether the trial cutoffs run where our branch-and-cut tree comes next after a root loop
#: that ended within its share of the limit (:func:`trials_wanted`). False: the tree gets
#: their time there. Their proven bound does not reach the tree (it prunes by the incumbent's
#: cost, not by a lower bound; the two bounds are only combined at the end), and where the
#: root's LPs are quick the tree raises the bound faster at these gaps (all above
#: :data:`PROOF_GAP`, so above :data:`taopt.models.sop_bc.TREE_MIN_GAP`): at 60 s, load
#: 2.7-4.9, the trials took prob.42 from 230 to 242 in 21 s (9.7 s of it on three trials above
#: 242 that gave up) and left the tree 25 s, too little to close it (the tree alone proves 243
#: in 13 s); on ry48p.1 they took 19 s for 14,775 -> 14,943 and the tree then reached 15,156 in
#: the 20 s left. Where the root loop did not end within :data:`ROOT_SHARE` of the limit the
#: tree, which starts with that loop again and re-solves an LP of its size per node, gets few
#: nodes (esc-like-65, root cut at 6 s: 0-2 nodes in 20 s) while the trials raised its bound
#: 609 -> 648 in 10 s; they run there as before, and where the cut engine does not follow.
TRIALS_BEFORE_TREE = False


#: Where the trial cutoffs are skipped for our tree (:func:`trials_wanted` false on a gap
#: above :data:`PROOF_GAP`), the first DP stage, its primal search and the second DP stage are
#: skipped too and the tree gets the time at once (:func:`tree_first`). Those stages' bound
#: stays at the root's on such a gap (the DP's states are pruned by the root's prices and the
#: gap is wide), and the tree finds its own orders: on prob.42 the first DP stage and its
#: search took 8-22 s of a 60-s run (their order 259, the optimum 243), the tree alone proves
#: 243 in 12.6-13.4 s. False: the stages run as before.
TREE_FIRST = True

#: On the tree-first path (:data:`TREE_FIRST`) the first DP stage's beam passes give the
#: tree an order within this share of the time left (of which the passes take
#: :data:`taopt.models.sop_dp.BEAM_SHARE`, the first at least its
#: :data:`~taopt.models.sop_dp.FIRST_BEAM_SHARE`): the tree's own roundings can stay far above
#: the DP's orders where the root is weak (esc-like-65-0.04 at 60 s, load 4.5: the tree's best
#: 1015 against 417 from the DP stage and its search; beams of 64, 256 and 1,024 give 666, 417
#: and 337 in 0.6, 1.1 and 3.3 s at load 4).
TREE_FIRST_BEAM_SHARE = 0.3

#: The widest of those passes (the DP stage's default ``beam_width``).
TREE_FIRST_BEAM_WIDTH = 1024

#: The share of the time left after the beam that the primal search (:func:`_searched`, from
#: the beam's order, stopped after :data:`ILS_PATIENCE` steps without a better order) may use
#: before the tree, whose cutoff its order becomes. Run after the tree instead, from the tree's
#: best order, it ended esc-like-65-0.04 at 510 (60 s, load 4.8), where the DP stage's order
#: and the search from it gave 417.
TREE_FIRST_SEARCH_SHARE = 0.15

#: On the tree-first path the primal search runs only where the beams' order is more than this
#: (relative) above the best bound: there the tree's own roundings stay far from it
#: (esc-like-65-0.04, beams' order 417 on a bound of 203-208: the tree's best 1015). Below it
#: the tree's orders are as good as the search's and its proof does not wait for it
#: (60 s, load 5-6, the search before the tree and not: the same final orders on prob.42 243,
#: ft53.1 7678-7679 and ry48p.1 15805, from beams' gaps of 15, 6.5 and 7.9 %; the search
#: took 2.3 s of prob.42's 16-s proof, 444 nodes with it and without it).
TREE_FIRST_SEARCH_GAP = 0.25


def trials_wanted(tree_next: bool, root_complete: bool) -> bool:
    """Whether the proof stage may run its trial cutoffs on a gap above :data:`PROOF_GAP`:
    :data:`TRIAL_CUTOFFS`, and not where our tree comes next (``tree_next``: the cut engine
    fits the memory with the ``"cuts"`` formulation) after a root loop that ended with no
    violated row within its share of the limit (``root_complete``), unless
    :data:`TRIALS_BEFORE_TREE`."""
    return TRIAL_CUTOFFS and (TRIALS_BEFORE_TREE or not (tree_next and root_complete))


def tree_first(tree_next: bool, root_complete: bool, gap: float) -> bool:
    """Whether our tree runs right after the root stage (:data:`TREE_FIRST`; the window stage
    between them only with :data:`TREE_FIRST_WINDOW`):
    where it comes next (``tree_next``) after a root loop complete within its share
    (``root_complete``) and the relative ``gap`` of the best order to the best bound is above
    :data:`PROOF_GAP`, that is where :func:`trials_wanted` leaves the gap to the tree."""
    return TREE_FIRST and gap > PROOF_GAP and not trials_wanted(tree_next, root_complete)


#: Whether the window stage runs where the root's gap already sends the tree first
#: (:func:`tree_first` on the root's bound and the order known after it). Its prices serve
#: the DP stages, which that path skips, and its bound stayed below the complete root loop's
#: on every file that took the path (10 s, load 1-1.5, window / root: prob.42 227 / 230,
#: ft53.1 6135 / 7189, ry48p.1 14058 / 14775, esc-like-65-0.04 110 / 170, ESC25 1569 / 1663,
#: ESC47 1199 / 1254; 0.2-0.8 s each). False: the tree goes first without it (the gap from
#: the root's bound alone); True: it runs, and its bound may still send the run to the DP
#: path, as before.
TREE_FIRST_WINDOW = False


#: Share of the time left the trial cutoffs may use: they replace the first DP stage's time
#: where its bound stays at the root's, and leave the rest to the primal search and the cut
#: engine as :data:`DP_SHARE` leaves it to the MILP.
TRIAL_SHARE = 0.5

#: The DP stages after the root stage bound their states also by the root's LP re-solved with
#: each state's ideal fixed (:class:`taopt.models.sop_statelp.StateLp`, within its share of
#: each stage's time). Off: on a quiet machine at 10 s it raised no bound of prob.42, ry48p.1,
#: ft53.1 or p43.1 (ry48p.1 14,794-14,798 on against 14,810-14,842 off, two runs each,
#: alternated, load 1.6-1.9), and at 60 s it gave the same bounds within noise; its gain is
#: below the incumbent's reach (prob.42 with its optimum 243 as the incumbent closes in 27 s
#: with it, open at 60 s without). :func:`~taopt.models.sop_dp.solve_sop_dp` takes it as
#: ``state_lp``.
STATE_LP = False

#: Share of the time left after the first DP stage (when it stopped without a proof) given to
#: the primal search (:func:`taopt.models.sop_lns.large_neighbourhood_search`: exact
#: reinsertion of removed nodes, SOP-3-exchange descents, escalating kicks and restarts) on
#: the stage's order (after its beam passes), before the second stage and the cut engine prune
#: with that order's cost (0: not run). From a width-64 beam's order, 5 CPU-seconds of it gave
#: ry48p.1 15805 on seeds 0-4 (the iterated local search: 16321 on each), ft53.1 7569-7753
#: (7922-8123) and prob.42 247-248 (248-257); 1 CPU-second was not enough (ry48p.1
#: 15947-16321), so it gets a larger share than the iterated search had (0.2: 0.8-0.9 s of
#: wall time at a 10 s limit).
ILS_SHARE = 0.3

#: Repair steps of that search in a run without a time limit.
ILS_ITERATIONS = 1000

#: The search stops after this many repair steps without a new best order.
ILS_PATIENCE = 400

#: It is not run when the stage's order is at most this share above its bound
#: (:func:`root_gap`): the later stages close such gaps (p43.1 at 10 s, under 1 %, closed in
#: 7.1 s without the search and not at all with 1.5 s of it before the DP), while the orders of
#: prob.42, ry48p.1 and ft53.1 were 13-17 % above the root bound. Run before the first DP
#: stage instead, from the insertion orders, it cost ESC47 its 10 s proof (2 iterations in
#: 1.3 s from an order of 2,430, optimum 1,288).
ILS_MIN_GAP = 0.05


def _far(result: Solution) -> bool:
    """The run's relative gap is above :data:`CUTS_SECOND_STAGE_GAP` (or unknown)."""
    bound, value = result.bound, result.objective
    if bound is None or not np.isfinite(value) or value <= 0:
        return True
    return (value - bound) / value > CUTS_SECOND_STAGE_GAP


#: Nodes from which the portfolio starts CP-SAT beside its own stages when ``cpsat=None``
#: (below, the DP closes in well under a second: ESC25 0.7 s; starting CP-SAT's worker would
#: only take a core's second from it).
CPSAT_MIN_NODES = 30

#: The least time limit with which the portfolio starts CP-SAT when ``cpsat=None`` (its
#: worker needs about a second to start and import OR-Tools).
CPSAT_MIN_LIMIT = 2.0

#: Seconds before the portfolio's deadline at which CP-SAT's run is told to end (the worker
#: starting, replying and being reaped are on the portfolio's clock).
CPSAT_MARGIN = 0.5

#: Seconds the portfolio waits for CP-SAT's reply past its own deadline before it stops the
#: worker and keeps the last order the worker sent.
CPSAT_WAIT = 0.3

#: Seconds the portfolio waits for CP-SAT's worker to be stopped and reaped once cancelled.
CPSAT_STOP_WAIT = 2.0

#: Niceness of CP-SAT's worker process beside the portfolio (0: the same CPU priority as
#: the portfolio). Chosen by the figures in ``docs/benchmarks.md`` (SOP section).
CPSAT_NICE = 0

#: With ``cpsat=None``, CP-SAT is not started when the order ideals were counted (at most
#: :data:`taopt.models.sop_dp.IDEAL_CAP`): the DP then runs alone over them, where CP-SAT's
#: circuit model has not helped on any instance measured (the dense-precedence .4 files:
#: at 10 s, load 4-6, ry48p.4 36,111 [21,390] against our optimum, ft53.4 16,189 [10,995]
#: against our 15,340 [12,814]; the crane stand-ins of ``rbg_from_atsp`` at closure
#: 0.84-0.89: no order in 60 s) and its worker takes a core from the DP (a 110-node crane
#: stand-in, 58,930 ideals: closed in 10.2 s alone, 13.6 s beside).
CPSAT_SKIP_COUNTED = True


def _dp_alone(capped: bool) -> bool:
    """Whether the portfolio's DP runs alone (the ideals were counted, not capped):
    CP-SAT is then not started by default (:data:`CPSAT_SKIP_COUNTED`)."""
    return CPSAT_SKIP_COUNTED and not capped


def _cpsat_peer(
    problem: SopProblem,
    cpsat: bool | None,
    engine: str,
    time_limit: float | None,
    max_memory_gb: float | None = None,
) -> tuple[Callable[..., Solution] | None, str]:
    """The registered CP-SAT peer of the SOP to run beside the portfolio, or None and why.

    Looked up in the registry (an exact model never imports the heuristics package): the
    peer is there once ``taopt.heuristics`` is imported, as :func:`taopt.solve` does, and
    available when ``ortools`` is installed (found, not imported).

    Raises
    ------
    SolverError
        ``cpsat=True`` and the peer is not registered or ``ortools`` is not installed.
    """
    from taopt.registry import methods

    if cpsat is False:
        return None, "off"
    if engine != "auto":
        return None, f"off: engine={engine!r}"
    spec = methods(problem).get("cpsat")
    if spec is None or not spec.available:
        if cpsat:
            raise SolverError(
                "cpsat=True needs OR-Tools (pip install ortools) and the peer registered "
                "(import taopt.heuristics; taopt.solve does)"
            )
        return None, "not available (ortools not installed or taopt.heuristics not imported)"
    if cpsat is None and problem.n < CPSAT_MIN_NODES:
        return None, f"off: {problem.n} nodes < {CPSAT_MIN_NODES}"
    if cpsat is None and time_limit is not None and time_limit < CPSAT_MIN_LIMIT:
        return None, f"off: time_limit {time_limit:g} s < {CPSAT_MIN_LIMIT:g} s"
    if cpsat is None and not _cpsat_fits(problem.n, max_memory_gb):
        from taopt.runtime import max_memory_gb as limit_gb

        worker = cpsat_worker_bytes(problem.n) / 1e6
        return None, (
            f"off: its worker ({worker:,.0f} MB) and the DP do not fit the memory limit of "
            f"{limit_gb(max_memory_gb):g} GB"
        )
    return spec.func, ""


def _cpsat_fits(n: int, max_memory_gb: float | None) -> bool:
    """Whether CP-SAT's worker (:func:`cpsat_worker_bytes`) leaves the stages the room of
    the DP (:func:`taopt.models.sop_stages.memory_plan` still "dp" in the limit less it)."""
    from taopt.models.sop_stages import memory_plan

    return memory_plan(n, _stage_limit(max_memory_gb, cpsat_worker_bytes(n))) == "dp"


def _stage_limit(max_memory_gb: float | None, reserve: float) -> float | None:
    """The memory limit (GB) left to the portfolio's stages when ``reserve`` bytes are spent
    beside them (CP-SAT's worker); ``max_memory_gb`` itself when nothing is. Never below a
    megabyte (a limit the stages then degrade to, :func:`taopt.models.sop_stages.memory_plan`)."""
    if not reserve:
        return max_memory_gb
    from taopt.runtime import max_memory_gb as limit_gb

    return max(limit_gb(max_memory_gb) - reserve / 1e9, 1e-3)


def _bounds_max(*bounds: float | None) -> float | None:
    """The largest of the proven bounds given (None when there is none)."""
    known = [float(b) for b in bounds if b is not None and not np.isnan(b)]
    return max(known) if known else None


def _beside(
    problem: SopProblem, ours: Solution, other: Solution | None, stop: str
) -> tuple[Solution, dict[str, Any]]:
    """The portfolio's result and CP-SAT's (None: no answer) as one: the better order, the
    larger proven bound, the status by the one rule (:func:`taopt.status.decide`) with
    ``stop`` for an open gap; and who found and who proved what."""
    credit: dict[str, Any] = {"order_from": "portfolio", "bound_from": "portfolio"}
    if ours.status == INFEASIBLE or other is None:
        if ours.status == OPTIMAL:
            credit["proved_by"] = "portfolio"
        return ours, credit
    usable_bound = None if other.status == INFEASIBLE else other.bound
    best = ours
    if other.solution is not None and other.objective < ours.objective:
        best = other
        credit["order_from"] = "cpsat"
    bound = _bounds_max(ours.bound, usable_bound)
    if usable_bound is not None and (ours.bound is None or usable_bound > ours.bound):
        credit["bound_from"] = "cpsat"
    status = best.status
    if np.isfinite(best.objective):
        bound = None if bound is None else min(bound, best.objective)
        status, credit["stopped_by"] = decide(stop, best.objective, bound)
    if status == OPTIMAL:  # who closed it: an engine whose own gap is closed, else the pair
        own = [name for name, run in (("portfolio", ours), ("cpsat", other))
               if run.status == OPTIMAL]  # fmt: skip
        credit["proved_by"] = "+".join(own) if own else "portfolio+cpsat"
    return best.replace(bound=bound, status=status), credit


def solve_sop_problem(
    problem: SopProblem,
    time_limit: float | None = None,
    formulation: str = PORTFOLIO_FORMULATION,
    mip_gap: float = 1e-9,
    verbose: bool = False,
    incumbent: Any = None,
    engine: str = "auto",
    ideal_cap: int | None = None,
    max_states: int = PORTFOLIO_MAX_STATES,
    max_memory_gb: float | None = None,
    cpsat: bool | None = None,
    seed: int = 0,
) -> Solution:
    """The SOP portfolio (the registered "exact"): the ideal DP for dense precedence, the
    MILP for sparse precedence, and CP-SAT beside them.

    CP-SAT (the model of :func:`taopt.heuristics.peers.cpsat_sop`, one search worker) is
    started at once in its worker process, with the portfolio's deadline less
    :data:`CPSAT_MARGIN`, and runs while this process runs the stages below
    (:class:`taopt.runtime.workers.Background`). The first side to prove the optimum stops
    the other (CP-SAT's "optimal" counts only after taopt's scorer re-scored its order and
    its bound, rounded down to the problem's units, closes the gap); otherwise the result is
    the better of the two orders with the larger of the two proven bounds, its status by
    the one rule (:func:`taopt.status.decide`). By default (``cpsat=None``) CP-SAT runs
    when OR-Tools is installed and the peer registered (:func:`taopt.solve` imports it), on
    :data:`CPSAT_MIN_NODES` nodes or more, with no limit or one of at least
    :data:`CPSAT_MIN_LIMIT` s, and ``engine="auto"``, unless the order ideals, counted first
    (on the clock), are few enough for the DP to run alone (:data:`CPSAT_SKIP_COUNTED`). The wall time stays within the limit
    plus :func:`~taopt.runtime.deadline.overrun_allowance`: the worker's start, reply and stop
    are on the clock.

    The portfolio's own stages. Rule (``engine="auto"``): count the order ideals up to
    ``ideal_cap`` (:func:`taopt.models.sop_dp.count_ideals`, milliseconds to a second; at most
    :data:`COUNT_SHARE` of the limit, a count cut short meaning too many).
    When they are fewer, the DP (:func:`taopt.models.sop_dp.solve_sop_dp`) runs alone: its
    states are at most n times the ideals. Otherwise, with the cut engine as the MILP stage
    (``formulation="cuts"``) and its model within the memory limit, a root stage runs the
    cut engine's root cut loop first, in :data:`ROOT_SHARE` of the limit
    (:func:`_root_stage`): its rounded LP point may improve the warm start, its LP duals
    give the DP stages a Lagrangian bound that drops states
    (:func:`taopt.models.sop_dp.solve_sop_dp`'s ``lagrange``, with the row credit of its
    path cuts, ``credit``, :data:`ROW_CREDIT`; and, when :data:`STATE_LP` is on, the root's
    LP re-solved per DP state with the state's ideal fixed, its prices inherited along each
    state's kept prefix, ``state_lp``), and the cut engine later goes on from its rows. Unless
    the cut engine goes first, a window stage follows (:func:`_window_stage`, at most
    :data:`WINDOW_SHARE` of the limit): the position-window
    Lagrangian bound (:mod:`taopt.models.sop_window`) from the assignment's prices; when it is
    above the assignment/arborescence bound, its prices bound every DP stage's states
    (``window``); the reported bound is never below it (``info["window"]``). When
    the best order is then within :data:`PROOF_GAP` of the root bound, or once the first DP
    stage and its local search brought it there, the proof stage runs
    (:data:`PROOF_STAGE`: the DP with the root's LP re-solved per state for the time left,
    giving the time back as soon as its layers show it cannot end; after them on a wider gap,
    its trial cutoffs, unless our tree follows a root loop complete within its share:
    :func:`trials_wanted`). When
    the root closes at least :data:`CUTS_FIRST_SHARE` of the gap
    between the DP's root bound and the best order (p43.1), the cut engine runs next with
    all the time left, and CP-SAT beside is stopped once :data:`CPSAT_PROBE_SHARE` of the
    limit has passed (its last order and bound kept). Where the trials would be skipped for
    our tree and the best order is more than :data:`PROOF_GAP` above the root's bound, the
    tree goes first (:func:`tree_first`, :data:`TREE_FIRST`; the window stage skipped unless
    :data:`TREE_FIRST_WINDOW`): the DP
    stage's beam passes give it an order, improved by the primal search where it is far above
    the bound (:data:`TREE_FIRST_SEARCH_GAP`), then it gets all the time left
    (``info["tree_first"]``). Otherwise the DP runs first with at
    most ``max_states`` states and :data:`DP_SHARE` of the time (its beam pass and its pruning
    often close the instance anyway: ESC25), then, if it has not proved the optimum, a
    second DP stage with the bound on both price sets (``both_prices``) and
    :data:`SECOND_STAGE_MAX_STATES` states in :data:`SECOND_STAGE_SHARE` of the time left
    (rbg050c), and if that has not either the flow
    MILP (:func:`solve_sop`) gets the rest, warm-started with the best order so far; the
    bound reported is the larger of the two proven bounds (never below the assignment
    and arborescence bounds). The rule is the same for any number of nodes (the DP's masks
    take several words beyond 64). ``info["stage_seconds"]`` gives the wall seconds each
    stage took. The figures behind the rule are in
    ``docs/benchmarks.md`` (SOP section).

    Parameters
    ----------
    problem : SopProblem
    time_limit : float, optional
        Wall-clock seconds for the whole portfolio.
    formulation : {"cuts", "flow", "mtz"}
        The MILP stage (:data:`PORTFOLIO_FORMULATION`): "cuts" runs
        :func:`~taopt.models.sop_cuts.solve_sop_cuts` (precedence path cuts on the arc
        model), "flow"/"mtz" :func:`solve_sop`.
    mip_gap, verbose
        Passed to the MILP stage.
    incumbent : Order, list of int or Solution, optional
        The warm start's order (NIA, MMA, SMMA through the registry).
    engine : {"auto", "dp", "milp"}
        Force one engine ("dp" runs the DP with ``max_states`` and no MILP after it).
    ideal_cap : int, optional
        Cap of the ideal count (default :data:`taopt.models.sop_dp.IDEAL_CAP`).
    max_states : int
        States the DP may keep when the ideals passed the cap (lowered to fit the memory
        limit, :func:`dp_state_cap`).
    max_memory_gb : float, optional
        The memory limit (default :func:`taopt.runtime.max_memory_gb`, passed on by
        ``taopt.solve``). Above it the MILP is skipped and the DP's state caps shrink; below
        what the DP needs, the beam or the cheap bounds alone run
        (:func:`taopt.models.sop_stages.memory_plan`): the run degrades to what fits and
        returns ``time_limit`` with its best order and a proven bound, never a refusal for
        size alone. CP-SAT's worker beside takes its estimated share of the limit first
        (:func:`cpsat_worker_bytes`; with ``cpsat=None`` it is not started when the DP would
        no longer fit beside it). A run whose stages end before its limit without a proof goes on with
        larger DP caps while they fit, then wider beams
        (:func:`taopt.models.sop_stages.use_the_rest`), so it uses its whole limit.
    cpsat : bool, optional
        Run CP-SAT beside the stages: True (a :class:`~taopt.errors.SolverError` when it is
        not available), False (never), None (default: the rule above).
    seed : int
        Seed of the primal search after the first DP stage (:data:`ILS_SHARE`).

    Returns
    -------
    Solution
        As :func:`solve_sop`; status "infeasible" when no path exists. ``info`` has
        ``engine`` ("dp", "milp", "dp+dp", "dp+milp", "dp+dp+milp", with "proof" where the
        proof stage ran (``info["proof"]``: why not, or its gap, status, bound, seconds,
        states, LPs and why it gave up), or the degraded
        "beam" / "bound"; "+cpsat" appended when CP-SAT found the order kept, the larger
        bound or the proof), ``cpsat`` (why it did not run, or its ``status``,
        ``cpsat_status``, ``objective``, ``bound``, ``seconds``, ``startup``, ``nice`` and
        ``worker``: why its worker was stopped), ``order_from`` / ``bound_from``
        ("portfolio" or "cpsat") and ``proved_by`` when optimal, ``ideals`` and
        ``ideals_capped``, the DP's ``states``/``pruned`` when it ran, ``memory_plan``,
        ``memory_estimate`` (the peak bytes predicted before the later stages,
        :func:`predicted_peak`: after the first DP stage's first layers, measured by its
        probe :class:`LayerWatch`, or before the cut engine when it goes first; its inputs,
        the probe's layers included, in ``memory_prediction``; where the rule made
        no prediction, a degraded or forced engine, the largest of the stages' estimates;
        plus CP-SAT's worker when it ran beside, :func:`cpsat_worker_bytes`;
        ``info["cpsat"]["memory_estimate"]`` is the worker's), ``memory_stages`` (the
        largest of the stages' upper estimates, each made before the stage started),
        ``rest`` (what ran after the stages, if anything) and ``root_stage`` when it ran (its
        bound, seconds, LP rounds, the share of the gap it closed, ``cuts_first``);
        ``cpsat["stopped"]`` when the rule stopped CP-SAT.
    """
    began = time.perf_counter()
    if engine not in PORTFOLIO_ENGINES:
        raise InstanceError(f"engine must be one of {PORTFOLIO_ENGINES}, got {engine!r}")
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    options = dict(
        formulation=formulation, mip_gap=mip_gap, verbose=verbose, incumbent=incumbent,
        engine=engine, ideal_cap=ideal_cap, max_states=max_states, max_memory_gb=max_memory_gb,
        seed=seed,
    )  # fmt: skip
    peer, why = _cpsat_peer(problem, cpsat, engine, time_limit, max_memory_gb)
    counted: tuple[int, bool, float] | None = None
    if peer is not None and cpsat is None and CPSAT_SKIP_COUNTED:
        # the count the stages need, made now (on the clock) to decide whether CP-SAT runs
        from taopt.models.sop_dp import IDEAL_CAP

        cap = IDEAL_CAP if ideal_cap is None else int(ideal_cap)
        counting = None if time_limit is None else Deadline(COUNT_SHARE * time_limit)
        counted = _ideal_count(problem, cap, counting)
        ideals, capped = counted[0], counted[1]
        if _dp_alone(capped):
            peer = None
            why = f"off: {ideals:,} ideals counted, the DP runs alone (CPSAT_SKIP_COUNTED)"
    if peer is None:
        result = _stages(problem, _left(time_limit, began), **options, counted=counted)
        runtime = time.perf_counter() - began
        return result.replace(runtime=runtime, info={**result.info, "cpsat": why})
    # CP-SAT's worker is a process of its own: its memory is counted, the stages get the rest
    reserve = cpsat_worker_bytes(problem.n)
    options["max_memory_gb"] = _stage_limit(max_memory_gb, reserve)
    left = _left(time_limit, began)  # less the count, when it was made above
    outer = Deadline(left)  # the caller's token, if any, stops both sides
    race = CancelToken(parent=outer.token)  # cancelled when CP-SAT proves the optimum
    seconds = None if left is None else max(left - CPSAT_MARGIN, MARGIN)

    def run_cpsat() -> Solution:
        found = peer(problem, time_limit=seconds, num_workers=1, nice=CPSAT_NICE)
        if found.status == OPTIMAL:  # re-scored by taopt's scorer, its bound closes the gap
            race.cancel()
        return found

    task = Background(run_cpsat, "cpsat-beside-portfolio", parent=outer.token)
    probe: list[threading.Timer] = []
    rule: dict[str, str] = {}

    def stop_cpsat() -> None:
        if not task.done():
            rule["stopped"] = (
                f"by the rule after {time.perf_counter() - began:.1f} s: the cut engine "
                "went first (CPSAT_PROBE_SHARE)"
            )
            task.cancel()  # its worker answers with the last order (and bound) it sent

    def on_tree() -> None:  # the tree's peer process takes CP-SAT's core (TREE_SPLIT)
        if not task.done():
            rule["stopped"] = (
                f"by the rule after {time.perf_counter() - began:.1f} s: the tree took its "
                "core (TREE_SPLIT)"
            )
            task.cancel()

    def on_root(cuts_first: bool) -> None:
        # the root closed most of the gap: CP-SAT's circuit bound will not help, and the cut
        # engine wants the cores; CP-SAT keeps CPSAT_PROBE_SHARE of the limit for its orders
        if cuts_first and time_limit is not None:
            wait = CPSAT_PROBE_SHARE * time_limit - (time.perf_counter() - began)
            timer = threading.Timer(max(wait, 0.0), stop_cpsat)
            timer.daemon = True
            probe.append(timer)
            timer.start()

    try:
        with cancel_scope(race):
            ours = _stages(
                problem, left, **options, on_root=on_root, counted=counted, on_tree=on_tree
            )
    except BaseException:  # Ctrl-C or an error: stop CP-SAT's worker too, then re-raise
        task.cancel()
        task.wait(CPSAT_STOP_WAIT)
        raise
    finally:
        for timer in probe:
            timer.cancel()
    if ours.status in (OPTIMAL, INFEASIBLE) or outer.cancelled:
        task.cancel()  # proved (or cancelled): CP-SAT's worker is stopped now
    left = outer.remaining()
    if not task.wait(None if left is None else left + CPSAT_WAIT):
        task.cancel()  # past the deadline: stopped; its last order is kept
    other: Solution | None = None
    cpsat_info: dict[str, Any] = {"nice": CPSAT_NICE, "memory_estimate": reserve}
    if task.wait(CPSAT_STOP_WAIT):
        try:
            other = task.result(0)
        except Exception as exc:  # CP-SAT's failure never costs the portfolio its answer
            cpsat_info["error"] = f"{type(exc).__name__}: {exc}"
    else:
        cpsat_info["error"] = f"its worker did not stop within {CPSAT_STOP_WAIT} s"
    cpsat_info["seconds"] = task.seconds
    cpsat_info.update(rule)
    if other is not None:
        cpsat_info.update(
            status=str(other.status),
            cpsat_status=other.info.get("cpsat_status"),
            objective=other.objective,
            bound=other.bound,
            startup=other.info.get("startup"),
        )
        if other.info.get("worker"):
            cpsat_info["worker"] = other.info["worker"]
    stop = "interrupted" if outer.cancelled else (ours.info.get("stopped_by") or "time_limit")
    if race.cancelled and not outer.cancelled:
        stop = "time_limit"  # our stages were stopped by CP-SAT's proof
    result, credit = _beside(problem, ours, other, stop)
    used = ours.info.get("engine", "")
    if "cpsat" in (credit["order_from"], credit["bound_from"]) or "cpsat" in credit.get(
        "proved_by", ""
    ):
        used += "+cpsat"
    estimate = ours.info.get("memory_estimate", BASE_BYTES) + reserve  # the two processes
    return result.replace(
        runtime=time.perf_counter() - began,
        method="exact-sop",
        info={
            **ours.info,
            **credit,
            "engine": used,
            "cpsat": cpsat_info,
            "memory_estimate": estimate,
        },
    )


#: Where the tree goes first (:func:`tree_first`), it searches in two processes
#: (:mod:`taopt.models.sop_split`, when :func:`~taopt.models.sop_split.split_wanted`): the
#: peer process is started as the path is chosen, and CP-SAT's worker beside the portfolio is
#: stopped then to give it its core (``on_tree``). On that path CP-SAT's circuit bound stayed
#: far below the root's and its orders above the tree's (60 s: prob.42 250 [180], ft53.1
#: 7569 [5931] against the root's 230 and 7,189 and the optima 243 and 7,531).
TREE_SPLIT = True

#: The tree-first path starts the peer only with this many seconds left (its start, about
#: 1.5-3.5 s on the 2-core machine, would take the whole of a shorter run).
TREE_SPLIT_MIN_SECONDS = 5.0


def _tree_peer(
    problem: SopProblem, deadline: Deadline, on_tree: Callable[[], None] | None, info: dict
) -> Any:
    """The tree's peer process, started (:data:`TREE_SPLIT`), or None; ``on_tree()`` first."""
    from taopt.models.sop_split import Peer, split_wanted

    left = deadline.remaining()
    if not (TREE_SPLIT and split_wanted()):
        info["tree_split"] = "off"
        return None
    if left is not None and left < TREE_SPLIT_MIN_SECONDS:
        info["tree_split"] = f"off: {left:.1f} s left < {TREE_SPLIT_MIN_SECONDS:g} s"
        return None
    if on_tree is not None:
        on_tree()
    info["tree_split"] = "on"
    return Peer(problem, left)


def _left(time_limit: float | None, began: float) -> float | None:
    """The part of ``time_limit`` left since ``began`` (never below :data:`MARGIN`)."""
    if time_limit is None:
        return None
    return max(time_limit - (time.perf_counter() - began), MARGIN)


def _root_stage(
    problem: SopProblem,
    deadline: Deadline,
    incumbent: Any,
    info: dict[str, Any],
    verbose: bool,
) -> tuple[Any, tuple[float, np.ndarray] | None, Any, bool]:
    """The portfolio's root stage: the cut engine's root cut loop within :data:`ROOT_SHARE`
    of the limit, before the DP.

    Returns ``(model, lagrange, incumbent, cuts_first)``: the cut model (its rows kept for the
    cut engine), its LP's Lagrangian bound for the DP
    (:meth:`taopt.models.sop_cuts.SopCutModel.lagrangian_prices`, None without duals), the
    better of ``incumbent`` and the LP point's rounded order, and whether the cut engine goes
    first (:data:`CUTS_FIRST_SHARE`). The root's rows are precedence path cuts valid for every
    order, and no arc is fixed here, so the Lagrangian bound holds for every order
    (:func:`taopt.models.sop_dp.solve_sop_dp`'s ``lagrange``). ``info`` gains
    ``root_stage`` (bound, seconds, rounds, whether its loop ended with no violated row, the
    share of the gap it closed).
    """
    from taopt.models.sop_cuts import SopCutModel, round_point

    began = time.perf_counter()
    model = SopCutModel(problem, verbose)
    root = model.root(Deadline(deadline.share(ROOT_SHARE), cancel=deadline.token))
    known = _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)
    if root.values is not None and not deadline.expired(MARGIN):
        rounded = round_point(model, root.values, deadline)
        if rounded is not None and (known is None or rounded[0] < known[0]):
            known = rounded
            incumbent = Order(rounded[1])
    # a loop stopped after adding rows has no LP solution: the last optimal LP's prices
    lagrange = model.lagrangian_prices(saved=True)
    cheap = _cheap_bound(problem)
    closed = 0.0
    if known is not None and known[0] > cheap and np.isfinite(root.bound):
        closed = (root.bound - cheap) / (known[0] - cheap)
    left = deadline.remaining()
    cuts_first = bool(closed >= CUTS_FIRST_SHARE) and (left is None or left >= CUTS_FIRST_MIN_LEFT)
    info["root_stage"] = {
        "bound": root.bound,
        "seconds": time.perf_counter() - began,
        "rounds": root.rounds,
        "complete": root.complete,
        "closed": closed,
        "cuts_first": cuts_first,
    }
    return model, lagrange, incumbent, cuts_first


def _window_stage(
    problem: SopProblem, deadline: Deadline, incumbent: Any, info: dict[str, Any], floor: float
) -> tuple[np.ndarray | None, float]:
    """The portfolio's window stage: the position-window Lagrangian bound
    (:mod:`taopt.models.sop_window`) from the assignment's prices, within
    :data:`WINDOW_SHARE` of the limit, towards the best order's cost.

    Returns ``(prices, bound)``: the prices for the DP stages (``window=`` of
    :func:`taopt.models.sop_dp.solve_sop_dp`), None when its bound is not above ``floor`` (the
    assignment/arborescence bound: the DP's own completion bound at the root; the subgradient
    then stops after its trial, :data:`taopt.models.sop_window.TRIAL`), and the bound (``-inf``
    without an order to aim at), valid for every order whatever the prices. Not compared with
    the root stage's LP: on the rbg stand-ins that LP equals the assignment bound and the
    window bound climbs above both only after hundreds of steps (rbg-atsp-255: a floor at the
    LP's 2,268 stopped it after its trial; without, it reached 2,320 in 6 s); the LP's prices
    bound the states' prefixes, these their completions. ``info["window"]`` says what ran."""
    from taopt.models.sop_dp import (  # sop_dp imports this module
        _cost_unit,
        _rounded_up,
        assignment_potentials,
    )

    known = _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)
    if known is None:
        info["window"] = "skipped: no order to aim at"
        return None, -np.inf
    # from the assignment's prices: the bound starts at the assignment bound
    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full(problem.cost.shape, np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    alpha, beta = assignment_potentials(usable, problem.start, problem.end)
    found = window_prices(
        problem,
        known[0],
        Deadline(deadline.share(WINDOW_SHARE), cancel=deadline.token),
        lam=start_prices(alpha, beta, problem.start, problem.end),
        floor=floor,
    )
    # every order's cost is a multiple of the costs' gcd when they are integral
    bound = float(_rounded_up(np.array([found.bound]), _cost_unit(problem))[0])
    used = bool(bound > floor)
    low, high = windows(problem)
    info["window"] = {
        "bound": bound,
        "seconds": found.seconds,
        "iterations": found.iterations,
        "width": float(np.mean(high - low + 1)) / problem.n,
        "floor": floor,
        "used": used,
    }
    return (found.lam if used else None), bound


def _beamed(
    problem: SopProblem,
    known: tuple[float, list[int]] | None,
    deadline: Deadline,
    info: dict[str, Any],
) -> tuple[float, list[int]] | None:
    """The better of ``known`` (cost, order) and the orders of the DP stage's beam passes
    (:func:`taopt.models.sop_dp._beam_start`: widths 64, 256 and
    :data:`TREE_FIRST_BEAM_WIDTH`, each started only when it should end in its budget) within
    :data:`TREE_FIRST_BEAM_SHARE` of the time left; ``info["tree_first_beam"]`` their best
    cost when it improved ``known``."""
    from taopt.models.sop_dp import _beam_start  # sop_dp imports this module

    budget = Deadline(deadline.share(TREE_FIRST_BEAM_SHARE), cancel=deadline.token)
    passes: dict[str, Any] = {}
    found = _beam_start(problem, known, TREE_FIRST_BEAM_WIDTH, budget, passes)
    info["tree_first_beam"] = passes.get("beam")
    return found


def _searched(
    problem: SopProblem,
    result: Solution,
    deadline: Deadline,
    seed: int,
    info: dict[str, Any],
    lower: float,
    share: float = ILS_SHARE,
    min_gap: float | None = None,
) -> Solution:
    """``result`` (the first DP stage's, stopped, or the beams' order on the tree-first path)
    with its order improved by the primal search
    (:func:`taopt.models.sop_lns.large_neighbourhood_search`, ``seed``) within ``share`` (by
    default :data:`ILS_SHARE`) of the time left and :data:`ILS_PATIENCE`; not run when its
    order is at most ``min_gap`` (None: :data:`ILS_MIN_GAP`; the tree-first path's
    :data:`TREE_FIRST_SEARCH_GAP`) above the larger of its bound and ``lower`` (the root
    stage's bound). The bound is kept (an order changes no bound); the order found is re-scored by
    the family's scorer; ``info["ils"]`` says what ran."""

    if not isinstance(result.solution, Order) or not np.isfinite(result.objective):
        info["ils"] = "skipped: no order"
        return result
    gap = root_gap(result.objective, max(result.bound or 0.0, lower))
    min_gap = ILS_MIN_GAP if min_gap is None else min_gap  # read at the call (tests set it)
    if gap <= min_gap:
        info["ils"] = f"skipped: the gap is {100 * gap:.1f} %, at most {100 * min_gap:g} %"
        return result
    began = time.perf_counter()
    budget = Deadline(deadline.share(share), cancel=deadline.token)
    iterations = None if deadline.limited else ILS_ITERATIONS
    value, order, found = large_neighbourhood_search(
        problem,
        list(result.solution),
        budget,
        iterations=iterations,
        seed=seed,
        patience=ILS_PATIENCE,
    )
    value = evaluate_order(problem, order)  # re-scored: raises on a broken precedence
    info["ils"] = {k: v for k, v in found.items() if k != "trace"}
    info["ils"].update({"from": result.objective, "to": value})
    info["ils"]["seconds"] = time.perf_counter() - began
    if not value < result.objective:
        return result
    bound = min(result.bound if result.bound is not None else -np.inf, value)
    status, _ = decide("time_limit", value, bound)
    return result.replace(solution=Order(order), objective=value, bound=bound, status=status)


def _stages(
    problem: SopProblem,
    time_limit: float | None,
    formulation: str,
    mip_gap: float,
    verbose: bool,
    incumbent: Any,
    engine: str,
    ideal_cap: int | None,
    max_states: int,
    max_memory_gb: float | None,
    on_root: Callable[[bool], None] | None = None,
    counted: tuple[int, bool, float] | None = None,
    seed: int = 0,
    on_tree: Callable[[], None] | None = None,
) -> Solution:
    """The portfolio's own stages (the rule of :func:`solve_sop_problem`), in this process.

    ``on_root(cuts_first)`` is called after the root stage (when it ran); ``on_tree()`` when
    the tree-first path starts its tree's peer process (:data:`TREE_SPLIT`). ``counted``:
    ``(ideals, capped, seconds)`` of a count already made (not made again)."""
    from taopt.models.sop_dp import IDEAL_CAP, solve_sop_dp, trial_cutoffs
    from taopt.models.sop_stages import degraded, memory_plan, use_the_rest

    began = time.perf_counter()
    deadline = Deadline(time_limit)
    unreachable = _unreachable(problem.cost, problem.closure, problem.start, problem.end)
    if unreachable is not None:
        return _infeasible(began, "portfolio", unreachable)
    cap = IDEAL_CAP if ideal_cap is None else int(ideal_cap)
    # the count gets COUNT_SHARE of the limit: past it the ideals are taken as too many
    counting_deadline = (
        Deadline(deadline.share(COUNT_SHARE), cancel=deadline.token) if deadline.limited else None
    )
    if counted is None:
        ideals, capped, counted_in = _ideal_count(problem, cap, counting_deadline)
    else:
        ideals, capped, counted_in = counted
    info: dict[str, Any] = {"ideals": ideals, "ideals_capped": capped}
    seconds: dict[str, float] = {}  # info["stage_seconds"]: wall seconds per stage
    if counted is None:
        seconds["count"] = counted_in
    clock = [time.perf_counter()]

    def lap(name: str) -> None:
        """Add the wall seconds since the last lap to stage ``name``."""
        now = time.perf_counter()
        seconds[name] = seconds.get(name, 0.0) + now - clock[0]
        clock[0] = now

    bounding = time.perf_counter()
    _cheap_bound(problem)  # now, on the clock: a stage stopped at the deadline only reads it
    # a DP stage's setup (its bounds, its first layers) runs outside its clock: about
    # DP_SETUP_PER_BOUND times the cheap bounds just computed, at least the count's time
    setup_guess = max(counted_in, DP_SETUP_PER_BOUND * (time.perf_counter() - bounding))
    max_states = dp_state_cap(problem.n, max_memory_gb, max_states)
    second_states = dp_state_cap(problem.n, max_memory_gb, max(max_states, SECOND_STAGE_MAX_STATES))
    # all the states the ideals allow (both directions), unless the memory caps them
    every_state = 2 * problem.n * ideals
    alone_states = dp_state_cap(problem.n, max_memory_gb, every_state)
    plan = memory_plan(problem.n, max_memory_gb)  # "dp", or a degraded stage that fits
    info["memory_plan"] = plan
    milp_ok = milp_fits(problem, formulation, max_memory_gb, time_limit)
    if not milp_ok:
        info["milp"] = "skipped: its memory estimate is above the limit"
    setups: list[float] = []  # the measured setup of each DP stage run (outside its clock)
    state_share = dp_state_share(problem)
    cheap = _cheap_bound(problem)

    def predict(
        path: str, known: Any, lower: float, seconds: float | None, cap: float
    ) -> LayerWatch | None:
        """Record the reported estimate (``info["memory_estimate"]``), once, before the
        stages: :func:`predicted_peak` from what is known now (``path``: "dp" alone, "dp"
        after the root stage or "cuts" first; the root gap of ``known`` against ``lower``).
        Where a DP stage runs first, the watch returned (:class:`LayerWatch`, handed to it)
        replaces it with the prediction from its first layers, made after PROBE_SHARE of the
        stage's time."""
        value = _known_order(problem.cost, problem.closure, problem.start, problem.end, known)
        gap = root_gap(None if value is None else value[0], max(lower, cheap))
        nonzeros = held() if path != "dp" or root_model is not None else 0.0
        beside = on_root is not None  # CP-SAT's worker beside (on_root is its hook)
        allowed = None if capped else every_state

        def made(probe: Probe | None) -> None:
            peak, features = predicted_peak(
                problem, path, seconds, cap, allowed, nonzeros, cut_time(path), probe, beside
            )
            info["memory_prediction"] = {**features, "gap": gap}
            if probe is None and path != "cuts":
                info["memory_prediction"]["probe"] = "not run (no DP layer yet)"
            predicted[:] = [peak]

        made(None)  # replaced by the probe's, when the DP stage gets its first layers
        if path == "cuts":
            return None
        left = deadline.remaining()  # the probe: PROBE_SHARE of the time left, at most
        budget = PROBE_MAX_SECONDS if left is None else min(PROBE_SHARE * left, PROBE_MAX_SECONDS)
        return LayerWatch(budget, made)

    predicted: list[float] = []

    def cut_time(path: str) -> float | None:
        """The most time the cut engine gets on ``path`` (0: it does not run): all the time
        left when it goes first, else what the first DP stage leaves (``1 - DP_SHARE``)."""
        if path == "dp" or not milp_ok or formulation != "cuts":
            return 0.0
        left = deadline.remaining()
        return left if left is None or path == "cuts" else left * (1.0 - DP_SHARE)

    def expect(
        states: float = 0.0,
        seconds: float | None = None,
        nonzeros: float = 0.0,
        compiled: bool = True,
    ) -> None:
        """Record the estimated peak of a stage about to run (``info["memory_estimate"]``: the
        largest over the stages run): a DP stage keeps at most its cap, the states the ideals
        allow and :func:`dp_states_in` its time (after its beam pass); a MILP its
        nonzeros, compiled or only built."""
        if seconds is not None:
            states = min(states, dp_states_in(problem.n, seconds))
        if not capped:
            states = min(states, every_state)
        dp_part = dp_bytes(problem.n, states) * state_share
        dp = max(dp_part, beam_bytes(problem.n, 1024)) if states else 0.0
        stage(BASE_BYTES + dp + sop_milp_bytes(nonzeros, compiled))

    def stage(need: float) -> None:
        info["memory_estimate"] = max(info.get("memory_estimate", BASE_BYTES), need)

    root_model: Any = None  # the root stage's cut model, handed to the cut engine

    def held() -> float:
        """Nonzeros of the root stage's cut model, kept in memory beside the DP stages."""
        if root_model is None:
            return 0.0
        return nonzero_count(problem.cost, problem.closure, problem.start, "cuts")

    def state_lp() -> Any:
        """The root model's LP re-solved per DP state (:data:`STATE_LP`), or None."""
        if not STATE_LP or root_model is None or lagrange is None or root_model.detached:
            return None
        return StateLp(root_model)

    lagrange: tuple[float, np.ndarray] | None = None  # its LP's Lagrangian bound, for the DP
    window: np.ndarray | None = None  # the window stage's prices, for the DP
    window_bound = -np.inf  # and its bound
    credit: Any = None  # the same LP's prices with its priced rows (the DP's row credit)

    def milp(
        known: Any,
        time_left: float | None,
        dp_result: Solution | None = None,
        peer: Any = None,
    ) -> Solution:
        if peer is not None and not (milp_ok and formulation == "cuts"):  # no tree: not used
            peer.close()
            peer = None
        if not milp_ok:  # degrade: the DP (state cap fitted to memory) for the rest
            return more_dp(dp_result, time_left)
        if formulation == "cuts":  # array-built and interruptible: no compile to fear
            from taopt.models.sop_bc import solve_sop_bc, wants_tree
            from taopt.models.sop_cuts import solve_sop_cuts

            order = _known_order(problem.cost, problem.closure, problem.start, problem.end, known)
            lower = max(
                float(info.get("root_stage", {}).get("bound", -np.inf)),
                -np.inf if dp_result is None else float(dp_result.bound or -np.inf),
            )
            if wants_tree(np.inf if order is None else order[0], lower):  # our own tree
                result = solve_sop_bc(
                    problem, time_left, known, verbose=verbose, model=root_model, peer=peer
                )
                peer = None  # stopped and reaped there
                info["cut_engine"] = "tree"
                if "peer" in result.info:
                    info["tree_peer"] = result.info["peer"]
            else:
                result = solve_sop_cuts(
                    problem, time_left, known, verbose=verbose, mip_gap=mip_gap, model=root_model
                )
                info["cut_engine"] = "mip-rounds"
            if peer is not None:  # the MIP rounds instead: the peer is not used
                peer.close()
            nonzeros = nonzero_count(problem.cost, problem.closure, problem.start, "cuts")
            stage(BASE_BYTES + cut_engine_bytes(nonzeros, time_left))
        else:
            if dp_result is not None and time_left is not None:
                # cvxpy's compile cannot be interrupted: after the DP stages the model is built
                # only when the time left covers MILP_SAFETY times its estimated build and
                # compile (p43.1 at 60 s under load: compiled in the last 6 s, ended at 71 s)
                columns = column_count(problem.cost, problem.closure, problem.start, formulation)
                need = MILP_SAFETY * compile_seconds(columns)
                if time_left < need:
                    info["milp"] = f"skipped: {time_left:.1f} s left, {need:.1f} s needed"
                    return more_dp(dp_result, time_left)
            nonzeros = nonzero_count(problem.cost, problem.closure, problem.start, formulation)
            result = solve_sop(
                problem.cost,
                problem.precedences,
                problem.start,
                problem.end,
                time_limit=time_left,
                formulation=formulation,
                mip_gap=mip_gap,
                verbose=verbose,
                incumbent=known,
                problem=problem,
            )
            if result.info.get("model") != "not built":  # built; compiled unless it says not
                expect(nonzeros=nonzeros, compiled=result.info.get("model") != STOPPED_EARLY[1])
        if dp_result is not None and result.status in (TIME_LIMIT, FEASIBLE):
            bound = max(result.bound or 0.0, dp_result.bound or 0.0)
            bound = min(bound, result.objective)
            status = result.status
            if np.isfinite(result.objective):
                stopped_by = result.info.get("stopped_by") or "time_limit"
                status, _ = decide(stopped_by, result.objective, bound)
            result = result.replace(bound=bound, status=status)
        if result.info.get("model") in STOPPED_EARLY and dp_result is not None:
            # the model could not be built or compiled in time: the DP uses the rest
            info["milp"] = result.info["model"]
            result = more_dp(result, deadline.remaining())
        return result

    def more_dp(before: Solution | None, time_left: float | None) -> Solution:
        """Another DP stage from the best order so far (both price sets, the memory-fitted
        cap) for the time left; the better order and the larger bound are kept. Not started
        when the time left does not cover twice the setup measured on an earlier stage."""
        if before is not None and time_left is not None:
            setup = max(setups, default=0.0)
            if time_left <= MARGIN or (setups and time_left < 2 * setup + MARGIN):
                if setups:
                    info["more_dp"] = f"skipped: {time_left:.2f} s left for a {setup:.2f} s setup"
                return before
        known = incumbent if before is None or before.solution is None else before.solution
        expect(second_states, time_left, nonzeros=held())
        again = solve_sop_dp(
            problem,
            None if time_left is None else max(time_left - MARGIN, MARGIN),
            incumbent=known,
            max_states=second_states,
            both_prices=True,
            beam_width=0 if before is not None else 1024,
            lagrange=lagrange,
            credit=credit,
            state_lp=state_lp(),
            window=window,
        )
        setups.append(again.info.get("setup_seconds", 0.0))
        return again if before is None else _combine(before, again)

    def root_closed() -> bool:
        """The root stage closed at least :data:`CUTS_FIRST_SHARE` of the gap."""
        return bool(info.get("root_stage", {}).get("closed", 0.0) >= CUTS_FIRST_SHARE)

    def proof(
        known: Any, bound: float | None, trials_ok: bool = False, setup: float = 0.0
    ) -> Solution | None:
        """The proof stage (:data:`PROOF_GAP`): the DP with the root's LP re-solved per state
        and its give-up rule, for the time left, from ``known`` (``bound``: a bound proven
        since the root stage; ``trials_ok``: where the gap is wider than :data:`PROOF_GAP`, the
        trial cutoffs instead of nothing (:func:`trials_wanted`); ``setup``: the measured
        setup of the DP stage before it, which it needs again). None when it does not run
        (``info["proof"]`` says why). A run
        that gave up is combined with the later stages' result at the end only, so their
        rules read their own gaps."""
        if not PROOF_STAGE or root_model is None:
            return None
        if lagrange is None:
            info["proof"] = "skipped: the root stage left no LP prices"
            return None
        if root_closed():
            # the root's LP closed most of the gap: the cut engine is the stage that closes it
            # (it goes first with time enough, CUTS_FIRST_MIN_LEFT)
            info["proof"] = "skipped: the root closed the gap (CUTS_FIRST_SHARE)"
            return None
        value = _known_order(problem.cost, problem.closure, problem.start, problem.end, known)
        root_bound = info.get("root_stage", {}).get("bound", cheap)
        lower = max(float(root_bound) if np.isfinite(root_bound) else cheap, cheap, window_bound)
        if bound is not None:
            lower = max(lower, bound)
        gap = root_gap(None if value is None else value[0], lower)
        trials = gap > PROOF_GAP
        if trials and not trials_ok:
            info["proof"] = f"skipped: the gap is {100 * gap:.1f} %"
            return None
        left = deadline.share(TRIAL_SHARE) if trials else deadline.remaining()
        need = max(setup_guess, setup, *setups)  # every trial sets up as a DP stage does
        if left is not None and left < 2 * need + MARGIN:
            info["proof"] = f"skipped: {left:.2f} s left for a {need:.2f} s setup"
            return None
        stage_began = time.perf_counter()
        expect(max_states, left, nonzeros=held())
        lp = StateLp(root_model, share=1.0)  # the LPs are this stage's work
        assert value is not None  # the gap is 1 without an order
        if trials:  # the gap is wide: raise the bound by trial cutoffs stepped up from it
            found = trial_cutoffs(
                problem,
                Order(value[1]),
                lower,
                None if left is None else max(left - MARGIN, MARGIN),
                lp,
                lagrange,
                credit,
                max_states,
                window,
            )
            info["proof"] = proof_record(found, gap, stage_began, "trials")
            info["proof_trials"] = found.info.get("trials") or []
            return found
        found = solve_sop_dp(
            problem,
            None if left is None else max(left - MARGIN, MARGIN),
            incumbent=Order(value[1]),
            max_states=max_states,
            beam_width=0,
            lagrange=lagrange,
            credit=credit,
            state_lp=lp,
            give_up=True,
            window=window,
        )
        setups.append(found.info.get("setup_seconds", 0.0))
        info["proof"] = proof_record(
            found, gap, stage_began, "states", "lp_solved", "lp_pruned", "gave_up"
        )
        return found

    dp_next = engine != "milp"
    # a DP stage first sets up its bounds and first layers outside its clock, about as long
    # as the count just measured (both follow the machine's load): not started without that
    dp_cannot_fit = (
        dp_next
        and deadline.limited
        and (deadline.remaining() or 0.0) * (1.0 if engine == "dp" or not capped else DP_SHARE)
        < counted_in + MARGIN
    )
    lap("setup")
    if plan != "dp" and engine != "milp":  # the DP does not fit the memory: a stage that does
        result = degraded(problem, plan, deadline, incumbent, max_memory_gb, began, stage)
        lap("degraded")
        used = plan
    elif deadline.expired(MARGIN) or dp_cannot_fit:  # no time left after warm start and count
        known = _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)
        stop_info = {"model": "not run", "count_seconds": counted_in}
        result = _stopped(problem, known, None, began, "portfolio", stop_info)
        used = "none"
    elif engine == "milp":
        result = milp(incumbent, deadline.remaining())
        lap("milp")
        used = "milp"
    elif engine == "dp" or not capped:
        alone = None if alone_states >= every_state else alone_states  # None: no cap
        dp_cap = max_states if capped else alone
        expect(every_state if dp_cap is None else dp_cap, deadline.remaining())
        watch = predict(
            "dp", incumbent, cheap, deadline.remaining(), every_state if dp_cap is None else dp_cap
        )
        result = solve_sop_dp(
            problem, deadline.remaining(), incumbent=incumbent, max_states=dp_cap, watch=watch
        )
        if watch is not None:  # stopped before the probe's end: what it saw
            watch.close()
        lap("dp")
        used = "dp"
    else:
        cuts_first = straight = False
        after_root: tuple[float, list[int]] | None = None  # the order known after the root
        watch = None
        if formulation == "cuts" and milp_ok:
            root_model, lagrange, incumbent, cuts_first = _root_stage(
                problem, deadline, incumbent, info, verbose
            )
            lap("root")
            if ROW_CREDIT and lagrange is not None:
                credit = root_model.row_credit(saved=True)
            if on_root is not None:
                on_root(cuts_first)
            root_bound = info["root_stage"]["bound"]
            lower = float(root_bound) if np.isfinite(root_bound) else cheap
            complete = bool(info["root_stage"].get("complete"))
            if not cuts_first and not root_closed():
                # the tree first where the trials would be skipped for it (TREE_FIRST)
                after_root = _known_order(
                    problem.cost, problem.closure, problem.start, problem.end, incumbent
                )
                cost_after = None if after_root is None else after_root[0]
                best = max(lower, cheap)
                straight = tree_first(True, complete, root_gap(cost_after, best))
            if straight and not TREE_FIRST_WINDOW:
                info["window"] = "skipped: the tree goes first (TREE_FIRST_WINDOW)"
            elif not cuts_first:
                window, window_bound = _window_stage(problem, deadline, incumbent, info, cheap)
                lap("window")
                if straight:  # the window's bound may narrow the gap below PROOF_GAP
                    best = max(best, window_bound)
                    straight = tree_first(True, complete, root_gap(cost_after, best))
            path = "cuts" if cuts_first or straight else "root+dp"
            watch = predict(path, incumbent, lower, deadline.share(DP_SHARE), max_states)
        if straight:  # the tree first (TREE_FIRST): the beams, the search on a wide gap, the tree
            peer = _tree_peer(problem, deadline, on_tree, info)  # starts while the beams run
            try:
                known = _beamed(problem, after_root, deadline, info)
                lap("beam")
                if known is not None:  # the beams' order, searched from on a wide gap
                    start = _stopped(problem, known, lower, began, "portfolio", {})
                    incumbent = start.solution
                    searched = _searched(
                        problem,
                        start,
                        deadline,
                        seed,
                        info,
                        best,
                        TREE_FIRST_SEARCH_SHARE,
                        min_gap=TREE_FIRST_SEARCH_GAP,
                    )
                    incumbent = searched.solution
                    if isinstance(info.get("ils"), dict):  # it ran
                        lap("search")
                if peer is not None:  # the tree and its peer: two of this model in memory
                    nonzeros = nonzero_count(problem.cost, problem.closure, problem.start, "cuts")
                    stage(2 * (BASE_BYTES + cut_engine_bytes(nonzeros, deadline.remaining())))
                handed, peer = peer, None
                result = milp(incumbent, deadline.remaining(), peer=handed)
            finally:
                if peer is not None:  # not handed on (an error before the tree)
                    peer.close()
            lap("milp")
            used = "milp"
            info["tree_first"] = True
        elif cuts_first:  # the root closed most of the gap: the cut engine gets the time
            result = milp(incumbent, deadline.remaining())
            lap("milp")
            used = "milp"
        else:
            # the proof stage first when the order known is already close to the root bound
            proved = proof(incumbent, None)
            lap("proof")
            if proved is not None and proved.solution is not None:
                incumbent = proved.solution
            share = deadline.share(DP_SHARE)
            used = "dp" if proved is None else "proof+dp"
            if proved is not None and proved.status != TIME_LIMIT:
                result = proved
                used = "proof"
            elif share is not None and share < setup_guess + MARGIN:
                # the root stage left too little for the DP's setup (chains-380-8-x0.01 at
                # 10 s, load 7: 0.7 s left, a 3.8 s setup, ended at 13-15 s): not started
                info["dp"] = f"skipped: {share:.2f} s for a {setup_guess:.2f} s setup"
                known = _known_order(
                    problem.cost, problem.closure, problem.start, problem.end, incumbent
                )
                bound = info["root_stage"]["bound"]
                stop_info = {"model": "not run", "setup_seconds": setup_guess}
                result = _stopped(problem, known, bound, began, "portfolio", stop_info)
                used = "root" if proved is None else "proof"
            else:
                expect(max_states, share, nonzeros=held())
                result = solve_sop_dp(
                    problem,
                    share,
                    incumbent=incumbent,
                    max_states=max_states,
                    lagrange=lagrange,
                    credit=credit,
                    watch=watch,
                    state_lp=state_lp(),
                    window=window,
                )
                if watch is not None:  # stopped before the probe's end: what it saw
                    watch.close()
                lap("dp")
            if result.status == TIME_LIMIT and not deadline.expired(MARGIN):
                root_bound = info.get("root_stage", {}).get("bound", cheap)
                lower = float(root_bound) if np.isfinite(root_bound) else cheap
                result = _searched(problem, result, deadline, seed, info, lower)
                lap("search")
            if result.status == TIME_LIMIT and proved is None and not deadline.expired(MARGIN):
                # the first stages brought the order close to the bound: the proof stage now,
                # or its trial cutoffs where the gap is still wide (TRIAL_CUTOFFS)
                proved = proof(
                    result.solution,
                    result.bound,
                    trials_ok=trials_wanted(
                        milp_ok and formulation == "cuts",
                        bool(info.get("root_stage", {}).get("complete")),
                    ),
                    setup=result.info.get("setup_seconds", 0.0),
                )
                lap("proof")
                if proved is not None:
                    used += "+proof"
                    if proved.status != TIME_LIMIT:
                        result = proved
            # a second stage sets up as the first did (its bounds, its first layers; seconds under
            # load, outside the DP's clock): started only when its share covers twice that
            setup = result.info.get("setup_seconds", 0.0)
            setups.append(setup)
            # without the MILP (above the memory limit) the second stage gets all the time left
            second_share = deadline.share(SECOND_STAGE_SHARE if milp_ok else 1.0)
            short = second_share is not None and second_share < 2 * setup + MARGIN
            if result.status == TIME_LIMIT and short:
                info["second_stage"] = (
                    f"skipped: {second_share:.2f} s left for a {setup:.2f} s setup"
                )
            elif result.status == TIME_LIMIT and formulation == "cuts" and _far(result):
                info["second_stage"] = "skipped: the DP's gap is wide, the cut engine gets the time"
            elif result.status == TIME_LIMIT and formulation == "cuts" and root_closed():
                # the DP's gap is narrow only by the root's prices (saved when its loop is cut):
                # the root closed most of the gap, the cut engine is the stage that closes it
                info["second_stage"] = "skipped: the root closed the gap (CUTS_FIRST_SHARE)"
            elif result.status == TIME_LIMIT and not deadline.expired(MARGIN):
                # second stage: the bound on both price sets (stronger, 1.5-1.7x slower per
                # state, so not the first choice) with more states, from the best order so far
                first = result
                known = first.solution if first.solution is not None else incumbent
                expect(second_states, second_share, nonzeros=held())
                second = solve_sop_dp(
                    problem,
                    second_share,
                    incumbent=known,
                    max_states=second_states,
                    both_prices=True,
                    lagrange=lagrange,
                    credit=credit,
                    state_lp=state_lp(),
                    window=window,
                )
                lap("second_dp")
                used += "+dp"
                result = _combine(first, second)
            if result.status == TIME_LIMIT and not deadline.expired(MARGIN):
                info.update({f"dp_{k}": v for k, v in result.info.items()})
                known = result.solution if result.solution is not None else incumbent
                result = milp(known, deadline.remaining(), dp_result=result)
                lap("milp")
                used += "+milp"
            if proved is not None and proved.status == TIME_LIMIT:
                # a proof stage that gave up: its order and bound join at the end, the later
                # stages' rules (CUTS_SECOND_STAGE_GAP) having read their own
                result = _combine(proved, result)
    # a degraded stage has used the limit already; "none": too little time for a stage
    full = (plan == "dp" or engine == "milp") and used != "none"
    if full and result.status == TIME_LIMIT and deadline.limited and not deadline.expired(MARGIN):
        # the stages ended before the limit without a proof: go on while it lasts (a DP with
        # more states while they fit the memory, unless the caller fixed them; wider beams)
        grow = engine != "dp" and plan == "dp"
        last_cap = max(second_states, max_states) if grow else 1 << 62
        setup = max(setups, default=counted_in)  # no DP stage ran: as long as the count
        result = use_the_rest(problem, result, deadline, last_cap, max_memory_gb, setup, stage)
        lap("rest")
    if result.status == TIME_LIMIT and np.isfinite(window_bound):
        result = _raised(result, window_bound)
    stage(BASE_BYTES)  # the process itself, whatever ran
    # the stages' upper estimate (each stage's, before it ran); the reported one is the
    # prediction made before the stages, where the rule's paths made one
    info["memory_stages"] = info["memory_estimate"]
    if predicted:
        info["memory_estimate"] = predicted[0]
    lap("other")
    info["stage_seconds"] = seconds
    return result.replace(
        runtime=time.perf_counter() - began,
        method="exact-sop",
        info={**result.info, **info, "engine": used},
    )
