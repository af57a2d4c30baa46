"""Every MILP the toolkit builds, written as an LP or MPS file with the thesis's names.

:func:`~taopt.orchestration.export.export` builds the named model of a problem with the
model's own builder (:mod:`taopt.models`), turns it into one HiGHS model and writes it with
``highspy.Highs.writeModel`` (the file's extension picks the format). The cvxpy models are
turned into HiGHS models through the matrices cvxpy hands HiGHS (``get_problem_data``): the
rows of every labelled cvxpy constraint are found again in those matrices, so each row and
column gets a name built from the thesis's symbols and equation numbers (``sigma_5_0`` for
σ_ij of the arc from start point 5 to target 0, ``eq2_3_in_0`` for row (2.3) of target 0).
The budgeted model, which lives on a HiGHS model already, is named in place.

The models, per family (:data:`~taopt.orchestration.export.MODELS`):

* ``AssignmentProblem``: ``dfj`` (2.2)–(2.5) with the subtour rows of a cut loop, ``mtz``,
  ``flow`` (:func:`taopt.models.routing.formulation.build`);
* ``CapabilityProblem``: ``printed`` (3.1)–(3.3) as printed, ``corrected`` (§3.6: one MTZ
  routing model per class, side by side), ``joint`` (:mod:`taopt.models.capability_joint`);
* ``DeliveryInstance``: ``milp``, the linear (5.1)–(5.7) (:func:`taopt.models.delivery.build`);
* ``SopProblem``: ``flow``, ``mtz`` (:func:`taopt.models.sop.build`);
* ``BudgetedProblem``: ``arc-vehicle``, §6.2's three-index model
  (:class:`taopt.models.budgeted.arc_vehicle.BudgetedModel`) with the subtour rows of a cut
  loop;
* ``FleetProblem``: ``milp``, the fleet teaching MILP (:mod:`taopt.models.fleet_milp`).

The DFJ models (``dfj``, ``joint``, ``arc-vehicle``) hold the subtour rows (2.5) of a cut
loop run to its end: solve, add a row for every subtour of the integral solution, re-solve,
until none is left. The file then has the cut pool at the end of that loop, and its optimum
is the certified optimum (a relaxation whose optimum is feasible). ``cuts="all"`` writes
every subset of two or more targets instead (tiny instances only).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from taopt.errors import InstanceError, OutputError, SolverError
from taopt.io import atomic_path

if TYPE_CHECKING:
    import cvxpy as cp
    import highspy

__all__ = ["FORMATS", "MODELS", "export", "export_model", "highs_model"]

#: The file formats :func:`~taopt.orchestration.export.export` writes (the extension of
#: ``path`` picks one).
FORMATS = ("lp", "mps")

#: Family problem type name -> the model names :func:`~taopt.orchestration.export.export`
#: builds for it.
MODELS: dict[str, tuple[str, ...]] = {
    "AssignmentProblem": ("dfj", "mtz", "flow"),
    "CapabilityProblem": ("printed", "corrected", "joint"),
    "DeliveryInstance": ("milp",),
    "SopProblem": ("flow", "mtz"),
    "BudgetedProblem": ("arc-vehicle",),
    "FleetProblem": ("milp",),
}

#: Subsets of (2.5) written in full by ``cuts="all"`` up to this many targets (2^n rows).
ALL_CUTS_MAX_TARGETS = 12

#: Rounds of the cut loop before :func:`~taopt.orchestration.export.export` gives up (each
#: round re-solves the MILP).
MAX_CUT_ROUNDS = 200

Namer = Callable[[int], str]


# ----------------------------------------------------------------------------- names
def _clean(text: str) -> str:
    """A name LP and MPS files accept: letters, digits and ``_`` only."""
    return re.sub(r"_+", "_", re.sub(r"[^A-Za-z0-9]+", "_", text)).strip("_")


def label_name(label: str) -> str:
    """The row-name stem of a cvxpy constraint label: its equation number, then a few words.

    >>> label_name("(2.3) every target entered once")
    'eq2_3_every_target_entered'
    >>> label_name("MTZ: 1 <= u_j")
    'MTZ_1_u_j'
    """
    match = re.match(r"\s*\(([0-9A-Za-z.]+)\)\s*(.*)", label)
    if match:
        number, rest = match.groups()
        words = _clean(rest).split("_")[:3]
        return "_".join(["eq" + _clean(number.replace(".", "_")), *words]).strip("_")
    return "_".join(_clean(label).split("_")[:4]) or "row"


def _indexed(stem: str, keys: Sequence[Any]) -> Namer:
    """``stem_<key>`` for row/column r, a key a number or a tuple of numbers."""

    def name(r: int) -> str:
        key = keys[r]
        parts = key if isinstance(key, tuple) else (key,)
        return "_".join([stem, *(str(int(p)) for p in parts)])

    return name


def _entries(shape: tuple[int, ...]) -> list[Any]:
    """The index of each entry of an array of ``shape`` in cvxpy's (column-major) order: an
    int for a vector, a tuple ``(i, j)`` for a matrix."""
    import numpy as np

    size = int(np.prod(shape, dtype=int))
    if len(shape) <= 1:
        return list(range(size))
    return list(zip(*np.unravel_index(np.arange(size), shape, order="F"), strict=True))


# ----------------------------------------------------------------------------- cvxpy -> HiGHS
def highs_model(
    problem: cp.Problem,
    columns: Mapping[int, Namer] | None = None,
    rows: Mapping[int, Namer] | None = None,
) -> highspy.Highs:
    """A HiGHS model holding a cvxpy MILP/LP, with named columns and rows.

    The matrices are those cvxpy hands HiGHS (``problem.get_problem_data(cp.HIGHS)``): the
    equality rows first, then the ``<=`` rows, each constraint's rows together, in its
    flattened order. Each of them is traced back to the constraint the model wrote.

    Parameters
    ----------
    problem : cvxpy.Problem
        Linear (a MILP or an LP).
    columns : dict, optional
        ``variable.id -> name(i)`` for entry ``i`` of the variable (cvxpy's column-major
        order); default ``<variable name>_<i>`` (``_<i>_<j>`` for a matrix).
    rows : dict, optional
        ``constraint.id -> name(r)`` for row ``r`` of the constraint; default
        ``<label stem>_<r>`` (:func:`~taopt.orchestration.export.label_name`), ``c<id>_<r>``
        for a constraint without a label.

    Returns
    -------
    highspy.Highs
        With the model passed and its names set (write it with ``writeModel(path)``).
    """
    import cvxpy as cp
    import highspy
    import numpy as np

    from taopt.runtime.highs import stdout_discarded

    columns, rows = columns or {}, rows or {}
    data, chain, inverse = problem.get_problem_data(cp.HIGHS)
    stuffing = next(
        inv for inv, red in zip(inverse, chain.reductions, strict=True)
        if type(red).__name__ == "ConeMatrixStuffing"
    )  # fmt: skip
    solver = inverse[-1].inverse_data if hasattr(inverse[-1], "inverse_data") else inverse[-1]
    # a canonical constraint's id -> the id of the constraint the model wrote
    origin = {c.id: c.id for c in problem.constraints}
    for inv in inverse:
        mapping = getattr(inv, "cons_id_map", None)
        if isinstance(mapping, dict):
            origin.update({new: origin.get(old, old) for old, new in mapping.items()})
    by_id = {c.id: c for c in problem.constraints}

    n_cols = int(stuffing.x_length)
    col_names = [f"x_{i}" for i in range(n_cols)]
    for var_id, offset in stuffing.var_offsets.items():
        variable = stuffing.id2var[var_id]
        namer = columns.get(var_id) or _indexed(
            _clean(variable.name()) or "x", _entries(variable.shape)
        )
        for i in range(int(np.prod(variable.shape, dtype=int))):
            col_names[offset + i] = namer(i)

    row_names: list[str] = []
    for canonical in [*solver["eq_constr"], *solver["other_constr"]]:
        written = by_id.get(origin.get(canonical.id, -1))
        size = int(canonical.size)
        if written is None:
            row_names += [f"bound_{canonical.id}_{r}" for r in range(size)]
            continue
        stem = label_name(written.label) if written.label else f"c{written.id}"
        shape = written.shape if int(np.prod(written.shape, dtype=int)) == size else (size,)
        namer = rows.get(written.id) or _indexed(stem, _entries(shape))
        row_names += [namer(r) for r in range(size)]

    matrix = data["A"].tocsc()
    b = np.asarray(data["b"], dtype=float)
    n_eq = int(data["dims"].zero)
    if len(row_names) != matrix.shape[0]:  # pragma: no cover - a cvxpy change
        raise SolverError(f"cannot match cvxpy's {matrix.shape[0]} rows to the model's constraints")
    inf = highspy.kHighsInf
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = n_cols, matrix.shape[0]
    cost = np.asarray(data["c"], dtype=float)
    offset = float(solver.get("offset", 0.0))
    if isinstance(problem.objective, cp.Maximize):  # cvxpy minimises -f: write max f
        cost, offset = -cost, -offset
        lp.sense_ = highspy.ObjSense.kMaximize
    lp.col_cost_, lp.offset_ = cost, offset
    lower = data["lower_bounds"]
    upper = data["upper_bounds"]
    col_lower = np.full(n_cols, -inf) if lower is None else np.asarray(lower, dtype=float).copy()
    col_upper = np.full(n_cols, inf) if upper is None else np.asarray(upper, dtype=float).copy()
    integers = [*data["bool_vars_idx"], *data["int_vars_idx"]]
    for i in data["bool_vars_idx"]:
        col_lower[i], col_upper[i] = max(col_lower[i], 0.0), min(col_upper[i], 1.0)
    lp.col_lower_, lp.col_upper_ = col_lower, col_upper
    lp.row_lower_ = np.concatenate([b[:n_eq], np.full(len(b) - n_eq, -inf)])
    lp.row_upper_ = b
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = matrix.indptr
    lp.a_matrix_.index_ = matrix.indices
    lp.a_matrix_.value_ = matrix.data
    if integers:
        kinds = [highspy.HighsVarType.kContinuous] * n_cols
        for i in integers:
            kinds[int(i)] = highspy.HighsVarType.kInteger
        lp.integrality_ = kinds
    lp.col_names_ = _unique(col_names)
    lp.row_names_ = _unique(row_names)
    with stdout_discarded():
        highs = highspy.Highs()
        highs.setOptionValue("output_flag", False)
        highs.passModel(lp)
    return highs


def _unique(names: list[str]) -> list[str]:
    """The names, a repeated one suffixed ``_dup<k>`` (a file needs distinct names)."""
    seen: dict[str, int] = {}
    out = []
    for name in names:
        count = seen.get(name, 0)
        seen[name] = count + 1
        out.append(name if count == 0 else f"{name}_dup{count}")
    return out


# ----------------------------------------------------------------------------- chapter 2
def _routing_names(model: Any, n: int) -> tuple[dict[int, Namer], dict[int, Namer]]:
    """σ_ij as ``sigma_i_j`` (targets 0..n-1, start points n..n+m-1), rows by equation."""
    import numpy as np

    tails, heads = model.tails, model.heads
    arcs = list(zip(tails.tolist(), heads.tolist(), strict=True))
    columns: dict[int, Namer] = {model.arc_use.id: _indexed("sigma", arcs)}
    if model.flow is not None:
        columns[model.flow.id] = _indexed("f", arcs)
    if model.order is not None:
        columns[model.order.id] = _indexed("u", range(n))
    rows: dict[int, Namer] = {}
    target_arcs = [arcs[a] for a in np.flatnonzero(tails < n)]
    for constraint in model.problem.constraints:
        label = constraint.label or ""
        if label.startswith("(2.3)"):
            rows[constraint.id] = _indexed("eq2_3_in", range(n))
        elif label.startswith("(2.4)"):
            rows[constraint.id] = _indexed("eq2_4_out", range(n + model_m(model, n)))
        elif label.startswith("(2.5) DFJ"):
            rows[constraint.id] = _indexed("eq2_5_dfj", [tuple(s) for s in model.cuts])
        elif label.startswith("(2.5) MTZ"):
            rows[constraint.id] = _indexed("eq2_5_mtz", target_arcs)
        elif label.startswith("MTZ: 1"):
            rows[constraint.id] = _indexed("mtz_u_lower", range(n))
        elif label.startswith("MTZ: u_j"):
            rows[constraint.id] = _indexed("mtz_u_upper", range(n))
        elif label.startswith("(2.5) flow: inflow"):
            rows[constraint.id] = _indexed("eq2_5_flow_balance", range(n))
        elif label.startswith("(2.5) flow: f_ij <="):
            rows[constraint.id] = _indexed("eq2_5_flow_cap", arcs)
        elif label.startswith("(2.5) flow: f_ij >="):
            rows[constraint.id] = _indexed("eq2_5_flow_link", arcs)
    return columns, rows


def model_m(model: Any, n: int) -> int:
    """Start points of a routing model: the tails beyond the targets."""
    return int(model.tails.max()) + 1 - n if len(model.tails) else 0


def _all_subsets(n: int) -> list[tuple[int, ...]]:
    if n > ALL_CUTS_MAX_TARGETS:
        raise InstanceError(
            f'cuts="all" writes 2^n subtour rows: {n} targets is more than '
            f"{ALL_CUTS_MAX_TARGETS}; use the cut loop (cuts=None)"
        )
    return [s for size in range(2, n + 1) for s in itertools.combinations(range(n), size)]


def _solve_cvxpy(problem: cp.Problem, what: str) -> None:
    """Solve with HiGHS in place (the cut loops); an error names ``what``."""
    import cvxpy as cp

    from taopt.runtime.highs import stdout_discarded

    with stdout_discarded():
        problem.solve(solver=cp.HIGHS)
    if problem.status not in ("optimal", "optimal_inaccurate"):
        raise SolverError(f"{what}: HiGHS ended {problem.status} in the cut loop")


def _routing(problem: Any, model: str, cuts: Any) -> highspy.Highs:
    from taopt.models.routing import build, find_subtours

    n = problem.n
    if model != "dfj":
        built = build(problem, sec=model)
        return highs_model(built.problem, *_routing_names(built, n))
    if cuts == "all":
        pool = _all_subsets(n)
    elif cuts is not None:
        pool = [tuple(sorted(int(v) for v in s)) for s in cuts]
    else:  # the cut loop: every subtour of the integral optimum, until none is left
        pool = []
        for _ in range(MAX_CUT_ROUNDS):
            built = build(problem, sec="dfj", cuts=pool)
            _solve_cvxpy(built.problem, "routing dfj")
            found = [tuple(sorted(s)) for s in find_subtours(problem, built)]
            if not found:
                break
            pool += [s for s in found if s not in pool]
        else:  # pragma: no cover - a loop adds a new row each round
            raise SolverError(f"routing dfj: subtours left after {MAX_CUT_ROUNDS} rounds")
    built = build(problem, sec="dfj", cuts=pool)
    return highs_model(built.problem, *_routing_names(built, n))


# ----------------------------------------------------------------------------- chapter 3
def _capability(problem: Any, model: str) -> highspy.Highs:
    import cvxpy as cp

    from taopt.models.capability_joint import build_joint
    from taopt.models.capability_printed import build_printed
    from taopt.models.routing import build

    if model == "corrected":  # §3.6: one routing model per class, side by side
        parts, objective, columns, rows = [], 0, {}, {}
        for q, cls in enumerate(problem.classes):
            if cls.problem is None:  # no target demands it
                continue
            built = build(cls.problem, sec="mtz")
            cols, rws = _routing_names(built, cls.problem.n)
            tag = f"q{q}_{_clean(str(cls.capability))}_"
            columns.update({k: _prefixed(tag, f) for k, f in cols.items()})
            rows.update({k: _prefixed(tag, f) for k, f in rws.items()})
            parts += built.problem.constraints
            objective = objective + built.problem.objective.expr
        return highs_model(cp.Problem(cp.Minimize(objective), parts), columns, rows)
    # σ_ijk: k the vehicle (printed) or the class q (joint)
    arcs = build_printed(problem) if model == "printed" else _capability_joint(problem, build_joint)
    keys = list(zip(arcs.tails.tolist(), arcs.heads.tolist(), arcs.labels.tolist(), strict=True))
    return highs_model(arcs.problem, {arcs.arc_use.id: _indexed("sigma", keys)})


def _prefixed(tag: str, namer: Namer) -> Namer:
    return lambda r: tag + namer(r)


def _capability_joint(problem: Any, build_joint: Callable[..., Any]) -> Any:
    """The joint model with the (q, S) subtour rows of a cut loop run to its end."""
    from taopt.models.capability_joint import _joint_decode

    pool: list[tuple[int, tuple[int, ...]]] = []
    for _ in range(MAX_CUT_ROUNDS):
        built = build_joint(problem, sec="dfj", cuts=pool)
        _solve_cvxpy(built.problem, "capability joint")
        found = _joint_decode(problem, built, built.arc_use.value)[1]
        new = [c for c in found if c not in pool]
        if not new:
            return built
        pool += new
    raise SolverError(f"capability joint: subtours left after {MAX_CUT_ROUNDS} rounds")


# ----------------------------------------------------------------------------- chapter 5, SOP
def _delivery(problem: Any) -> highspy.Highs:
    from taopt.models.delivery import build

    built = build(problem)
    sorties = list(zip(built.position, built.launch, built.customer, built.landing, strict=True))
    columns = {
        built.sortie.id: _indexed("y", sorties),
        built.launch_time.id: _indexed("S", range(problem.n)),
        built.service_time.id: _indexed("t", range(problem.n)),
        built.recovery_time.id: _indexed("R", range(problem.n)),
    }
    if built.truck_leg is not None:
        legs = list(zip(built.leg_position, built.leg_from, built.leg_to, strict=True))
        columns[built.truck_leg.id] = _indexed("w", legs)
    return highs_model(built.problem, columns)


def _sop(problem: Any, model: str) -> highspy.Highs:
    from taopt.models.sop import build

    built = build(problem.cost, problem.precedences, problem.start, problem.end, model)
    arcs = list(zip(built.tails.tolist(), built.heads.tolist(), strict=True))
    columns = {built.arc_use.id: _indexed("x", arcs)}
    if built.position is not None:
        columns[built.position.id] = _indexed("u", range(len(problem.cost)))
    return highs_model(built.problem, columns)


def _fleet(problem: Any) -> highspy.Highs:
    from taopt.models.fleet_milp import build

    # built as arrays straight into HiGHS (no cvxpy), with the model's own names
    return build(problem).highs(names=True).highs


# ----------------------------------------------------------------------------- chapter 6
def _budgeted(problem: Any, cuts: Any) -> highspy.Highs:
    import numpy as np

    from taopt.models.budgeted.arc_vehicle import BudgetedModel
    from taopt.runtime.highs import stdout_discarded

    built = BudgetedModel(problem)
    highs = built.model.highs
    n, m = problem.n, problem.m
    if cuts == "all":
        built.add_cuts(_all_subsets(n))
    elif cuts is not None:
        built.add_cuts([tuple(s) for s in cuts])
    else:
        for _ in range(MAX_CUT_ROUNDS):
            with stdout_discarded():
                highs.run()
            if highs.getModelStatus() != highspy_status("kOptimal"):
                break  # infeasible: nothing to cut, the file says so when re-solved
            decoded = built.decode(np.asarray(highs.getSolution().col_value))
            cycles = [] if decoded is None else [tuple(c) for c in decoded[1]]
            if not cycles or not built.add_cuts(cycles):
                break
    tails, heads = built.tails, built.heads
    for c in range(built.n_columns):
        a = int(built.arc[c])
        highs.passColName(c, f"x_{int(built.vehicle[c])}_{int(tails[a])}_{int(heads[a])}")
    names = [f"eq2_3_in_{j}" for j in range(n)]
    names += [f"eq2_4_flow_{j}_{k}" for j in range(n) for k in range(m)]
    names += [f"eq2_4_start_{k}" for k in range(m)]
    for stem, limits in (("sec6_2_capacity", problem.capacity), ("sec6_2_time", problem.max_time)):
        names += [f"{stem}_{k}" for k in np.flatnonzero(np.isfinite(limits))]
    names += ["eq2_5_dfj_" + "_".join(map(str, s)) for s in built.cuts]
    for r, name in enumerate(names[: highs.getNumRow()]):
        highs.passRowName(r, name)
    return highs


def highspy_status(name: str) -> Any:
    import highspy

    return getattr(highspy.HighsModelStatus, name)


# ----------------------------------------------------------------------------- entry point
def export_model(problem: Any, model: str, cuts: Any = None) -> highspy.Highs:
    """The named model of ``problem`` as a HiGHS model with the thesis's names.

    Raises
    ------
    InstanceError
        ``model`` is not one of the models of the problem's family (the message lists them).
    """
    kind = type(problem).__name__
    valid = MODELS.get(kind)
    if valid is None:
        raise InstanceError(
            f"no exportable MILP for a {kind}; export covers "
            + ", ".join(f"{k} ({', '.join(v)})" for k, v in MODELS.items())
        )
    if model not in valid:
        raise InstanceError(
            f"unknown model {model!r} for a {kind}: choose one of {', '.join(valid)}"
        )
    if kind == "AssignmentProblem":
        return _routing(problem, model, cuts)
    if kind == "CapabilityProblem":
        return _capability(problem, model)
    if kind == "DeliveryInstance":
        return _delivery(problem)
    if kind == "SopProblem":
        return _sop(problem, model)
    if kind == "BudgetedProblem":
        return _budgeted(problem, cuts)
    return _fleet(problem)


def export(
    problem: Any,
    model: str,
    path: str | Path,
    format: str | None = None,  # noqa: A002 - the CLI's word
    cuts: Any = None,
) -> Path:
    """Write one of the toolkit's MILPs of ``problem`` as an LP or MPS file.

    Parameters
    ----------
    problem : a family's problem
        :class:`~taopt.routing.problem.AssignmentProblem`, ``CapabilityProblem``,
        ``DeliveryInstance``, ``SopProblem``, ``BudgetedProblem`` or ``FleetProblem``.
    model : str
        One of :data:`~taopt.orchestration.export.MODELS` for the problem's type (e.g.
        ``"dfj"``, ``"mtz"``, ``"flow"``).
    path : str or Path
        Where to write; written atomically (a temporary file renamed into place).
    format : {"lp", "mps"}, optional
        Default: the extension of ``path``.
    cuts : None, "all" or list of subsets
        DFJ models only: the subtour rows (2.5) written. None (default): the pool at the end
        of a cut loop (the file's optimum is the certified optimum); ``"all"``: every subset
        of two or more targets (at most
        :data:`~taopt.orchestration.export.ALL_CUTS_MAX_TARGETS` targets); a list: those.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InstanceError
        An unknown model or format (the message lists the valid ones).
    OutputError
        The file cannot be written.

    Example
    -------
    >>> import numpy as np, tempfile, pathlib, taopt
    >>> problem = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), 2)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     out = taopt.export(problem, "mtz", pathlib.Path(folder) / "ch2.lp")
    ...     "eq2_3_in_0" in out.read_text()
    True

    Notes
    -----
    Names: σ_ij of chapter 2 is ``sigma_i_j`` (targets ``0..n-1``, start points
    ``n..n+m-1``), rows ``eq2_3_in_j`` (2.3), ``eq2_4_out_i`` (2.4), ``eq2_5_dfj_<S>``,
    ``eq2_5_mtz_i_j``, ``eq2_5_flow_*`` (2.5); chapter 3's σ_ijk ``sigma_i_j_k`` (k a
    vehicle for ``printed``, the class for ``joint``); chapter 5's ``y_p_i_j_k``, ``w_p_k_i``,
    ``S_p``, ``t_p``, ``R_p``; a row of any other labelled constraint is named by its
    equation number and first words (:func:`~taopt.orchestration.export.label_name`) and its
    index.

    References
    ----------
    Thesis §2.2.1 (2.2)–(2.5), §3.2 (3.1)–(3.3), §5.2.2 (5.1)–(5.7), §6.2.
    """
    path = Path(path)
    fmt = (format or path.suffix.lstrip(".")).lower()
    if fmt not in FORMATS:
        raise InstanceError(f"{path}: unknown format {fmt!r}: choose one of {', '.join(FORMATS)}")
    highs = export_model(problem, model, cuts)
    if path.suffix.lower() != "." + fmt:
        raise InstanceError(f"{path}: a {fmt} file must end in .{fmt} (HiGHS picks by extension)")
    from taopt.runtime.highs import stdout_discarded

    with atomic_path(path) as tmp:
        with stdout_discarded():
            status = highs.writeModel(str(tmp))
        if not tmp.exists() or status == highspy_status_error():
            raise OutputError(f"{path}: HiGHS could not write the model")
    return path


def highspy_status_error() -> Any:
    import highspy

    return highspy.HighsStatus.kError
