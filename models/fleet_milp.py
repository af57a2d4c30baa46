"""The fleet family's teaching MILP (HiGHS): positions, sortie slots and big-M times.

It certifies tiny instances (n <= 5 or so; the exact method of the family reaches further) and
reads like the timing rules of :mod:`taopt.fleet.evaluate`, one labelled family of rows per
rule; ``print(build(problem).problem)`` shows them (a cvxpy view of the same rows, one
labelled constraint per family). The equations are in ``docs/families/fleet.md`` ("The
teaching MILP").

Building and solving under a wall-clock limit
---------------------------------------------
The rows are generated family by family with numpy into one sparse matrix and passed to
HiGHS as arrays (no cvxpy on the solving path: at n = 10, K = 2, D = 2, c = 2, 253k rows and a
million nonzeros, the Python row loop and cvxpy's compilation took 3.5 s + 0.6 s, the arrays
0.2-0.5 s). The deadline is looked at before each family (:class:`BuildTimeout`). A big model
(:data:`WORKER_MIN_NONZEROS`) under a limit is run by HiGHS in a worker process
(:func:`~taopt.runtime.highs.run_arrays`), stopped at the limit by its ``time_limit`` and its
interrupt callbacks and, when it is in a phase that looks at neither (its presolve, the IPX
analytic centre its MIP solver computes at the root), killed. Whenever the limit comes first
the incumbent is returned with the family's lower bound (:func:`taopt.fleet.bounds.fleet_lower`)
and status ``time_limit``.

Sets and sizes
--------------
Trucks k with positions p = 0..P−1, ``P = 1 + 2n`` (an optimal plan needs no more: every
position after the depot can be made to hold an event, and a truck has at most one event per
customer it serves and two per sortie); drones (k, d) with sortie slots σ = 0..S−1 (S the
drone-servable customers), each with customer slots i = 0..c−1.

Variables
---------
binary ``y[k,p,w]`` truck k's position p is stop w; ``x[k,p,j]`` truck k serves j at p;
``u[σ]`` sortie σ is flown; ``lp[σ,p]``, ``rp[σ,p]`` launched / recovered at position p;
``ls[σ,w]``, ``rs[σ,w]`` at stop w (the products ``lp·y``, ``rp·y``); ``z[σ,i,j]`` customer j
in slot i of σ. Continuous ``A[k,p]``, ``Dep[k,p]`` (arrival, departure), ``δ[k,p]`` (drive p ->
p+1), ``t_j`` (service), ``L[σ]``, ``T[σ,i]``, ``B[σ]``, ``R[σ]`` (launch, slot service, back,
recovery), ``out[σ]``, ``mid[σ,i]``, ``back[σ]`` (flight legs, for the range), f.

Big-M
-----
H = U + P·max tt + 2 (max flight time + 2τ) + 1, U the incumbent's objective (or a greedy
plan's). Every time of the earliest schedule of an optimal plan is at most H: under
``"return"`` every event precedes the last return (<= U); under ``"last_service"`` every
service is at most f* <= U and what follows is one drive per remaining position and one
flight home plus τ per drone. A row "X >= Y + c − H (1 − indicator)" is then slack whenever
its indicator is 0, and exact when it is 1.

Why the optimum is the family's: every row is a lower bound of :mod:`taopt.fleet.evaluate`'s
(waiting is allowed everywhere), so the times of any feasible point are at least the earliest
schedule of its decoded plan, and the earliest schedule of any plan (within the sizes above)
is a feasible point. So the model's optimum equals the best earliest-schedule objective, and
the decoded plan re-scored by :func:`taopt.evaluate` equals the model's objective at an
optimum (checked; a mismatch raises).
"""

from __future__ import annotations

import math
import os
import time
from concurrent.futures import wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp

from taopt.errors import InstanceError, SolverError
from taopt.fleet.bounds import fleet_lower
from taopt.fleet.evaluate import as_plan, evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.models.highs import CLOCKLESS_MIP_PHASES, HighsModel, HighsRun, highs_outcome
from taopt.registry import register_method
from taopt.result import INFEASIBLE, OPTIMAL, TIME_LIMIT, Solution, finish
from taopt.runtime import MARGIN, Deadline
from taopt.runtime.deadline import overrun_allowance
from taopt.runtime.highs import run_arrays
from taopt.runtime.workers import drop_pool, shared_pool
from taopt.status import STOPS

#: A model with at least this many nonzeros, solved under a time limit, is run in a worker
#: process (:func:`~taopt.runtime.highs.run_arrays`), killed if HiGHS overruns the limit in
#: a phase that looks at neither its clock nor its callbacks. n = 10, K = 2, D = 2, c = 2
#: has a million nonzeros: HiGHS 1.16's presolve took 12 s for a 10 s limit, and the IPX
#: analytic centre it computes at the root of a MIP (unconditionally, without a clock)
#: 8.6 s, at load 10 on 2 cores. Smaller models run here (no process start-up).
WORKER_MIN_NONZEROS = 100_000

#: The share of :func:`~taopt.runtime.deadline.overrun_allowance` the owner waits past the
#: deadline for HiGHS in a worker before killing it (0.25 s for limits up to 20 s).
KILL_GRACE = 0.25

#: A big model (run in a worker) is not handed to HiGHS with fewer seconds left than this:
#: the worker's start-up alone takes about that under load, and HiGHS's presolve of such a
#: model longer; the run then ends at once with the incumbent and the family's bound.
WORKER_MIN_SECONDS = 1.0

