"""The DFJ loop of chapter 2: (2.2)–(2.4) on one live HiGHS model, (2.5) rows added lazily.

:class:`DfjModel` passes (2.2)–(2.4) once to HiGHS and adds (2.5) rows in place;
:meth:`DfjModel.root` solves the root LP with exact separation
(:func:`~taopt.models.routing.separation.separate_subtours`), :func:`dfj_root` returns it,
and :func:`_solve_dfj` runs the MIP rounds on a reduced-cost core until the gap is closed
(see :func:`taopt.models.routing.solve.solve_routing`, Notes).

References
----------
Thesis §2.2.1, (2.5).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from taopt.errors import FeasibilityError, SolverError
from taopt.models.highs import HighsModel
from taopt.models.routing.compact import (
    ASSIGNMENT_SECONDS_PER_CUBE,
    _first_incumbent,
    _highs_limit,
    _solve_compact,
)
from taopt.models.routing.formulation import (
    RoutingModel,
    _check,
    arc_list,
    assignment_bound,
    build,
    decode,
    entry_bound,
    repair,
)
from taopt.models.routing.separation import (
    blossom_arcs,
    cut_rows,
    lifted_cycle_arcs,
    separate_blossoms,
    separate_lifted_cycles,
    separate_subtours,
)
from taopt.result import Routes, Solution, finish
from taopt.routing.problem import AssignmentProblem, evaluate_routes
from taopt.routing.subtours import new_subsets
from taopt.status import OPTIMALITY_TOLERANCE, relative_gap

#: First core of the DFJ loop: at most this many arcs per point (n + m), by reduced cost.
CORE_SIZE = 4


#: HiGHS options of the DFJ rounds; the optimum and its proof depend on neither.
#: A smaller cut pool than HiGHS's default (10000) roughly halved the time of the hard
#: rounds (p43, ry48p, n120m5; benchmarks/bench_routing_exact.py). No restart of the
#: root after HiGHS fixes columns by reduced cost: a round on a core is a small MIP whose
#: time went mostly to repeated root work (four restarts and five nodes in a 6 s round of
#: a 57-target chapter-3 class); without restarts chapter 3's n90m10 classes took 0.60x
#: the CPU time and the slowest chapter-2 scenarios 0.72x, TSPLIB the same
#: (docs/benchmarks.md, "No restarts in the DFJ rounds").
MIP_OPTIONS = {"mip_pool_soft_limit": 500, "mip_allow_restart": False}


#: Seconds per arc to build :class:`DfjModel` (arrays and HiGHS's ``passModel``), and per
#: arc before HiGHS's simplex first checks its clock (its setup of the LP): upper
#: estimates measured on a loaded 2-core machine (about 1 and 3.5 µs for n = 1000,
#: benchmarks/bench_routing_exact.py --limit). Under a time limit a stage is not started
#: when its estimate exceeds the time left: the incumbent and the bounds proven so far
#: are returned instead (status "time_limit").
BUILD_SECONDS_PER_ARC = 2e-6


#: Seconds per arc before HiGHS's simplex first checks its clock (see above).
LP_SECONDS_PER_ARC = 4e-6


#: Rounds of the root LP that may add lifted rows once no (2.5) row is violated; 0 switches
#: them off.
LIFTED_ROUNDS = 10


#: The families of lifted rows separated at the root: ``"dk"`` (D_k^+ / D_k^-,
#: :func:`~taopt.models.routing.separation.lifted_cycle_arcs`) and ``"blossom"``
#: (2-matching inequalities on σ + σ^T, :func:`~taopt.models.routing.separation.blossom_arcs`).
LIFTED_FAMILIES = ("blossom",)


#: The lifted rows are kept only when they raise the root bound L (the DFJ bound before
#: them) by at least this fraction of ``|L|``; otherwise the model is put back as it was
#: before them. Rows that barely move the bound only slow HiGHS's rounds down (p43, ry48p,
#: ftv55: +0–0.2 % bound, +30 % time with them; chapter 3's n90m10 classes: +0.4–1 % bound,
#: up to −40 % time; benchmarks/bench_routing_exact.py, docs/benchmarks.md, Chapter 3).
LIFTED_MIN_GAIN = 0.0025


#: Seconds that must be left under a time limit for ``improve`` to be called (a local
#: search of 100 moves takes about 0.75 s at n400m50).
IMPROVE_MIN_SECONDS = 1.0


#: Compact formulation that finishes a DFJ loop which stalls with an open gap.
FALLBACK_SEC = "flow"


#: Arcs whose σ is at most this are left out of a traced point (``trace=True``).
TRACE_ZERO = 1e-9


def _finite(value: Any) -> float | None:
    """``value`` as a float, or None when it is not finite (JSON has no infinity)."""
    value = float(value)
    return value if np.isfinite(value) else None


def trace_point(dfj: DfjModel, values: np.ndarray | None) -> list[list[float]]:
    """The nonzero arcs of a point as ``[tail, head, σ]`` (σ rounded to 1e-9), for a trace."""
    if values is None:
        return []
    used = np.flatnonzero(np.asarray(values) > TRACE_ZERO)
    return [[int(dfj.tails[a]), int(dfj.heads[a]), round(float(values[a]), 9)] for a in used]


def _sets(subsets: Any) -> list[list[int]]:
    """Subsets as sorted lists of ints (JSON-able, comparable)."""
    return [sorted(int(v) for v in subset) for subset in subsets]


def _lifted_plain(cut: tuple) -> dict[str, Any]:
    """A lifted row (:meth:`DfjModel.add_lifted`) as JSON-able data."""
    if cut[0] == "blossom":
        return {
            "kind": "blossom",
            "handle": sorted(int(v) for v in cut[1]),
            "teeth": [[int(a), int(b)] for a, b in cut[2]],
        }
    return {"kind": f"D_k{cut[0]}", "sequence": [int(v) for v in cut[1]]}


@dataclass
class RootRelaxation:
    """The DFJ LP relaxation at the root: (2.2)–(2.4) plus separated (2.5) rows.

    Attributes
    ----------
    cuts : list of tuple
        The subsets S whose (2.5) rows were added (every one a valid row).
    value : float
        HiGHS's LP value with those rows (``-inf`` if no LP finished).
    bound : float
        A proven lower bound on the optimum of (2.2)–(2.5) from the LP's row
        duals (:meth:`taopt.models.highs.HighsModel.lagrangian_bound`); equal
        to ``value`` up to solver tolerances.
    reduced_costs : ndarray
        Reduced cost ``d_a`` of every arc: a solution that uses arc a costs at
        least ``bound + d_a``.
    values : ndarray or None
        σ at the LP optimum.
    rounds : int
        LPs solved.
    complete : bool
        The last separation found no violated (2.5) row: ``value`` is the LP
        bound of the full (2.2)–(2.5).
        With lifted rows kept (:meth:`DfjModel.root`) the LP is stronger and
        ``value`` is at least that bound.
    """

    cuts: list[tuple[int, ...]]
    value: float
    bound: float
    reduced_costs: np.ndarray
    values: np.ndarray | None
    rounds: int
    complete: bool


class DfjModel:
    """(2.2)–(2.4) passed once to one live HiGHS model; (2.5) rows added in place.

    The rows of :func:`build` (no cuts) are written straight into sparse
    arrays — column a is σ of arc ``tails[a] -> heads[a]``, with a 1 in row
    ``heads[a]`` of (2.3) and in row ``n + tails[a]`` of (2.4) — and passed to
    HiGHS by :meth:`taopt.models.highs.HighsModel.from_arrays`: the same model
    cvxpy would compile, without cvxpy's compilation (about 20 s for the
    million arcs of n = 1000, against a fraction of a second here; the
    cvxpy model is :attr:`formulation`, built on demand). Afterwards every
    (2.5) row found, at the root LP or in a MIP round, is added to the same
    ``highspy.Highs`` object; arcs are switched off and on through their upper
    bounds, and a MIP start is passed with ``Highs.setSolution``.
    """

    def __init__(self, problem: AssignmentProblem, verbose: bool = False) -> None:
        self.problem = problem
        n, m = problem.n, problem.m
        size = n + m
        self.tails, self.heads = arc_list(problem)
        n_arcs = len(self.tails)
        self.arcs = np.arange(n_arcs)
        # (2.3) rows 0..n-1: sum_i sigma_ij = 1; (2.4) rows n..2n+m-1: sum_j sigma_ij <= 1
        rows = np.empty(2 * n_arcs, dtype=np.int64)
        rows[0::2] = self.heads
        rows[1::2] = n + self.tails
        matrix = sp.csc_matrix(
            (np.ones(2 * n_arcs), rows, np.arange(0, 2 * n_arcs + 1, 2)),
            shape=(n + size, n_arcs),
        )
        self.model = HighsModel.from_arrays(
            cost=problem.cost[self.tails, self.heads],  # (2.2)
            matrix=matrix,
            lower=np.concatenate([np.ones(n), np.full(size, -np.inf)]),
            upper=np.ones(n + size),
            column_lower=np.zeros(n_arcs),
            column_upper=np.ones(n_arcs),
            integers=self.arcs,
            verbose=verbose,
        )
        self.cuts: list[tuple[int, ...]] = []
        self._known: set[tuple[int, ...]] = set()
        #: lifted cycle rows in the model, as ``(kind, sequence)`` (:meth:`add_lifted`)
        self.lifted: list[tuple] = []
        self._known_lifted: set[tuple] = set()
        self.arc_index = np.full((size, n), -1, dtype=np.int64)
        self.arc_index[self.tails, self.heads] = np.arange(n_arcs)
        self._formulation: RoutingModel | None = None
        #: the rounds recorded when a trace is asked for (``trace=True``), else None: one
        #: dict per LP of :meth:`root` and per MIP round (:func:`_solve_dfj`)
        self.trace: list[dict[str, Any]] | None = None

    @property
    def formulation(self) -> RoutingModel:
        """The same (2.2)–(2.4) as a labelled cvxpy model (:func:`build`), built on first use."""
        if self._formulation is None:
            self._formulation = build(self.problem, "dfj")
        return self._formulation

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = new_subsets(cuts, self._known)
        if new:
            rows, lower, upper = cut_rows(self.problem, new, self.tails, self.heads)
            full = sp.csr_matrix(
                (rows.data, self.arcs[rows.indices], rows.indptr),
                shape=(rows.shape[0], self.model.n_columns),
            )
            self.model.add_rows(full, lower, upper)
            self.cuts.extend(new)
        return len(new)

    def add_lifted(self, cuts: list[tuple]) -> int:
        """Add the lifted rows not in the model yet; returns how many.

        A cut is ``("+", sequence)`` or ``("-", sequence)`` (``D_k^±``,
        :func:`lifted_cycle_arcs`) or ``("blossom", handle, teeth)`` (:func:`blossom_arcs`).
        """
        new = [cut for cut in cuts if cut not in self._known_lifted]
        if not new:
            return 0
        n = self.problem.n
        rows, columns, data, upper = [], [], [], []
        for r, cut in enumerate(new):
            if cut[0] == "blossom":
                arcs, rhs = blossom_arcs(cut[1], cut[2])
            else:
                arcs, rhs = lifted_cycle_arcs(cut[0], cut[1]), len(cut[1]) - 1.0
            arcs = [(a, b, c) for a, b, c in arcs if b < n]  # no arc enters a start point
            rows += [r] * len(arcs)
            columns += [self.arcs[self.arc_index[tail, head]] for tail, head, _ in arcs]
            data += [float(c) for _, _, c in arcs]
            upper.append(rhs)
        matrix = sp.csr_matrix((data, (rows, columns)), shape=(len(new), self.model.n_columns))
        self.model.add_rows(matrix, None, np.asarray(upper))
        self._known_lifted.update(new)
        self.lifted.extend(new)
        return len(new)

    def _rollback(self, n_rows: int, n_cuts: int) -> None:
        """Delete every row added after the model had ``n_rows`` rows and ``n_cuts`` cuts."""
        extra = self.model.n_rows - n_rows
        if extra > 0:
            rows = np.arange(n_rows, n_rows + extra, dtype=np.int32)
            self.model.highs.deleteRows(extra, rows)
            # HighsModel keeps the rows in blocks (one per add_rows) for its Lagrangian
            # bound: drop the blocks added since, so the two stay in step
            blocks, total, kept = self.model._row_blocks, 0, 0
            for block in blocks:
                if total + block[0].shape[0] > n_rows:
                    break
                total, kept = total + block[0].shape[0], kept + 1
            del blocks[kept:]
        for subset in self.cuts[n_cuts:]:
            self._known.discard(subset)
        del self.cuts[n_cuts:]
        self._known_lifted.clear()
        self.lifted.clear()

    def _trace_cuts(self, n_known: int) -> None:
        """Record the (2.5) rows added since the model had ``n_known`` in the last round."""
        if self.trace is not None and self.trace:
            self.trace[-1]["cuts"] += _sets(self.cuts[n_known:])

    def arc_values(self, solution: np.ndarray | None = None) -> np.ndarray:
        """σ of every arc in the last solution (or in ``solution``, a full column vector)."""
        if solution is None:
            return np.asarray(self.model.highs.getSolution().col_value, dtype=float)[self.arcs]
        return np.asarray(solution, dtype=float)[self.arcs]

    def start_vector(self, routes: list[list[int]]) -> np.ndarray:
        """The full column vector of σ for ``routes`` (a MIP start)."""
        vector = np.zeros(self.model.n_columns)
        vector[self.arcs[self.route_arcs(routes)]] = 1.0
        return vector

    def route_arcs(self, routes: list[list[int]]) -> np.ndarray:
        """Arc indices used by ``routes``."""
        n = self.problem.n
        arcs: list[int] = []
        for k, route in enumerate(routes):
            points = [n + k, *route]
            arcs.extend(self.arc_index[points[:-1], points[1:]])
        return np.asarray(arcs, dtype=np.int64)

    def root(
        self,
        budget: float | None = None,
        max_rounds: int | None = None,
        lifted: int | None = None,
    ) -> RootRelaxation:
        """Solve the DFJ LP, separating (2.5) exactly (:func:`separate_subtours`) until none is left.

        The model is switched to its LP relaxation for the loop and back to
        binary σ at the end. Each re-solve after new rows starts from the last
        basis. Stops early after ``budget`` seconds or ``max_rounds`` LPs
        (``complete`` False).

        Once no (2.5) row is violated, up to ``lifted`` (default :data:`LIFTED_ROUNDS`)
        more rounds add lifted rows (:data:`LIFTED_FAMILIES`) and separate (2.5) again,
        while each raises the bound by at least a tenth of :data:`LIFTED_MIN_GAIN` ``|L|``.
        The lifted rows are kept only if they raise the bound L by at least
        :data:`LIFTED_MIN_GAIN` ``|L|``; otherwise every row added since is deleted and
        the LP before them returned.
        """
        began = time.perf_counter()
        deadline = None if budget is None else began + budget
        self.model.relax(True)
        rounds, value, complete = 0, -np.inf, False
        lifted_rounds = LIFTED_ROUNDS if lifted is None else lifted
        snapshot: tuple[Any, ...] | None = (
            None  # the model and LP when no (2.5) row was violated the first time
        )
        last_bound = -np.inf  # the bound when no (2.5) row was violated the last time
        bound, reduced, values = -np.inf, np.zeros(len(self.arcs)), None
        try:
            while max_rounds is None or rounds < max_rounds:
                left = None if budget is None else budget - (time.perf_counter() - began)
                if left is not None and left < LP_SECONDS_PER_ARC * len(self.arcs):
                    break  # HiGHS would not even reach its first clock check in time
                rounds += 1
                run = self.model.solve(time_limit=left)
                if run.solver_status != "optimal" or run.objective is None:
                    if run.solver_status not in ("user_limit",):
                        raise SolverError(
                            f"the DFJ LP relaxation ended with status {run.solver_status!r}"
                        )
                    break
                value = run.objective
                values = self.arc_values()
                bound, full_reduced = self.model.lagrangian_bound()
                reduced = full_reduced[self.arcs]
                found = separate_subtours(
                    self.problem, self.tails, self.heads, values, deadline=deadline
                )
                n_known = len(self.cuts)
                if self.trace is not None:
                    self.trace.append(
                        {
                            "round": len(self.trace) + 1,
                            "stage": "root",
                            "value": _finite(value),
                            "bound": _finite(bound),
                            "arcs": trace_point(self, values),
                            "subtours": _sets(found),
                            "cuts": [],
                            "lifted": [],
                        }
                    )
                if deadline is not None and time.perf_counter() >= deadline:
                    self.add_cuts(found)  # valid rows, but the separation may be unfinished
                    self._trace_cuts(n_known)
                    break
                added = self.add_cuts(found)
                self._trace_cuts(n_known)
                if added:
                    complete = False
                    continue
                complete = True  # no (2.5) row violated: the DFJ bound
                if snapshot is None:
                    snapshot = (self.model.n_rows, len(self.cuts), value, bound, reduced, values)
                    snapshot += (rounds,)
                elif bound - last_bound < 0.1 * LIFTED_MIN_GAIN * abs(snapshot[3]):
                    break  # the last lifted round barely moved the bound: stop here
                last_bound = bound
                if lifted_rounds <= 0 or (deadline is not None and time.perf_counter() >= deadline):
                    break
                lifted_rounds -= 1
                lifted_cuts: list[tuple] = []
                if "dk" in LIFTED_FAMILIES:
                    lifted_cuts += separate_lifted_cycles(
                        self.problem, self.tails, self.heads, values
                    )
                if "blossom" in LIFTED_FAMILIES:
                    lifted_cuts += separate_blossoms(self.problem, self.tails, self.heads, values)
                n_lifted = len(self.lifted)
                if not self.add_lifted(lifted_cuts):
                    break
                if self.trace is not None:
                    self.trace[-1]["lifted"] = [_lifted_plain(c) for c in self.lifted[n_lifted:]]
            if snapshot is not None and self.lifted and complete:
                n_rows, n_cuts, *before = snapshot
                closed = bound - before[1]
                if closed < LIFTED_MIN_GAIN * abs(before[1]):
                    self._rollback(n_rows, n_cuts)
                    value, bound, reduced, values, rounds = before
                    if self.trace is not None:  # the rounds after the snapshot were undone
                        root_rounds = [r for r in self.trace if r["stage"] == "root"]
                        for record in root_rounds[rounds:]:
                            record["discarded"] = True
                        root_rounds[rounds - 1]["lifted"] = []
        finally:
            self.model.relax(False)
        return RootRelaxation(
            cuts=list(self.cuts),
            value=value,
            bound=bound,
            reduced_costs=reduced,
            values=values,
            rounds=rounds,
            complete=complete,
        )


def dfj_root(problem: AssignmentProblem, time_limit: float | None = None) -> RootRelaxation:
    """The root DFJ LP of (2.2)–(2.5) with its exactly separated (2.5) rows.

    Every returned subset S is a row of (2.5), so any feasible solution
    satisfies ``Σ_{i,j∈S} σ_ij ≤ |S| − 1``.

    Example
    -------
    >>> import numpy as np
    >>> from taopt import AssignmentProblem
    >>> cost = np.array([[0, 1, 9], [1, 0, 9], [5, 6, 0.0]])
    >>> root = dfj_root(AssignmentProblem(cost, 2))
    >>> root.cuts, root.value
    ([(0, 1)], 6.0)
    """
    _check(problem, "dfj")
    return DfjModel(problem).root(budget=time_limit, lifted=0)


def rounded_routes(
    problem: AssignmentProblem, dfj: DfjModel, values: np.ndarray
) -> list[list[int]] | None:
    """Routes near a fractional σ (the root LP's point): an incumbent for the MIP rounds.

    The assignment (:func:`scipy.optimize.linear_sum_assignment`) that gives every target one
    predecessor and every point at most one successor with the most LP weight (ties to the
    cheaper arc) is an integral point of (2.3)-(2.4); its subtours are patched into the
    routes (:func:`~taopt.models.routing.formulation.repair`). When the LP point is
    already one set of routes this returns them, and the incumbent then meets the root bound
    without a MIP round (rbg403: the root LP is the optimum).
    """
    from scipy.optimize import linear_sum_assignment

    n, size = problem.n, problem.n + problem.m
    tails, heads = dfj.tails, dfj.heads
    cost = problem.cost[tails, heads]
    scale = float(np.abs(cost).max()) or 1.0
    forbidden, bonus = -1e9, float(size + 1)
    weight = np.full((size, n + size), forbidden)
    # an arc's weight: its LP value, a small tie-break to the cheaper arc, and a bonus that
    # makes covering every target worth more than any choice of weights
    weight[tails, heads] = bonus + values - 1e-3 * cost / scale
    outflow = np.bincount(tails, weights=values, minlength=size)
    weight[np.arange(size), n + np.arange(size)] = 1.0 - outflow  # point i has no successor
    rows, columns = linear_sum_assignment(weight, maximize=True)
    chosen = columns < n
    if int(chosen.sum()) != n or (weight[rows, columns] <= forbidden / 2).any():
        return None
    point = np.zeros(len(tails))
    point[dfj.arc_index[rows[chosen], columns[chosen]]] = 1.0
    try:
        routes, subtours = decode(problem, dfj, point)
    except SolverError:
        return None
    return repair(problem, routes, subtours) if subtours else routes


class _Search:
    """The state of one :func:`_solve_dfj` call: the incumbent (best routes and value), the
    proven lower bound, the clock and the improver."""

    def __init__(
        self,
        problem: AssignmentProblem,
        time_limit: float | None,
        started: float,
        improve: Any,
        given: list[list[int]] | None,
    ) -> None:
        self.problem = problem
        self.time_limit = time_limit
        self.started = started
        self.improve = improve
        self.best_routes, self.best_value = _first_incumbent(problem, given)
        self.best_bound = -np.inf
        self.improved = 0

    def remaining(self) -> float | None:
        """Seconds left (None without a limit)."""
        if self.time_limit is None:
            return None
        return self.time_limit - (time.perf_counter() - self.started)

    def improved_routes(
        self, routes: Routes | list[list[int]] | None
    ) -> tuple[list[list[int]], float] | None:
        """``improve(problem, routes)`` and its value, if time allows and it is feasible."""
        left = self.remaining()
        if (
            self.improve is None
            or routes is None
            or (left is not None and left < IMPROVE_MIN_SECONDS)
        ):
            return None
        better = [[int(t) for t in route] for route in self.improve(self.problem, routes)]
        try:
            return better, evaluate_routes(self.problem, better)
        except FeasibilityError as exc:
            raise SolverError(f"improve returned routes that are not feasible: {exc}") from exc

    def offer(self, routes: Routes | list[list[int]] | None) -> None:
        """Improve ``routes``; keep the answer if it beats the incumbent."""
        found = self.improved_routes(routes)
        if found is not None and found[1] < self.best_value:
            (self.best_routes, self.best_value), self.improved = found, self.improved + 1

    def keep(self, routes: list[list[int]], value: float) -> None:
        """Keep ``routes`` (of total ``value``) if they beat the incumbent."""
        if value < self.best_value:
            self.best_routes, self.best_value = routes, value

    def finish(self, stopped_by: str, info: dict[str, Any]) -> Solution:
        """The answer by the one status rule: optimal only when proven within 1e-6."""
        return finish(
            self.problem,
            None if self.best_routes is None else Routes(self.best_routes),
            method="exact-dfj",
            stop=stopped_by,
            bound=self.best_bound,
            runtime=time.perf_counter() - self.started,
            info=info,
        )


class _Core:
    """The arcs the MIP rounds run on: those of small reduced cost at the root, at most
    :data:`CORE_SIZE` per point at first (all arcs if the root LP did not finish)."""

    def __init__(self, dfj: DfjModel, root: RootRelaxation, n: int, m: int) -> None:
        self.dfj = dfj
        self.root = root
        if np.isfinite(root.bound):
            size = min(CORE_SIZE * (n + m), len(dfj.arcs))
            self.cap = float(np.partition(root.reduced_costs, size - 1)[size - 1])
        else:
            self.cap = np.inf
        self.mask = np.ones(len(dfj.arcs), dtype=bool)

    def resize(self, best_value: float, best_routes: list[list[int]]) -> bool:
        """Core := arcs with ``d_a <= min(UB − L, cap)``, plus the incumbent's. Changed?

        Arcs with ``d_a > UB − L`` cannot be in a solution better than the incumbent
        (``UB``); ``cap`` keeps the first rounds small while UB is still poor.
        """
        root, dfj, core = self.root, self.dfj, self.mask
        if not np.isfinite(root.bound):
            return False
        slack = 1e-9 * max(1.0, abs(best_value))
        wanted = root.reduced_costs <= min(best_value - root.bound + slack, self.cap)
        wanted[dfj.route_arcs(best_routes)] = True
        on, off = wanted & ~core, core & ~wanted
        dfj.model.set_upper(dfj.arcs[on], 1.0)
        dfj.model.set_upper(dfj.arcs[off], 0.0)
        core[:] = wanted
        return bool(on.any() or off.any())

    def outside_bound(self) -> float:
        """Proven bound on every solution using an arc outside the core."""
        if self.mask.all():
            return np.inf
        return self.root.bound + float(self.root.reduced_costs[~self.mask].min())


class _Rounds:
    """MIP rounds on the core, (2.5) rows from every solution HiGHS reports; each answer
    (its subtours patched) a candidate incumbent, the round's best one improved."""

    def __init__(self, search: _Search, dfj: DfjModel, core: _Core) -> None:
        self.search = search
        self.dfj = dfj
        self.core = core
        self.harvested: list[tuple[int, ...]] = []
        self.candidates: list[tuple[float, list[list[int]]]] = []

    def harvest(self, solution: np.ndarray) -> None:
        """HiGHS's callback on each solution it finds: its subtours, its patched routes."""
        problem, dfj = self.search.problem, self.dfj
        values = dfj.arc_values(solution)
        try:
            routes, subtours = decode(problem, dfj, values)
        except SolverError:  # not an integral point of (2.3)-(2.4): nothing to learn
            return
        if subtours:
            self.harvested.extend(tuple(sorted(c)) for c in subtours)
            routes = repair(problem, routes, subtours)
        self.candidates.append((evaluate_routes(problem, routes), routes))

    def run(self, mip_gap: float, max_rounds: int) -> tuple[int, str, str, bool]:
        """The rounds until the gap closes or a limit; returns (rounds, HiGHS's last status,
        why they stopped, whether they stalled with an open gap)."""
        search, dfj, core = self.search, self.dfj, self.core
        problem = search.problem
        target_gap = max(float(mip_gap), OPTIMALITY_TOLERANCE)
        rounds = 0
        solver_status, stopped_by = "", "time_limit"
        while True:
            if relative_gap(search.best_value, min(search.best_bound, search.best_value)) <= (
                target_gap
            ):
                # the incumbent already meets the bound (the rounded root point)
                gap = relative_gap(search.best_value, min(search.best_bound, search.best_value))
                stopped_by = "optimal" if gap <= OPTIMALITY_TOLERANCE else "mip_gap"
                break
            left = search.remaining()
            if left is not None and left < LP_SECONDS_PER_ARC * int(core.mask.sum()):
                stopped_by = "time_limit"  # HiGHS would overrun the limit before its first check
                break
            rounds += 1
            dfj.model.set_start(dfj.start_vector(search.best_routes))
            self.harvested.clear()
            self.candidates.clear()
            run = dfj.model.solve(
                time_limit=_highs_limit(left),
                mip_rel_gap=mip_gap,
                on_solution=self.harvest,
                options=MIP_OPTIONS,
            )
            solver_status = run.solver_status
            if solver_status not in ("optimal", "user_limit"):
                raise SolverError(f"HiGHS returned status {solver_status!r} on the DFJ model")
            # every solution stays in the core (cost >= HiGHS's bound) or leaves it
            core_bound = run.bound if run.bound is not None else -np.inf
            search.best_bound = max(search.best_bound, min(core_bound, core.outside_bound()))
            for value, routes in self.candidates:
                search.keep(routes, value)
            subtours: list[list[int]] = []
            if run.has_point:
                routes, subtours = decode(problem, dfj, dfj.arc_values())
                candidate = repair(problem, routes, subtours) if subtours else routes
                value = evaluate_routes(problem, candidate)
                self.candidates.append((value, candidate))
                search.keep(candidate, value)
            if self.candidates:  # the round's best answer, improved (often the next optimum)
                search.offer(min(self.candidates, key=lambda pair: pair[0])[1])
            n_known = len(dfj.cuts)
            if dfj.trace is not None:
                dfj.trace.append(
                    {
                        "round": len(dfj.trace) + 1,
                        "stage": "mip",
                        "value": _finite(run.objective) if run.has_point else None,
                        "bound": _finite(search.best_bound),
                        "incumbent": _finite(search.best_value),
                        "core_arcs": int(core.mask.sum()),
                        "arcs": trace_point(dfj, dfj.arc_values()) if run.has_point else [],
                        "subtours": _sets(subtours),
                        "cuts": [],
                    }
                )
            dfj.add_cuts([*map(tuple, subtours), *self.harvested])
            dfj._trace_cuts(n_known)
            stopped_by = run.stopped_by
            best_value = search.best_value
            if relative_gap(best_value, min(search.best_bound, best_value)) <= target_gap:
                break  # proven: "optimal", or "mip_gap" for a loose gap
            if run.stopped_by in ("time_limit", "solver_limit"):
                break  # a limit: the incumbent stands with the bound proven so far
            if rounds >= max_rounds:
                stopped_by = "max_rounds"
                break
            # only arcs that can still improve on the incumbent stay in the model; once
            # the core's own optimum has no cycle, every such arc comes in
            if not subtours:
                core.cap = np.inf
            if not run.has_point or (
                not core.resize(search.best_value, search.best_routes) and not subtours
            ):
                # Nothing left to learn, yet the gap is open: the round's answer contradicts
                # the proof (a solver fault, as HiGHS 1.16's MIP starts in a presolved space
                # were before HighsModel checked them). A compact model closes it.
                return rounds, solver_status, stopped_by, True
        return rounds, solver_status, stopped_by, False


def _solve_dfj(
    problem: AssignmentProblem,
    time_limit: float | None,
    mip_gap: float,
    verbose: bool,
    max_rounds: int,
    given: list[list[int]] | None,
    started: float,
    improve: Any = None,
    trace: bool = False,
) -> Solution:
    """The DFJ loop (module docstring): first bounds, the root LP with exact separation (at
    most half of a time limit), the reduced-cost core, MIP rounds on it (:class:`_Rounds`)
    and, if they stall with an open gap, the compact :data:`FALLBACK_SEC` model.

    ``trace``: ``info["trace"]`` holds every round (:func:`~taopt.models.routing.solve_routing`).
    """
    search = _Search(problem, time_limit, started, improve, given)
    search.offer(search.best_routes)
    n, m = problem.n, problem.m
    search.best_bound = entry_bound(problem)
    left = search.remaining()
    if left is None or left > ASSIGNMENT_SECONDS_PER_CUBE * n**2 * (n + m):
        search.best_bound = max(search.best_bound, assignment_bound(problem))
    n_arcs = (n + m) * n - n
    left = search.remaining()
    if left is not None and left < BUILD_SECONDS_PER_ARC * n_arcs:
        # no time to build the model: the incumbent with the bounds proven so far
        info: dict[str, Any] = {"rounds": 0, "cuts": 0, "arcs": n_arcs, "stopped_by": "time_limit"}
        info.update(solver_status="", stage="build", mip_gap=mip_gap)
        if trace:
            info["trace"] = new_trace(problem, [])
        return search.finish("time_limit", info)
    dfj = DfjModel(problem, verbose=verbose)
    if trace:
        dfj.trace = []
    # 1. root LP with exact separation; at most half of a time limit
    budget = search.remaining()
    root = dfj.root(budget=None if budget is None else 0.5 * budget)
    root_cuts = len(dfj.cuts)
    search.best_bound = max(search.best_bound, root.bound)
    if root.values is not None:  # the root point rounded: often the optimum itself
        rounded = rounded_routes(problem, dfj, root.values)
        if rounded is not None:
            search.keep(rounded, evaluate_routes(problem, rounded))
            search.offer(rounded)
    # 2. the core; 3. MIP rounds on it
    core = _Core(dfj, root, n, m)
    core.resize(search.best_value, search.best_routes)
    rounds, solver_status, stopped_by, stall = _Rounds(search, dfj, core).run(mip_gap, max_rounds)
    if stall:
        fallback = _solve_compact(
            problem, FALLBACK_SEC, time_limit, mip_gap, verbose, search.best_routes, started
        )
        if fallback.routes is not None:
            search.keep(fallback.routes, fallback.objective)
        if fallback.bound is not None:
            search.best_bound = max(search.best_bound, fallback.bound)
        stopped_by = fallback.info["stopped_by"]
        solver_status = fallback.info["solver_status"]
        if dfj.trace is not None and fallback.routes is not None:
            fallback_point = np.zeros(len(dfj.arcs))
            fallback_point[dfj.route_arcs(fallback.routes)] = 1.0
            dfj.trace.append(
                {
                    "round": len(dfj.trace) + 1,
                    "stage": "fallback",
                    "value": _finite(fallback.objective),
                    "bound": _finite(search.best_bound),
                    "incumbent": _finite(search.best_value),
                    "arcs": trace_point(dfj, fallback_point),
                    "subtours": [],
                    "cuts": [],
                }
            )
    info = {
        "rounds": rounds,
        "cuts": len(dfj.cuts),
        "root_cuts": root_cuts,
        "lifted_cuts": len(dfj.lifted),
        "root_rounds": root.rounds,
        "lp_bound": root.bound,
        "core_arcs": int(core.mask.sum()),
        "arcs": len(dfj.arcs),
        "solver_status": solver_status,
        "mip_gap": mip_gap,
        "stopped_by": stopped_by,
        "reruns": dfj.model.reruns,
        "fallback": FALLBACK_SEC if stall else None,
        "improved": search.improved,
    }
    if dfj.trace is not None:
        info["trace"] = new_trace(problem, dfj.trace)
    return search.finish(stopped_by, info)


def new_trace(problem: AssignmentProblem, rounds: list[dict[str, Any]]) -> dict[str, Any]:
    """The ``info["trace"]`` of a DFJ run: its size and its rounds (plain JSON data)."""
    return {"kind": "dfj", "n": int(problem.n), "m": int(problem.m), "rounds": rounds}


__all__ = [
    "CORE_SIZE",
    "MIP_OPTIONS",
    "BUILD_SECONDS_PER_ARC",
    "LP_SECONDS_PER_ARC",
    "FALLBACK_SEC",
    "IMPROVE_MIN_SECONDS",
    "TRACE_ZERO",
    "LIFTED_FAMILIES",
    "LIFTED_MIN_GAIN",
    "LIFTED_ROUNDS",
    "RootRelaxation",
    "DfjModel",
    "dfj_root",
    "rounded_routes",
]
