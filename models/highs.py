"""One way to solve a cvxpy model with HiGHS and say what was proven.

Every exact model of :mod:`taopt.models` (routing, delivery, SOP) solves
through :func:`solve_highs`, so the three agree on what "optimal" means
(docs/architecture.md, invariant 4, "exact means certified"):

* **optimal** only when the incumbent is proven within
  :data:`OPTIMALITY_TOLERANCE` (relative gap ``(objective − bound) /
  |objective|`` at most 1e-6), whatever ``mip_rel_gap`` HiGHS was given;
* a MIP that HiGHS calls optimal because a looser user ``mip_rel_gap`` was
  met is **feasible**, with ``stopped_by = "mip_gap"`` and its proven bound;
* a run stopped by ``time_limit`` with a point is **time_limit**, with the
  proven bound.

The rule is :func:`taopt.status.decide` (here on HiGHS's raw status); the models end
through :func:`taopt.result.finish`, which applies the same rule to their final answer
after they combine the solver's bound with their own valid bounds and re-score the
decoded solution.

Two ways to solve. :func:`solve_highs` hands a cvxpy problem to cvxpy's HiGHS
interface (one solve, values written back into the cvxpy variables).
:class:`HighsModel` compiles a cvxpy problem ONCE (``get_problem_data``) into a
``highspy.Highs`` object that stays alive, so a loop can add rows
(:meth:`HighsModel.add_rows`), fix columns, switch integrality off and on, give
a MIP start (``Highs.setSolution``) and watch the MIP's solutions (HiGHS's
``kCallbackMipSolution``) without ever rebuilding: the DFJ loop of
:mod:`taopt.models.routing` runs on one such model.

cvxpy maps HiGHS's ``kOptimal`` to "optimal" and ``kTimeLimit`` (and the other
limits) to "user_limit"; ``problem.solver_stats.extra_stats`` is HiGHS's
``HighsInfo``: ``primal_solution_status`` (2 = a feasible point exists),
``mip_dual_bound`` (the proven bound of a MIP), ``mip_gap``,
``mip_node_count`` and ``objective_function_value``.

Example
-------
>>> import cvxpy as cp
>>> x = cp.Variable(2, integer=True)
>>> run = solve_highs(cp.Problem(cp.Minimize(x.sum()), [x >= 0.5]))
>>> run.status, run.objective, run.bound
('optimal', 2.0, 2.0)
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import highspy
import numpy as np
import scipy.sparse as sp

from taopt.errors import SolverError
from taopt.result import ERROR
from taopt.runtime.deadline import current_token
from taopt.runtime.highs import (
    cvxpy_interruptible,
    interrupt_when,
    run_interruptibly,
    stdout_discarded,
)
from taopt.status import OPTIMALITY_TOLERANCE, decide, relative_gap

#: A MIP run whose reported objective differs from ``c·x + offset`` of its own point by more
#: than this (relative, at least 1e-6 absolute) is not trusted (see :meth:`HighsModel.solve`).
CONSISTENCY_TOLERANCE = 1e-6

logger = logging.getLogger("taopt")

__all__ = [
    "OPTIMALITY_TOLERANCE",
    "HighsModel",
    "HighsRun",
    "add_csr_rows",
    "new_highs",
    "relative_gap",
    "solve_highs",
]


def new_highs(verbose: bool = False) -> highspy.Highs:
    """A ``highspy.Highs`` object created with its output off from the start.

    highspy 1.16 prints "Running HiGHS ... Copyright" on standard output the
    moment the first ``Highs()`` of a process is built, before ``output_flag``
    can be switched off; older versions print nothing. Every HiGHS object of
    taopt is made here, so no version's banner reaches a user's table.
    """
    with stdout_discarded():
        highs = highspy.Highs()
        highs.setOptionValue("output_flag", bool(verbose))
    return highs


# The banner is printed once per process, by whichever Highs() comes first:
# cvxpy's HiGHS interface builds its own, so take the first one here, quietly.
new_highs()


@dataclass(frozen=True)
class HighsRun:
    """What one HiGHS solve found and proved.

    Attributes
    ----------
    status : str
        taopt status by :func:`taopt.status.decide`: "optimal", "feasible" (loose
        ``mip_rel_gap``), "time_limit", "infeasible" or "error".
    stopped_by : str
        "optimal", "mip_gap", "time_limit", "solver_limit" (a HiGHS limit other
        than ``time_limit``), "infeasible" or "error".
    solver_status : str
        cvxpy's status ("optimal", "user_limit", "infeasible", ...), or
        "solver_error" when cvxpy raised.
    has_point : bool
        HiGHS holds a feasible point (``primal_solution_status == 2``); only
        then are the variables' values meaningful.
    objective : float or None
        The model's objective at that point.
    bound : float or None
        Proven lower bound: ``mip_dual_bound`` for a MIP, the LP value for an
        LP solved to optimality; None when nothing is proven.
    mip_gap : float
        HiGHS's own ``mip_gap`` (NaN for an LP or without info).
    nodes : int
        Branch-and-bound nodes (``mip_node_count``; -1 without info).
    is_mip : bool
    message : str
        cvxpy's error text when ``solver_status == "solver_error"``.
    info : HighsInfo or None
        The raw HiGHS info.
    """

    status: str
    stopped_by: str
    solver_status: str
    has_point: bool
    objective: float | None
    bound: float | None
    mip_gap: float
    nodes: int
    is_mip: bool
    message: str = ""
    info: Any = field(default=None, repr=False)


def _number(info: Any, name: str, default: float = math.nan) -> float:
    value = getattr(info, name, default) if info is not None else default
    return float(value)


def thread_options() -> dict[str, Any]:
    """HiGHS's ``threads`` from ``TAOPT_SOLVER_THREADS`` (the study runner sets 1 in its tasks,
    so parallel scenarios do not compete for cores); empty when unset."""
    threads = os.environ.get("TAOPT_SOLVER_THREADS")
    return {"threads": int(threads)} if threads and threads.isdigit() else {}


def solve_highs(
    problem: cp.Problem,
    time_limit: float | None = None,
    mip_rel_gap: float | None = None,
    objective_bound: float | None = None,
    verbose: bool = False,
    extra: dict[str, Any] | None = None,
) -> HighsRun:
    """Solve a cvxpy problem with HiGHS; never raises for a solver outcome.

    Parameters
    ----------
    problem : cvxpy.Problem
        A minimisation LP or MILP.
    time_limit : float, optional
        HiGHS ``time_limit`` in seconds (at least 1 ms is passed).
    mip_rel_gap : float, optional
        HiGHS ``mip_rel_gap`` (ignored for an LP). A run that stops because
        this gap is met but is not within :data:`OPTIMALITY_TOLERANCE` is
        "feasible".
    objective_bound : float, optional
        HiGHS ``objective_bound``: a MIP cut-off; nodes whose bound exceeds it
        are pruned (HiGHS reports "infeasible" if no point lies below it).
    verbose : bool
        HiGHS log.
    extra : dict, optional
        Further HiGHS options by name (e.g. ``mip_feasibility_tolerance`` for a big-M
        model, whose integrality slack is the tolerance times M).

    Returns
    -------
    HighsRun
        Status "error" (with ``message``) when cvxpy raised; the caller
        decides what to do with every outcome.
    """
    is_mip = bool(problem.is_mixed_integer())
    options: dict[str, Any] = dict(thread_options())
    if time_limit is not None:
        options["time_limit"] = max(float(time_limit), 1e-3)
    if is_mip and mip_rel_gap is not None:
        options["mip_rel_gap"] = float(mip_rel_gap)
    if objective_bound is not None:
        options["objective_bound"] = float(objective_bound)
    options.update(extra or {})
    try:
        with warnings.catch_warnings(), cvxpy_interruptible():
            # cvxpy warns "Solution may be inaccurate" on every limit; the status says it
            warnings.filterwarnings("ignore", message="Solution may be inaccurate")
            problem.solve(solver=cp.HIGHS, verbose=verbose, **options)
    except cp.error.SolverError as exc:
        return HighsRun(
            status=ERROR,
            stopped_by="error",
            solver_status="solver_error",
            has_point=False,
            objective=None,
            bound=None,
            mip_gap=math.nan,
            nodes=-1,
            is_mip=is_mip,
            message=str(exc),
        )
    solver_status = problem.status
    info = problem.solver_stats.extra_stats if problem.solver_stats else None
    has_point = info is not None and int(getattr(info, "primal_solution_status", 0)) == 2
    objective = float(problem.value) if has_point and problem.value is not None else None
    bound = None
    if is_mip:
        dual_bound = _number(info, "mip_dual_bound")
        bound = dual_bound if math.isfinite(dual_bound) else None
    elif solver_status == "optimal" and has_point:
        bound = _number(info, "objective_function_value")  # an LP at its optimum
    status, stopped_by = decide(
        solver_status,
        objective,
        bound,
        solver="highs",
        time_limited=time_limit is not None,
        has_point=has_point,
    )
    return HighsRun(
        status=status,
        stopped_by=stopped_by,
        solver_status=solver_status,
        has_point=has_point,
        objective=objective,
        bound=bound,
        mip_gap=_number(info, "mip_gap") if is_mip else math.nan,
        nodes=int(_number(info, "mip_node_count", -1)) if is_mip else -1,
        is_mip=is_mip,
        info=info,
    )


# ------------------------------------------------------------------ persistent model
#: HiGHS model statuses, in cvxpy's words (as cvxpy's own HiGHS interface maps them),
#: so a run of :class:`HighsModel` and one of :func:`solve_highs` read alike.
_SOLVER_STATUS = {
    "kOptimal": "optimal",
    "kInfeasible": "infeasible",
    "kUnboundedOrInfeasible": "infeasible_or_unbounded",
    "kUnbounded": "unbounded",
    "kObjectiveBound": "user_limit",
    "kObjectiveTarget": "user_limit",
    "kTimeLimit": "user_limit",
    "kIterationLimit": "user_limit",
    "kSolutionLimit": "user_limit",
    "kInterrupt": "user_limit",
    "kHighsInterrupt": "user_limit",
}


def _highs_run(highs: highspy.Highs, is_mip: bool, time_limit: float | None) -> HighsRun:
    """:class:`HighsRun` of the last ``highs.run()``: the rules of :func:`solve_highs`."""
    info = highs.getInfo()
    return highs_outcome(
        highs.getModelStatus().name,
        int(info.primal_solution_status) == 2,
        float(info.objective_function_value),
        float(info.mip_dual_bound),
        float(info.mip_gap),
        int(info.mip_node_count),
        is_mip=is_mip,
        time_limited=time_limit is not None,
        info=info,
    )


def highs_outcome(
    model_status: str,
    has_point: bool,
    objective: float,
    mip_dual_bound: float,
    mip_gap: float,
    nodes: int,
    *,
    is_mip: bool,
    time_limited: bool,
    info: Any = None,
) -> HighsRun:
    """:class:`HighsRun` of one HiGHS run read as plain values (``model_status`` is the
    ``HighsModelStatus`` name), under the status rules of
    :func:`~taopt.models.highs.solve_highs`: from a live ``Highs`` (``_highs_run``) or from what
    :func:`~taopt.runtime.highs.run_arrays` returned in a worker process."""
    solver_status = _SOLVER_STATUS.get(model_status, "solver_error")
    value = float(objective) if has_point else None
    bound = None
    if is_mip:
        bound = mip_dual_bound if math.isfinite(mip_dual_bound) else None
    elif solver_status == "optimal" and has_point:
        bound = value  # an LP at its optimum
    status, stopped_by = decide(
        solver_status,
        value,
        bound,
        solver="highs",
        time_limited=time_limited,
        has_point=has_point,
    )
    return HighsRun(
        status=status,
        stopped_by=stopped_by,
        solver_status=solver_status,
        has_point=has_point,
        objective=value,
        bound=bound,
        mip_gap=float(mip_gap) if is_mip else math.nan,
        nodes=int(nodes) if is_mip else -1,
        is_mip=is_mip,
        message="" if solver_status != "solver_error" else f"HiGHS status {model_status}",
        info=info,
    )


def add_csr_rows(highs: highspy.Highs, block: Any, lower: np.ndarray, upper: np.ndarray) -> None:
    """Append the rows ``lower <= block @ x <= upper`` (a CSR block over all columns: a
    ``scipy.sparse.csr_matrix``, or anything with its ``shape``, ``nnz``, ``indptr``,
    ``indices`` and ``data``, as :class:`~taopt.models.sop_bc.CsrRows`) to ``highs`` (one
    ``addRows`` call)."""
    highs.addRows(
        block.shape[0],
        lower,
        upper,
        block.nnz,
        block.indptr[:-1].astype(np.int32),
        block.indices.astype(np.int32),
        block.data.astype(float),
    )


#: HiGHS options (name -> (value in a time-limited MIP run, value otherwise)) for the MIP
#: phases that do not look at HiGHS's clock: probing in presolve (rule 2^15) and a presolve
#: restart after the root. With them a 3 s run of the 20-customer delivery MILP took 4.1 s
#: and a 6 s run 7.8-13 s (HiGHS 1.16, issue 30); without them 3.2 s and 6.2 s.
CLOCKLESS_MIP_PHASES: dict[str, tuple[Any, Any]] = {
    "presolve_rule_off": (2**15, 0),
    "mip_allow_restart": (False, True),
}


class HighsModel:
    """A cvxpy LP/MILP compiled once into a ``highspy.Highs`` that stays alive.

    cvxpy stays the modelling layer: the problem is written (and labelled) in
    cvxpy, compiled once by ``problem.get_problem_data(cp.HIGHS)`` into the same
    rows cvxpy's own HiGHS interface would pass, and from then on changed in
    place: rows added, column bounds changed, integrality switched, a MIP start
    given. Nothing is rebuilt between solves, and an LP re-solve after new rows
    starts from the previous basis (dual simplex).

    Parameters
    ----------
    problem : cvxpy.Problem
        A minimisation LP or MILP (affine objective and constraints).
    verbose : bool
        HiGHS log.

    Attributes
    ----------
    highs : highspy.Highs
        The live solver object.
    n_columns : int
    is_mip : bool
        The compiled problem has integer columns (whatever :meth:`relax` says).
    offset : float
        Constant term of the objective (added to HiGHS's objective by HiGHS).

    Example
    -------
    >>> import cvxpy as cp, numpy as np, scipy.sparse as sp
    >>> x = cp.Variable(2, integer=True)
    >>> model = HighsModel(cp.Problem(cp.Minimize(x.sum()), [x >= 0.5]))
    >>> model.solve().objective
    2.0
    >>> model.add_rows(sp.csr_matrix(np.array([[1.0, 0.0]])), lower=[2.5])  # x0 >= 2.5
    >>> float(model.solve().objective), model.values(x).tolist()
    (4.0, [3.0, 1.0])
    """

    def __init__(self, problem: cp.Problem | None, verbose: bool = False) -> None:
        self.highs = new_highs(verbose)
        for name, value in thread_options().items():
            self.highs.setOptionValue(name, value)
        self._columns: dict[int, tuple[int, int]] = {}
        self._start: np.ndarray | None = None
        #: MIP runs re-done without presolve because HiGHS's answer contradicted its point
        self.reruns = 0
        # HiGHS keeps the interrupt flag of an interrupted run: the next run needs the
        # flag-clearing hook of taopt.runtime.highs.interrupt_when
        self._interrupted = False
        if problem is None:  # filled by from_arrays
            return
        data, _, inverse = problem.get_problem_data(cp.HIGHS)
        program = data["param_prob"]
        self._columns = {
            var.id: (program.var_id_to_col[var.id], int(var.size)) for var in program.variables
        }
        dims = data["dims"]
        upper = np.asarray(data["b"], dtype=float)
        equalities = int(dims.zero)
        # cvxpy's cone form: rows [0, zero) are A x = b, the rest A x <= b
        lower = np.concatenate([upper[:equalities], np.full(len(upper) - equalities, -np.inf)])
        integers = np.asarray(
            sorted({*data["bool_vars_idx"], *data["int_vars_idx"]}), dtype=np.int64
        )
        self._load(
            cost=np.asarray(data["c"], dtype=float),
            matrix=sp.csr_matrix(data["A"]),
            lower=lower,
            upper=upper,
            column_lower=data["lower_bounds"],
            column_upper=data["upper_bounds"],
            booleans=np.asarray(data["bool_vars_idx"], dtype=np.int64),
            integers=integers,
            offset=float(inverse[-1][cp.settings.OFFSET]) if inverse else 0.0,
        )

    @classmethod
    def from_arrays(
        cls,
        cost: np.ndarray,
        matrix: sp.spmatrix,
        lower: np.ndarray,
        upper: np.ndarray,
        column_lower: np.ndarray | None = None,
        column_upper: np.ndarray | None = None,
        integers: np.ndarray | None = None,
        offset: float = 0.0,
        verbose: bool = False,
    ) -> HighsModel:
        """A model from numpy arrays, without cvxpy: ``min c x + offset``, ``lower <= A x <= upper``.

        For models too large for cvxpy's compilation within a time limit (the DFJ model of
        n = 1000 targets has a million columns: about 20 s through ``get_problem_data``,
        a fraction of a second here). :meth:`columns` knows no cvxpy variable then.
        """
        model = cls(None, verbose=verbose)
        integers = np.zeros(0, dtype=np.int64) if integers is None else np.asarray(integers)
        model._load(
            cost=np.asarray(cost, dtype=float),
            matrix=matrix if sp.issparse(matrix) else sp.csr_matrix(matrix),
            lower=np.asarray(lower, dtype=float),
            upper=np.asarray(upper, dtype=float),
            column_lower=column_lower,
            column_upper=column_upper,
            booleans=np.zeros(0, dtype=np.int64),
            integers=integers.astype(np.int64),
            offset=float(offset),
        )
        return model

    def _load(
        self,
        cost: np.ndarray,
        matrix: sp.spmatrix,
        lower: np.ndarray,
        upper: np.ndarray,
        column_lower: np.ndarray | None,
        column_upper: np.ndarray | None,
        booleans: np.ndarray,
        integers: np.ndarray,
        offset: float,
    ) -> None:
        """Pass the model to HiGHS: one ``passModel`` of numpy arrays, integrality included."""
        n_columns = len(cost)
        column_lower = (
            np.full(n_columns, -np.inf)
            if column_lower is None
            else np.array(column_lower, dtype=float)
        )
        column_upper = (
            np.full(n_columns, np.inf)
            if column_upper is None
            else np.array(column_upper, dtype=float)
        )
        column_lower[booleans] = np.maximum(column_lower[booleans], 0.0)
        column_upper[booleans] = np.minimum(column_upper[booleans], 1.0)
        self.offset = offset
        self.n_columns = n_columns
        self.is_mip = len(integers) > 0
        self._integers = integers.astype(np.int32)
        self._relaxed = False
        self.cost = cost
        # the rows as kept here too (for Lagrangian bounds): matrix, lower, upper
        self._row_blocks: list[tuple[sp.spmatrix, np.ndarray, np.ndarray]] = [
            (matrix, lower, upper)
        ]
        by_column = matrix.tocsc()
        if not by_column.has_sorted_indices:
            by_column = by_column.sorted_indices()
        integrality = np.zeros(n_columns, dtype=np.int32)
        integrality[self._integers] = int(highspy.HighsVarType.kInteger)
        # passModel's array form: numpy arrays in, no Python loop over columns (a HighsLp's
        # attributes are copied element by element: 2 s for a million columns)
        status = self.highs.passModel(
            n_columns,
            matrix.shape[0],
            by_column.nnz,
            int(highspy.MatrixFormat.kColwise),
            int(highspy.ObjSense.kMinimize),
            self.offset,
            np.ascontiguousarray(cost, dtype=np.float64),
            column_lower,
            column_upper,
            np.ascontiguousarray(lower, dtype=np.float64),
            np.ascontiguousarray(upper, dtype=np.float64),
            by_column.indptr.astype(np.int32),
            by_column.indices.astype(np.int32),
            by_column.data.astype(np.float64),
            integrality,
        )
        if status == highspy.HighsStatus.kError:
            raise SolverError("HiGHS rejected the compiled model")
        self.column_lower = column_lower
        self.column_upper = column_upper

    # ------------------------------------------------------------------ columns
    def columns(self, variable: cp.Variable) -> np.ndarray:
        """Column indices of a cvxpy variable (flattened in cvxpy's column-major order)."""
        if variable.id not in self._columns:
            raise SolverError(f"variable {variable.name()} is not in the compiled model")
        start, size = self._columns[variable.id]
        return np.arange(start, start + size)

    def values(self, variable: cp.Variable, solution: Any = None) -> np.ndarray:
        """The variable's values in the last solution (or in ``solution``, a full column vector)."""
        if solution is None:
            solution = self.highs.getSolution().col_value
        return np.asarray(solution, dtype=float)[self.columns(variable)]

    def set_upper(self, columns: Any, upper: Any) -> None:
        """Change the upper bounds of some columns (e.g. 0 to fix a binary off)."""
        columns = np.asarray(columns, dtype=np.int32)
        if len(columns) == 0:
            return
        upper = np.broadcast_to(np.asarray(upper, dtype=float), columns.shape).copy()
        self.column_upper[columns] = upper
        self.highs.changeColsBounds(len(columns), columns, self.column_lower[columns], upper)

    def relax(self, relaxed: bool = True) -> None:
        """Switch the integer columns to continuous (the LP relaxation) or back."""
        if not self.is_mip or relaxed == self._relaxed:
            return
        kind = highspy.HighsVarType.kContinuous if relaxed else highspy.HighsVarType.kInteger
        flags = np.full(len(self._integers), int(kind), dtype=np.uint8)
        self.highs.changeColsIntegrality(len(self._integers), self._integers, flags)
        self._relaxed = relaxed

    # --------------------------------------------------------------------- rows
    def add_rows(self, matrix: sp.spmatrix, lower: Any = None, upper: Any = None) -> None:
        """Add rows ``lower <= matrix @ x <= upper`` (over ALL columns) to the live model.

        ``None`` for a side means unbounded on that side.
        """
        matrix = sp.csr_matrix(matrix)
        count = matrix.shape[0]
        if count == 0:
            return
        if matrix.shape[1] != self.n_columns:
            raise SolverError(f"rows have {matrix.shape[1]} columns, the model {self.n_columns}")
        lower = np.full(count, -np.inf) if lower is None else np.asarray(lower, dtype=float)
        upper = np.full(count, np.inf) if upper is None else np.asarray(upper, dtype=float)
        lower = np.broadcast_to(lower, (count,)).copy()
        upper = np.broadcast_to(upper, (count,)).copy()
        matrix.sort_indices()
        add_csr_rows(self.highs, matrix, lower, upper)
        self._row_blocks.append((matrix, lower, upper))

    @property
    def n_rows(self) -> int:
        return sum(block[0].shape[0] for block in self._row_blocks)

    # -------------------------------------------------------------------- solve
    def set_start(self, solution: np.ndarray) -> bool:
        """Give HiGHS a full column vector as a MIP start (``Highs.setSolution``).

        HiGHS checks it and keeps it as its first incumbent if it is feasible.
        Returns False if HiGHS rejected the call. The start is kept for the next
        :meth:`solve` only (a re-run of it may need it again).
        """
        solution = np.asarray(solution, dtype=float)
        if solution.shape != (self.n_columns,):
            raise SolverError(f"a start needs {self.n_columns} values, got {solution.shape}")
        self._start = solution.copy()
        status = self.highs.setSolution(
            self.n_columns, np.arange(self.n_columns, dtype=np.int32), solution
        )
        return status != highspy.HighsStatus.kError

    def solve(
        self,
        time_limit: float | None = None,
        mip_rel_gap: float | None = None,
        on_solution: Any = None,
        options: dict[str, Any] | None = None,
        offer: Any = None,
    ) -> HighsRun:
        """Run HiGHS on the model as it stands; never raises for a solver outcome.

        Parameters
        ----------
        time_limit : float, optional
            Seconds (at least 1 ms is passed); None for no limit. The run also stops at
            HiGHS's next interrupt callback once the cancel token of the innermost
            :func:`taopt.runtime.cancel_scope` (if any) is set.
        mip_rel_gap : float, optional
            HiGHS ``mip_rel_gap`` (HiGHS's default 1e-4 when None).
        on_solution : callable, optional
            Called with the full column vector (a numpy array) of every
            solution HiGHS's MIP search finds (``kCallbackMipSolution``).
        options : dict, optional
            Further HiGHS options for this and later runs (name -> value).
        offer : callable, optional
            ``offer() -> full column vector or None``, asked whenever HiGHS's MIP search
            takes a solution from the user (``kCallbackMipUserSolution``: after setup and
            before its dives); a vector returned is passed to HiGHS, which keeps it as
            its incumbent if it is feasible and better.

        Returns
        -------
        HighsRun
            With the status rules of :func:`solve_highs`.
        """
        highs = self.highs
        limit = math.inf if time_limit is None else max(float(time_limit), 1e-3)
        is_mip = self.is_mip and not self._relaxed
        highs.setOptionValue("time_limit", self._clock_limit(limit, is_mip))
        highs.setOptionValue("mip_rel_gap", 1e-4 if mip_rel_gap is None else float(mip_rel_gap))
        if is_mip:  # a limited MIP run leaves out the phases that ignore the clock
            for name, (limited, free) in CLOCKLESS_MIP_PHASES.items():
                if name not in (options or {}):
                    highs.setOptionValue(name, limited if time_limit is not None else free)
        for name, value in (options or {}).items():
            if highs.setOptionValue(name, value) == highspy.HighsStatus.kError:
                raise SolverError(f"HiGHS refused option {name} = {value!r}")

        def forward(event: Any) -> None:
            on_solution(np.array(event.data_out.mip_solution, dtype=float))

        began = time.perf_counter()
        deadline = began + limit
        # HiGHS looks at time_limit rarely inside an LP; its interrupt callbacks come every
        # simplex / IPM iteration and MIP node, so a limit is kept more closely; they also
        # stop the run once the caller's cancel token is set (docs/architecture.md, "the
        # runtime contract")
        token = current_token()
        hooks = contextlib.ExitStack()
        if time_limit is not None or token is not None or self._interrupted:
            hooks.enter_context(
                interrupt_when(
                    highs,
                    lambda: (
                        time.perf_counter() >= deadline or (token is not None and token.cancelled)
                    ),
                )
            )

        def give(event: Any) -> None:
            vector = offer()
            if vector is not None:
                event.data_in.setSolution(np.asarray(vector, dtype=float))

        if on_solution is not None and is_mip:
            highs.cbMipSolution.subscribe(forward)
        if offer is not None and is_mip:
            highs.cbMipUserSolution.subscribe(give)
        start, self._start = self._start, None
        try:
            run_interruptibly(highs)  # Ctrl-C: HiGHS stops, then KeyboardInterrupt
            run = _highs_run(highs, is_mip, time_limit)
            if is_mip and (run.solver_status == "solver_error" or not self._consistent(run)):
                # HiGHS 1.16 can map a MIP start into its presolved space with the wrong
                # objective (e.g. "feasible in the reduced space: objective value is 1" for a
                # start of value 4) and then stop at node 0 calling that start "Optimal",
                # with objective and dual bound both in the wrong space. And when its
                # presolve reduces a MIP to nothing, its postsolve can leave violations
                # ("untransformed violations") and end with a solve error (a 4-target
                # budgeted model of zero costs). Neither outcome is a proof, so the same run
                # is done again without presolve, start included.
                self.reruns += 1
                if run.solver_status == "solver_error":
                    logger.info("HiGHS ended with %s; solving again without presolve", run.message)
                else:
                    logger.info(
                        "HiGHS reported objective %.10g for a point of value %.10g; solving "
                        "again without presolve",
                        run.objective,
                        self.point_objective(),
                    )
                left = limit - (time.perf_counter() - began)
                highs.setOptionValue("time_limit", self._clock_limit(max(left, 1e-3), is_mip))
                highs.setOptionValue("presolve", "off")
                try:
                    if start is not None:
                        self._give_start(start)
                    run_interruptibly(highs)  # Ctrl-C: HiGHS stops, then KeyboardInterrupt
                finally:
                    highs.setOptionValue("presolve", "choose")
                run = _highs_run(highs, is_mip, time_limit)
                if run.solver_status == "solver_error":
                    raise SolverError(f"HiGHS ended with {run.message}, also without presolve")
                if not self._consistent(run):
                    raise SolverError(
                        f"HiGHS reported objective {run.objective} for a point of value "
                        f"{self.point_objective()}, also without presolve"
                    )
        finally:
            if on_solution is not None and is_mip:
                highs.cbMipSolution.unsubscribe(forward)
            if offer is not None and is_mip:
                highs.cbMipUserSolution.unsubscribe(give)
            hooks.close()
            self._interrupted = highs.getModelStatus() == highspy.HighsModelStatus.kInterrupt
        return run

    def _clock_limit(self, seconds: float, is_mip: bool) -> float:
        """HiGHS's ``time_limit`` value that gives this run ``seconds``.

        HiGHS 1.16 compares an LP's ``time_limit`` with its run clock summed over every run of
        the same object (a MIP run is timed on its own): a cut loop that re-solved its LP with
        "the time left" was stopped at once after a few rounds, saying ``time_limit`` long
        before its deadline. So an LP run is given the run time so far plus its seconds.
        """
        if is_mip or math.isinf(seconds):
            return seconds
        return float(self.highs.getRunTime()) + seconds

    def point_objective(self, solution: Any = None) -> float:
        """``c·x + offset`` of the last solution (or of ``solution``), computed here."""
        if solution is None:
            solution = self.highs.getSolution().col_value
        return float(self.cost @ np.asarray(solution, dtype=float)) + self.offset

    def _consistent(self, run: HighsRun) -> bool:
        """HiGHS's objective is the value of the point it returns (True without a point)."""
        if not run.has_point or run.objective is None:
            return True
        value = self.point_objective()
        return abs(value - run.objective) <= CONSISTENCY_TOLERANCE * max(1.0, abs(value))

    def _give_start(self, solution: np.ndarray) -> None:
        self.highs.setSolution(self.n_columns, np.arange(self.n_columns, dtype=np.int32), solution)

    def lagrangian_bound(self) -> tuple[float, np.ndarray]:
        """A proven lower bound and reduced costs from the last LP's row duals.

        For any row duals y of the right signs (free on equalities, ``<= 0`` on
        ``A x <= u`` rows, ``>= 0`` on ``A x >= l`` rows) and reduced costs
        ``d = c - A^T y``, every x in the column bounds that satisfies the rows
        has ``c x >= y·b + Σ_j min(d_j l_j, d_j u_j) =: L``. HiGHS's duals are
        clipped to those signs and L is computed here, so the bound holds
        whatever the solver's tolerances. Moreover a point with ``x_j = u_j``
        for a column at its lower bound in the LP (``d_j > 0``, ``l_j = 0``)
        costs at least ``L + d_j u_j``: the basis of reduced-cost fixing.

        Returns
        -------
        bound : float
            L plus the objective's offset (``-inf`` without a dual solution).
        reduced_costs : ndarray
            d, one per column.
        """
        solution = self.highs.getSolution()
        if not solution.dual_valid:
            return -math.inf, np.zeros(self.n_columns)
        duals = np.asarray(solution.row_dual, dtype=float)
        bound = self.offset
        reduced = self.cost.copy()
        start = 0
        for matrix, lower, upper in self._row_blocks:
            y = duals[start : start + matrix.shape[0]].copy()
            start += matrix.shape[0]
            finite_lower, finite_upper = np.isfinite(lower), np.isfinite(upper)
            equal = finite_lower & finite_upper & (lower == upper)
            # a <= row can only have y <= 0, a >= row y >= 0; a ranged row takes the side
            # its sign points to
            y = np.where(~finite_lower & (y > 0), 0.0, y)
            y = np.where(~finite_upper & (y < 0), 0.0, y)
            rhs = np.where(y > 0, np.where(finite_lower, lower, 0.0), 0.0)
            rhs = np.where(y < 0, np.where(finite_upper, upper, 0.0), rhs)
            rhs = np.where(equal, lower, rhs)
            bound += float(y @ rhs)
            reduced -= matrix.T @ y
        low = np.where(np.isfinite(self.column_lower), self.column_lower, 0.0)
        high = np.where(np.isfinite(self.column_upper), self.column_upper, 0.0)
        if np.any((reduced > 0) & ~np.isfinite(self.column_lower)) or np.any(
            (reduced < 0) & ~np.isfinite(self.column_upper)
        ):
            return -math.inf, reduced  # an unbounded column direction: no bound from y
        bound += float(np.minimum(reduced * low, reduced * high).sum())
        return bound, reduced