_POOL_KEY = ("fleet-milp", 1)


class BuildTimeout(Exception):
    """The deadline passed while the rows were generated (caught by
    :func:`solve_fleet_milp`, which then returns its incumbent; never seen by a caller)."""


class _Columns:
    """The model's columns, allocated a named block at a time (one numpy array of column
    indices per variable, -1 where an entry does not exist)."""

    def __init__(self) -> None:
        self.count = 0
        self.binary: list[np.ndarray] = []
        self.index: dict[str, np.ndarray] = {}

    def add(self, name: str, shape: tuple[int, ...], binary: bool, mask: Any = None) -> np.ndarray:
        keep = np.ones(shape, dtype=bool) if mask is None else np.broadcast_to(mask, shape)
        cols = np.full(shape, -1, dtype=np.int64)
        size = int(keep.sum())
        cols[keep] = self.count + np.arange(size)
        if binary:
            self.binary.append(cols[keep])
        self.count += size
        self.index[name] = cols
        return cols

    @staticmethod
    def names_of(index: dict[str, np.ndarray], count: int) -> list[str]:
        """``<variable>_<index>`` per column (``y_0_3_5`` is y[k=0, p=3, w=5])."""
        out = [""] * count
        for name, cols in index.items():
            if cols.ndim == 0:
                out[int(cols)] = name
                continue
            for key in zip(*np.nonzero(cols >= 0), strict=True):
                out[int(cols[key])] = "_".join([name, *(str(int(k)) for k in key)])
        return out


class _Rows:
    """Sparse rows ``Σ coef·column (>= | ==) rhs`` grouped in labelled families, generated a
    block at a time from numpy arrays (no Python loop over rows)."""

    def __init__(self, deadline: Deadline | None = None) -> None:
        self.families: list[dict[str, Any]] = []
        self.deadline = deadline
        self.count = 0
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []
        self._vals: list[np.ndarray] = []
        self._lower: list[np.ndarray] = []
        self._upper: list[np.ndarray] = []

    def family(self, label: str, sense: str, implements: str) -> None:
        if self.deadline is not None and self.deadline.expired():
            raise BuildTimeout(label)
        self.families.append(
            {"label": label, "sense": sense, "implements": implements, "start": self.count}
        )

    def add(
        self,
        rhs: Any,
        terms: list[tuple[Any, Any]],
        mask: Any = None,
    ) -> None:
        """Rows of shape ``np.shape(rhs)``: each term is ``(columns, coefficients)``, both
        broadcastable to that shape plus one trailing axis (the terms summed in a row);
        ``mask`` (same shape as ``rhs``) keeps only some rows. Columns -1 are left out."""
        rhs = np.asarray(rhs, dtype=float)
        shape = rhs.shape
        keep = np.ones(shape, dtype=bool) if mask is None else np.broadcast_to(mask, shape)
        number = np.full(shape, -1, dtype=np.int64)
        size = int(keep.sum())
        number[keep] = self.count + np.arange(size)
        for cols, coefs in terms:
            cols = np.asarray(cols)
            coefs = np.asarray(coefs, dtype=float)
            full = np.broadcast_shapes(cols.shape, coefs.shape, (*shape, 1))
            r = np.broadcast_to(number[..., None], full).ravel()
            cc = np.broadcast_to(cols, full).ravel()
            vv = np.broadcast_to(coefs, full).ravel()
            ok = (r >= 0) & (cc >= 0) & (vv != 0.0)
            self._rows.append(r[ok])
            self._cols.append(cc[ok])
            self._vals.append(vv[ok])
        values = rhs[keep]
        self._lower.append(values)
        sense = self.families[-1]["sense"]
        self._upper.append(values if sense == "==" else np.full(size, np.inf))
        self.count += size

    def arrays(self, n_columns: int) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
        """The rows as one sparse matrix (duplicate entries summed), lower and upper sides."""
        matrix = sp.csr_matrix(
            (np.concatenate(self._vals), (np.concatenate(self._rows), np.concatenate(self._cols))),
            shape=(self.count, n_columns),
        )
        return matrix, np.concatenate(self._lower), np.concatenate(self._upper)


@dataclass
class FleetMilp:
    """The built model: its rows as arrays (passed straight to HiGHS), the index maps and
    the row families.

    Attributes
    ----------
    index : dict
        Variable name -> numpy array of its column numbers (``index["y"][k, p, w]``), -1
        where the entry does not exist (``x`` of a drone-only customer, ``mid[σ, 0]``).
    matrix, lower, upper, cost, binary
        ``min cost·x`` subject to ``lower <= matrix·x <= upper``, ``x >= 0``, the columns
        ``binary`` in {0, 1}.
    families : list of dict
        Per labelled row family: ``label``, ``rows`` (how many), ``implements`` (the rule),
        ``start`` (its first row).
    """

    index: dict[str, np.ndarray]
    positions: int
    sorties: list[tuple[int, int, int]]  # σ -> (k, d, slot)
    matrix: sp.csr_matrix
    lower: np.ndarray
    upper: np.ndarray
    cost: np.ndarray
    binary: np.ndarray
    families: list[dict[str, Any]] = field(default_factory=list)
    big_m: float = 0.0

    @property
    def n_columns(self) -> int:
        return int(self.matrix.shape[1])

    def column_names(self) -> list[str]:
        """``<variable>_<index>`` per column (``y_0_3_5`` is y[k=0, p=3, w=5], ``f``)."""
        return _Columns.names_of(self.index, self.n_columns)

    def row_names(self) -> list[str]:
        """``<label stem>_<r>`` per row, r counted within its family (``eqF4_every_customer
        _served_2``: the third row of (F4)); :func:`~taopt.orchestration.export.label_name`."""
        from taopt.orchestration.export import label_name

        names: list[str] = []
        for fam in self.families:
            stem = label_name(fam["label"])
            names += [f"{stem}_{r}" for r in range(fam["rows"])]
        return names

    @property
    def problem(self) -> cp.Problem:
        """The same model as a cvxpy problem, one labelled constraint per row family (binary
        columns in a boolean variable ``binary``, the others in ``time``):
        ``print(build(problem).problem)`` reads it. Built on request (tiny instances)."""
        binary = np.zeros(self.n_columns, dtype=bool)
        binary[self.binary] = True
        xb = cp.Variable(int(binary.sum()), boolean=True, name="binary")
        xc = cp.Variable(int((~binary).sum()), nonneg=True, name="time")
        by_column = self.matrix.tocsc()
        parts = (by_column[:, np.flatnonzero(binary)], by_column[:, np.flatnonzero(~binary)])
        constraints = []
        for fam in self.families:
            rows = slice(fam["start"], fam["start"] + fam["rows"])
            lhs = parts[0][rows] @ xb + parts[1][rows] @ xc
            con = lhs == self.lower[rows] if fam["sense"] == "==" else lhs >= self.lower[rows]
            con.set_label(fam["label"])
            constraints.append(con)
        cost = (self.cost[binary] @ xb if self.cost[binary].any() else 0) + (
            self.cost[~binary] @ xc
        )
        return cp.Problem(cp.Minimize(cost), constraints)

    def arrays(self) -> dict[str, Any]:
        """The model as :func:`~taopt.runtime.highs.run_arrays` takes it (the matrix by
        columns)."""
        by_column = self.matrix.tocsc()
        by_column.sort_indices()
        binary = _mask(self.binary, self.n_columns)
        return {
            "cost": self.cost,
            "lower": self.lower,
            "upper": self.upper,
            "column_lower": np.zeros(self.n_columns),
            "column_upper": np.where(binary, 1.0, np.inf),
            "start": by_column.indptr,
            "index": by_column.indices,
            "value": by_column.data,
            "integrality": binary.astype(np.int32),
        }

    def highs(self, names: bool = False, verbose: bool = False) -> HighsModel:
        """The model in a live HiGHS object (one ``passModel`` of the arrays); with
        ``names``, every column and row named (``y_0_3_5``, ``eqF4_every_customer_served_2``)."""
        model = HighsModel.from_arrays(
            self.cost,
            self.matrix,
            self.lower,
            self.upper,
            column_lower=np.zeros(self.n_columns),
            column_upper=np.where(_mask(self.binary, self.n_columns), 1.0, np.inf),
            integers=self.binary,
            verbose=verbose,
        )
        if names:
            for j, name in enumerate(self.column_names()):
                model.highs.passColName(j, name)
            for r, name in enumerate(self.row_names()):
                model.highs.passRowName(r, name)
        return model


def _mask(columns: np.ndarray, size: int) -> np.ndarray:
    out = np.zeros(size, dtype=bool)
    out[columns] = True
    return out


def _horizon(problem: FleetProblem, upper: float, positions: int) -> float:
    tt_max = float(problem.truck_time.max())
    span = float(np.hypot(*(np.ptp(np.vstack([problem.customers, problem.stops]), axis=0))))
    fly = min(problem.flight_range, 2.0 * span) / problem.v_drone
    return upper + positions * tt_max + 2.0 * (fly + 2.0 * problem.service_time) + 1.0


def build(
    problem: FleetProblem, upper: float | None = None, deadline: Deadline | None = None
) -> FleetMilp:
    """Build the model (module docstring) with big-M from ``upper``, a feasible objective
    (default: the objective of the one-by-one plan, :func:`describe`'s).

    The rows are generated family by family with numpy (no Python loop over rows: the
    n = 10, K = 2, D = 2, c = 2 model of 253k rows takes a fraction of a second), and the
    deadline is looked at before each family.

    Raises
    ------
    InstanceError
        ``upper`` is not finite.
    BuildTimeout
        ``deadline`` expired before the last family was generated.
    """
    if upper is None:
        upper = evaluate_fleet(problem, _one_by_one(problem))
    if not math.isfinite(upper):
        raise InstanceError("the fleet MILP needs a finite upper bound (a feasible plan)")
    n, s, K = problem.n, problem.s, problem.K
    c = problem.capacity
    P = 1 + 2 * n
    tt = np.asarray(problem.truck_time, dtype=float)
    fs = np.asarray(problem.flight_stop, dtype=float)
    fc = np.asarray(problem.flight_customer, dtype=float)
    vd, tau = problem.v_drone, problem.service_time
    H = _horizon(problem, upper, P)
    drone_js = np.array([j for j in range(n) if problem.drone_servable(j)], dtype=np.int64)
    truck_js = np.array([j for j in range(n) if problem.truck_servable(j)], dtype=np.int64)
    S = len(drone_js)
    sorties = [(k, d, q) for k in range(K) for d in range(problem.drones[k]) for q in range(S)]
    G = len(sorties)
    sk = np.array([k for k, _, _ in sorties], dtype=np.int64)  # σ -> its truck
    sq = np.array([q for _, _, q in sorties], dtype=np.int64)  # σ -> its slot
    truck_ok = np.zeros(n, dtype=bool)
    truck_ok[truck_js] = True
    drone_ok = np.zeros(n, dtype=bool)
    drone_ok[drone_js] = True

    # ---- variables ------------------------------------------------------------------------
    col = _Columns()
    y = col.add("y", (K, P, s), True)
    x = col.add("x", (K, P, n), True, truck_ok)
    A = col.add("A", (K, P), False)
    Dep = col.add("Dep", (K, P), False)
    delta = col.add("delta", (K, max(P - 1, 0)), False)
    t = col.add("t", (n,), False)
    f = col.add("f", (), False)
    u = col.add("u", (G,), True)
    L = col.add("L", (G,), False)
    B = col.add("B", (G,), False)
    R = col.add("R", (G,), False)
    out = col.add("out", (G,), False)
    back = col.add("back", (G,), False)
    lp = col.add("lp", (G, P), True)
    rp = col.add("rp", (G, P), True)
    ls = col.add("ls", (G, s), True)
    rs = col.add("rs", (G, s), True)
    T = col.add("T", (G, c), False)
    mid = col.add("mid", (G, c), False, np.arange(c) > 0)
    z = col.add("z", (G, c, n), True, drone_ok)
    zd = z[:, :, drone_js]  # (G, c, S): the drone-servable customers only
    pos = np.arange(P, dtype=float)
    one = np.ones(1)

    rows = _Rows(deadline)
    # ---- trucks ---------------------------------------------------------------------------
    rows.family("(F1) one stop per position", "==", "Σ_w y[k,p,w] = 1, y[k,0,depot] = 1")
    rows.add(np.ones((K, P)), [(y, one)])
    rows.add(np.ones(K), [(y[:, 0, problem.depot, None], one)])
    rows.family(
        "(F2) drive between positions", ">=", "δ[k,p] >= tt[w,w'] (y[k,p,w] + y[k,p+1,w'] − 1)"
    )
    if P > 1:
        cost = tt[None, None, :, :, None]
        rows.add(
            np.broadcast_to(-tt, (K, P - 1, s, s)),
            [
                (delta[:, :, None, None, None], one),
                (y[:, :-1, :, None, None], -cost),
                (y[:, 1:, None, :, None], -cost),
            ],
            mask=(~np.eye(s, dtype=bool)) & (tt > 0),
        )
    rows.family("(F3) truck times", ">=", "A[k,p+1] >= Dep[k,p] + δ[k,p], Dep >= A, A[k,0] = 0")
    rows.add(np.zeros((K, P)), [(Dep[..., None], one), (A[..., None], -one)])
    if P > 1:
        rows.add(
            np.zeros((K, P - 1)),
            [(A[:, 1:, None], one), (Dep[:, :-1, None], -one), (delta[..., None], -one)],
        )
    rows.add(np.zeros(K), [(A[:, 0, None], -one)])
    # ---- every customer once ----------------------------------------------------------------
    rows.family("(F4) every customer served once", "==", "Σ x[k,p,j] + Σ z[σ,i,j] = 1")
    rows.add(np.ones(n), [(x.reshape(K * P, n).T, one), (z.reshape(G * c, n).T, one)])
    rows.family(
        "(F5) a truck serves at the customer's stop",
        ">=",
        "x <= y[k,p,stop_j], t_j >= A[k,p] − H(1 − x), Dep[k,p] >= t_j − H(1 − x)",
    )
    if len(truck_js):
        stop_of = np.array([problem.truck_stop(int(j)) for j in truck_js], dtype=np.int64)
        xt = x[:, :, truck_js, None]  # (K, P, m, 1)
        shape = (K, P, len(truck_js))
        rows.add(np.zeros(shape), [(y[:, :, stop_of, None], one), (xt, -one)])
        rows.add(
            np.full(shape, -H),
            [(t[None, None, truck_js, None], one), (A[:, :, None, None], -one), (xt, -H * one)],
        )
        rows.add(
            np.full(shape, -H),
            [(Dep[:, :, None, None], one), (t[None, None, truck_js, None], -one), (xt, -H * one)],
        )
    # ---- sorties ----------------------------------------------------------------------------
    rows.family(
        "(F6) a flown sortie has one launch and one recovery, in order",
        "==",
        "Σ_p lp = u, Σ_p rp = u",
    )
    rows.add(np.zeros(G), [(lp, one), (u[:, None], -one)])
    rows.add(np.zeros(G), [(rp, one), (u[:, None], -one)])
    rows.family(
        "(F6') recovery not before launch; a drone's sorties in order",
        ">=",
        "Σ p rp[σ] >= Σ p lp[σ]; Σ p lp[σ+1] >= Σ p rp[σ] − P(1 − u[σ+1]); u[σ+1] <= u[σ]",
    )
    rows.add(np.zeros(G), [(rp, pos), (lp, -pos)])
    nxt = np.flatnonzero(sq + 1 < S)  # σ with a next slot σ + 1 on the same drone
    rows.add(
        np.full(len(nxt), -float(P)),
        [(lp[nxt + 1], pos), (rp[nxt], -pos), (u[nxt + 1, None], -float(P) * one)],
    )
    rows.add(np.zeros(len(nxt)), [(u[nxt, None], one), (u[nxt + 1, None], -one)])
    # drones of a truck used in order (symmetry): the first slot of drone d before d + 1's
    first = np.array(
        [g for g, (k, d, q) in enumerate(sorties) if q == 0 and d + 1 < problem.drones[k]],
        dtype=np.int64,
    )
    rows.add(np.zeros(len(first)), [(u[first, None], one), (u[first + S, None], -one)])
    rows.family(
        "(F7) customer slots filled from the first",
        ">=",
        "Σ_j z[σ,0,j] = u[σ], Σ_j z[σ,i,j] >= Σ_j z[σ,i+1,j]",
    )
    rows.add(np.zeros(G), [(zd[:, 0, :], one), (u[:, None], -one)])
    rows.add(np.zeros(G), [(zd[:, 0, :], -one), (u[:, None], one)])
    if c > 1:
        rows.add(np.zeros((G, c - 1)), [(zd[:, :-1, :], one), (zd[:, 1:, :], -one)])
    rows.family(
        "(F8) launch and recovery stops",
        ">=",
        "ls[σ,w] >= lp[σ,p] + y[k,p,w] − 1 (same for rs), Σ_w ls = Σ_w rs = u",
    )
    for at_stop, at_position in ((ls, lp), (rs, rp)):
        rows.add(np.zeros(G), [(at_stop, -one), (u[:, None], one)])
        rows.add(np.zeros(G), [(at_stop, one), (u[:, None], -one)])
        rows.add(
            np.full((G, P, s), -1.0),
            [
                (at_stop[:, None, :, None], one),
                (at_position[:, :, None, None], -one),
                (y[sk][..., None], -one),
            ],
        )
    rows.family(
        "(F9) launch time",
        ">=",
        "L >= A[k,p] − H(1 − lp), Dep[k,p] >= L − H(1 − lp), L[σ+1] >= R[σ] − H(1 − u[σ+1])",
    )
    rows.add(
        np.full((G, P), -H),
        [(L[:, None, None], one), (A[sk][..., None], -one), (lp[..., None], -H * one)],
    )
    rows.add(
        np.full((G, P), -H),
        [(Dep[sk][..., None], one), (L[:, None, None], -one), (lp[..., None], -H * one)],
    )
    rows.add(
        np.full(len(nxt), -H),
        [(L[nxt + 1, None], one), (R[nxt, None], -one), (u[nxt + 1, None], -H * one)],
    )
    fsd = fs[drone_js]  # (S, s): drone customers to stops
    fcd = fc[np.ix_(drone_js, drone_js)]  # (S, S)
    rows.family(
        "(F10) first customer of a sortie",
        ">=",
        "T[σ,0] >= L + fs(w,j)/v_d + τ − H(2 − z[σ,0,j] − ls[σ,w])",
    )
    rows.add(
        np.broadcast_to(fsd / vd + tau - 2 * H, (G, S, s)),
        [
            (T[:, 0, None, None, None], one),
            (L[:, None, None, None], -one),
            (zd[:, 0, :, None, None], -H * one),
            (ls[:, None, :, None], -H * one),
        ],
    )
    different = ~np.eye(S, dtype=bool)
    rows.family(
        "(F11) next customer of a sortie",
        ">=",
        "T[σ,i] >= T[σ,i−1] + fc(j',j)/v_d + τ − H(2 − z[σ,i−1,j'] − z[σ,i,j])",
    )
    if c > 1:
        rows.add(
            np.broadcast_to(fcd / vd + tau - 2 * H, (G, c - 1, S, S)),
            [
                (T[:, 1:, None, None, None], one),
                (T[:, :-1, None, None, None], -one),
                (zd[:, :-1, :, None, None], -H * one),
                (zd[:, 1:, None, :, None], -H * one),
            ],
            mask=different,
        )
    rows.family(
        "(F12) a drone customer's service time is its slot's",
        ">=",
        "t_j >= T[σ,i] − H(1 − z), T[σ,i] >= t_j − H(1 − z)",
    )
    td = t[drone_js]
    rows.add(
        np.full((G, c, S), -H),
        [(td[None, None, :, None], one), (T[:, :, None, None], -one), (zd[..., None], -H * one)],
    )
    rows.add(
        np.full((G, c, S), -H),
        [(T[:, :, None, None], one), (td[None, None, :, None], -one), (zd[..., None], -H * one)],
    )
    rows.family(
        "(F13) back at the recovery stop",
        ">=",
        "B >= T[σ,i] + fs(j,w)/v_d − H(2 − z[σ,i,j] − rs[σ,w])",
    )
    rows.add(
        np.broadcast_to(fsd / vd - 2 * H, (G, c, S, s)),
        [
            (B[:, None, None, None, None], one),
            (T[:, :, None, None, None], -one),
            (zd[:, :, :, None, None], -H * one),
            (rs[:, None, None, :, None], -H * one),
        ],
    )
    rows.family(
        "(F14) recovery",
        ">=",
        "R >= B + τ − H(1 − u), R >= A[k,p] + τ − H(1 − rp), Dep[k,p] >= R − H(1 − rp)",
    )
    rows.add(np.full(G, tau - H), [(R[:, None], one), (B[:, None], -one), (u[:, None], -H * one)])
    rows.add(
        np.full((G, P), tau - H),
        [(R[:, None, None], one), (A[sk][..., None], -one), (rp[..., None], -H * one)],
    )
    rows.add(
        np.full((G, P), -H),
        [(Dep[sk][..., None], one), (R[:, None, None], -one), (rp[..., None], -H * one)],
    )
    if math.isfinite(problem.flight_range):
        rows.family(
            "(F15) flight range (5.6) over all legs",
            ">=",
            "out + Σ_i mid[σ,i] + back <= range; legs >= distance of the chosen pair",
        )
        leg = fsd[None, :, :, None]  # (1, S, s, 1)
        rows.add(
            np.broadcast_to(-fsd, (G, S, s)),
            [
                (out[:, None, None, None], one),
                (zd[:, 0, :, None, None], -leg),
                (ls[:, None, :, None], -leg),
            ],
        )
        # the back leg from the last used slot i: z[σ,i,j] = 1 and slot i + 1 empty
        leg = fsd[None, None, :, :, None]  # (1, 1, S, s, 1)
        terms = [
            (back[:, None, None, None, None], one),
            (zd[:, :, :, None, None], -leg),
            (rs[:, None, None, :, None], -leg),
        ]
        if c > 1:
            following = np.concatenate([zd[:, 1:, :], np.full((G, 1, S), -1)], axis=1)
            terms.append((following[:, :, None, None, :], leg))
        rows.add(np.broadcast_to(-fsd, (G, c, S, s)), terms)
        if c > 1:
            leg = fcd[None, None, :, :, None]
            rows.add(
                np.broadcast_to(-fcd, (G, c - 1, S, S)),
                [
                    (mid[:, 1:, None, None, None], one),
                    (zd[:, :-1, :, None, None], -leg),
                    (zd[:, 1:, None, :, None], -leg),
                ],
                mask=different,
            )
        rows.add(
            np.full(G, -problem.flight_limit),
            [(out[:, None], -one), (back[:, None], -one), (mid, -one)],
        )
    rows.family("(F16) precedence (5.7) across the fleet", ">=", "t_j >= t_r")
    edges = np.array(list(problem.precedences), dtype=np.int64).reshape(-1, 2)
    rows.add(np.zeros(len(edges)), [(t[edges[:, 1], None], one), (t[edges[:, 0], None], -one)])
    # r before j (transitively) and one truck serving both: r's position comes first. Valid
    # for every plan the scorer accepts (the other order is a waiting cycle there); without
    # it a point whose services share one instant (drives of length 0 between positions at
    # one stop) would decode to such a cycle.
    closure = nx.transitive_closure_dag(problem.precedence_graph)
    pairs = np.array(
        [(r, j) for r, j in closure.edges if truck_ok[r] and truck_ok[j]], dtype=np.int64
    ).reshape(-1, 2)
    if len(pairs) and P > 1:
        rows.family(
            "(F16') precedence on one truck in position order",
            ">=",
            "x[k,p,r] + Σ_{p'<p} x[k,p',j] <= 1",
        )
        earlier = -(np.arange(P)[None, :] < np.arange(P)[:, None]).astype(float)  # [p, p']
        rows.add(
            np.full((len(pairs), K, P), -1.0),
            [
                (x[:, :, pairs[:, 0]].transpose(2, 0, 1)[..., None], -one),
                (x[:, :, pairs[:, 1]].transpose(2, 0, 1)[:, :, None, :], earlier),
            ],
        )
    if problem.objective == "return":
        rows.family(
            "(F17) objective: every truck back",
            ">=",
            "f >= Dep[k,P−1] + Σ_w tt[w,depot] y[k,P−1,w]",
        )
        rows.add(
            np.zeros(K),
            [
                (np.broadcast_to(f, (K, 1)), one),
                (Dep[:, P - 1, None], -one),
                (y[:, P - 1, :], -tt[:, problem.depot]),
            ],
        )
    else:
        rows.family("(F17) objective (5.1): the last service", ">=", "f >= t_j")
        rows.add(np.zeros(n), [(np.broadcast_to(f, (n, 1)), one), (t[:, None], -one)])
    if deadline is not None and deadline.expired():
        raise BuildTimeout("matrix")
    matrix, lower, upper_side = rows.arrays(col.count)
    families = []
    ends = [fam["start"] for fam in rows.families[1:]] + [rows.count]
    for fam, end in zip(rows.families, ends, strict=True):
        if end > fam["start"]:
            families.append({**fam, "rows": end - fam["start"]})
    cost_vector = np.zeros(col.count)
    cost_vector[int(f)] = 1.0
    binary = np.sort(np.concatenate(col.binary)) if col.binary else np.zeros(0, np.int64)
    return FleetMilp(
        index=col.index,
        positions=P,
        sorties=sorties,
        matrix=matrix,
        lower=lower,
        upper=upper_side,
        cost=cost_vector,
        binary=binary,
        families=families,
        big_m=H,
    )


def decode(model: FleetMilp, problem: FleetProblem, values: Any) -> FleetPlan:
    """The plan at a point of the model (``values``, one per column): routes with every
    position, truck services, each drone's flown sorties in order."""
    point = np.round(np.asarray(values, dtype=float)).astype(int)

    def on(name: str, *key: int) -> bool:
        column = int(model.index[name][tuple(key)])
        return column >= 0 and bool(point[column])

    P = model.positions
    routes = []
    served: list[list[tuple[int, int]]] = []
    for k in range(problem.K):
        routes.append([next(w for w in range(problem.s) if on("y", k, p, w)) for p in range(P)])
        served.append(
            [
                (p, j)
                for p in range(P)
                for j in range(problem.n)
                if problem.truck_servable(j) and on("x", k, p, j)
            ]
        )
    flights: list[list[list[Sortie]]] = [[[] for _ in range(dk)] for dk in problem.drones]
    drone_js = [j for j in range(problem.n) if problem.drone_servable(j)]
    for g, (k, d, _) in enumerate(model.sorties):
        if not on("u", g):
            continue
        launch = next(p for p in range(P) if on("lp", g, p))
        recovery = next(p for p in range(P) if on("rp", g, p))
        customers = []
        for i in range(problem.capacity):
            here = [j for j in drone_js if on("z", g, i, j)]
            if here:
                customers.append(here[0])
        flights[k][d].append(Sortie(launch, tuple(customers), recovery))
    return FleetPlan(routes, served, flights)


@register_method(
    FleetProblem,
    "milp",
    category="exact",
    warm_start=("MMA", "SMMA"),
    default=lambda p: p.n <= 3 and p.K * max(p.drones) <= 2,
    not_default="the teaching MILP runs by default only for n <= 3 and K·D_k <= 2 (it is slow "
    "beyond: --methods milp)",
)
def solve_fleet_milp(
    problem: FleetProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    verbose: bool = False,
) -> Solution:
    """The teaching MILP (module docstring) solved by HiGHS: certified on tiny instances.

    ``incumbent`` (a plan or Solution, :func:`taopt.solve` passes MMA's and SMMA's best) sets
    the big-M horizon and HiGHS's objective cut-off; without one, MMA's construction rule is
    not called (models never run heuristics): a plan serving each customer by its own sortie
    or truck visit in a topological order is built instead. ``info``: ``binaries``,
    ``rows``, ``big_m``, ``model_objective``, ``nodes``, ``stopped_by``, ``family_bound``
    (:func:`taopt.fleet.bounds.fleet_lower`, its ``"fast"`` terms under a limit: the bound
    returned when HiGHS proves nothing better) and, when the limit came first,
    ``stopped_in`` (``"build"``: the rows were not all generated in time, or too little time
    was left to hand a big model to HiGHS; ``"highs"``: HiGHS's worker was stopped at the
    limit).

    Under a limit the run keeps the wall-clock contract (module docstring): it ends
    ``time_limit`` with the incumbent and the family's bound, never with an exception.
    """
    began = time.perf_counter()
    deadline = Deadline(time_limit)
    missing = problem.unservable()
    if missing:
        return finish(
            problem,
            None,
            method="milp",
            stop="infeasible",
            bound=float("inf"),
            runtime=time.perf_counter() - began,
            info={"reason": f"customer {missing[0]} can be served by no vehicle"},
        )
    plan = as_plan(incumbent) if incumbent is not None else _one_by_one(problem)
    objective = evaluate_fleet(problem, plan)
    # the family's bound (taopt.lower): what a run stopped before HiGHS proves more returns.
    # Under a limit its fast terms only: chapter 5's bound of a K = D = c = 1 fleet takes
    # seconds at n = 20-40 and is not looked at by any clock
    lower = min(fleet_lower(problem, "fast" if deadline.limited else "auto"), objective)
    info: dict[str, Any] = {"family_bound": lower}

    def stopped(where: str) -> Solution:
        """The incumbent, the family's bound, ``time_limit`` (``interrupted`` when cancelled):
        the limit came first."""
        info["stopped_in"] = where
        return finish(
            problem,
            plan,
            method="milp",
            stop=deadline.reason,
            bound=lower,
            runtime=time.perf_counter() - began,
            info=info,
        )

    left = deadline.remaining()
    if (
        left is not None
        and left >= 2 * WORKER_MIN_SECONDS
        and (_estimated_nonzeros(problem) >= WORKER_MIN_NONZEROS)
    ):
        # a big model under a limit runs in a worker process: start it now, while the rows
        # are built (its start-up, about a second under load, then overlaps the build)
        shared_pool(_POOL_KEY, 1, hide_main=True).submit(os.getpid)
    try:
        model = build(problem, objective, deadline)
    except BuildTimeout:
        return stopped("build")
    info.update(binaries=len(model.binary), rows=int(model.matrix.shape[0]), big_m=model.big_m)
    options: dict[str, Any] = {
        "mip_rel_gap": 1e-9,
        "objective_bound": objective * (1 + 1e-6) + 1e-9,
        "mip_feasibility_tolerance": 1e-9,
        "primal_feasibility_tolerance": 1e-9,
    }
    if deadline.limited:  # leave out the MIP phases that ignore the clock
        options.update({name: limited for name, (limited, _) in CLOCKLESS_MIP_PHASES.items()})
    in_worker = deadline.limited and model.matrix.nnz >= WORKER_MIN_NONZEROS
    left = deadline.remaining()
    if in_worker and left is not None and left < WORKER_MIN_SECONDS:
        return stopped("build")
    out = _run_highs(model, options, deadline, in_worker)
    if out is not None and out["col_value"] is not None:
        point = float(model.cost @ out["col_value"])
        if abs(point - out["objective"]) > 1e-6 * max(1.0, abs(point)):
            # HiGHS's objective is not its point's (a presolve/postsolve slip of HiGHS 1.16,
            # see taopt.models.highs.HighsModel.solve): the same run again without presolve
            out = _run_highs(model, {**options, "presolve": "off"}, deadline, in_worker)
    if out is None:
        return stopped("highs")
    run = _as_run(out, model, deadline.limited)
    if run.solver_status == "solver_error":
        raise SolverError(f"HiGHS failed on the fleet MILP: {run.message}")
    info["nodes"] = run.nodes
    model_objective = float("nan")
    if run.has_point and run.status in (OPTIMAL, TIME_LIMIT, "feasible"):
        decoded = decode(model, problem, out["col_value"])
        value = evaluate_fleet(problem, decoded)
        assert run.objective is not None  # has_point
        model_objective = float(run.objective)
        if value > model_objective + 1e-6 * max(1.0, abs(value)) and run.status == OPTIMAL:
            raise SolverError(
                f"decoded plan scores {value!r} but the fleet MILP says {model_objective!r}"
            )
        if value <= objective:
            plan, objective = decoded, value
    elif run.status not in (INFEASIBLE, TIME_LIMIT):
        raise SolverError(f"HiGHS returned {run.solver_status!r} on the fleet MILP")
    bound = run.bound
    if run.status == INFEASIBLE:
        # the cut-off pruned everything: nothing beats the incumbent by 1e-6 -> it is optimal
        bound = objective / (1 + 1e-6)
    bound = min(max(lower, -math.inf if bound is None else float(bound)), objective)
    stopped_by = "optimal" if run.status in (OPTIMAL, INFEASIBLE) else run.stopped_by
    info.update(model_objective=model_objective)
    return finish(
        problem,
        plan,
        method="milp",
        stop=stopped_by if stopped_by in STOPS else "solver_limit",
        bound=bound,
        runtime=time.perf_counter() - began,
        info=info,
    )


def _estimated_nonzeros(problem: FleetProblem) -> int:
    """A lower estimate of the model's nonzeros, before it is built: the rows (F2) and (F8),
    three nonzeros each."""
    P = 1 + 2 * problem.n
    drone_js = sum(problem.drone_servable(j) for j in range(problem.n))
    sorties = problem.D * drone_js
    return 3 * (problem.K * (P - 1) * problem.s**2 + 2 * sorties * P * problem.s)


def _run_highs(
    model: FleetMilp, options: dict[str, Any], deadline: Deadline, in_worker: bool
) -> dict[str, Any] | None:
    """:func:`~taopt.runtime.highs.run_arrays` on the model, here or in a worker process.

    In a worker, the owner waits until the deadline plus :data:`KILL_GRACE` of the overrun
    allowance; a worker still
    running then (HiGHS in a phase that looks at neither its clock nor its callbacks: the
    presolve of a big model, the IPX analytic centre at the root) is killed, and None is
    returned; also when the run is cancelled. Ctrl-C kills it too, then propagates.
    """
    remaining = deadline.remaining()
    seconds = None if remaining is None else max(remaining - MARGIN, 1e-3)
    grace = KILL_GRACE * overrun_allowance(deadline.seconds or 0.0)
    arrays = model.arrays()
    if not in_worker:
        return run_arrays(arrays, options, seconds, stop=lambda: deadline.cancelled)
    # the worker's limit as an instant: its start-up and the arrays' transfer count
    until = None if seconds is None else time.time() + seconds
    future = shared_pool(_POOL_KEY, 1, hide_main=True).submit(
        run_arrays, arrays, options, until=until
    )
    try:
        while not wait([future], timeout=0.05).done:
            if deadline.cancelled or deadline.expired(-grace):
                drop_pool(_POOL_KEY)
                return None
        return dict(future.result())
    except BrokenProcessPool as exc:
        drop_pool(_POOL_KEY)
        raise SolverError(f"the worker running HiGHS on the fleet MILP died: {exc}") from exc
    except BaseException:
        drop_pool(_POOL_KEY)
        raise


def _as_run(out: dict[str, Any], model: FleetMilp, time_limited: bool) -> HighsRun:
    """What :func:`~taopt.runtime.highs.run_arrays` found, under the status rules of
    :func:`taopt.models.highs.solve_highs`."""
    return highs_outcome(
        out["model_status"],
        out["primal_solution_status"] == 2 and out["col_value"] is not None,
        out["objective"],
        out["mip_dual_bound"],
        out["mip_gap"],
        out["mip_node_count"],
        is_mip=len(model.binary) > 0,
        time_limited=time_limited,
    )


def _one_by_one(problem: FleetProblem) -> FleetPlan:
    """A feasible plan for the big-M: truck 0 (with a drone if it has one, else the first truck
    with one) serves the customers in a topological order, each by itself at its stop or by a
    sortie from and back to the stop nearest the customer."""

    order = list(nx.lexicographical_topological_sort(problem.precedence_graph))
    with_drone = next((k for k in range(problem.K) if problem.drones[k] > 0), -1)
    routes: list[list[int]] = [[problem.depot] for _ in range(problem.K)]
    served: list[list[tuple[int, int]]] = [[] for _ in range(problem.K)]
    flights: list[list[list[Sortie]]] = [[[] for _ in range(dk)] for dk in problem.drones]
    k0 = with_drone if with_drone >= 0 else 0
    for j in order:
        if problem.truck_servable(j) and (with_drone < 0 or not problem.drone_servable(j)):
            routes[0].append(int(problem.customer_stop[j]))
            served[0].append((len(routes[0]) - 1, j))
        else:
            w = int(np.argmin(problem.flight_stop[j]))
            routes[k0].append(w)
            p = len(routes[k0]) - 1
            flights[k0][0].append(Sortie(p, (j,), p))
    return FleetPlan(routes, served, flights)


def describe(problem: FleetProblem) -> list[dict[str, Any]]:
    """The model's row families: label, number of rows, the rule each implements."""
    return build(problem).families


__all__ = ["BuildTimeout", "FleetMilp", "build", "decode", "describe", "solve_fleet_milp"]
