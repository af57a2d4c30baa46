"""The fleet family's teaching MILP (cvxpy + HiGHS): positions, sortie slots and big-M times.

It certifies tiny instances (n <= 5 or so; the exact method of the family reaches further) and
reads like the timing rules of :mod:`taopt.fleet.evaluate`, one labelled family of rows per
rule; ``print(build(problem).problem)`` shows them. The equations are in
``docs/families/fleet.md`` ("The teaching MILP").

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
import time
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np
import scipy.sparse as sp

from taopt.errors import InstanceError, SolverError
from taopt.fleet.evaluate import as_plan, evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.models.highs import solve_highs
from taopt.registry import register_method
from taopt.result import INFEASIBLE, OPTIMAL, TIME_LIMIT, Solution, finish
from taopt.runtime import MARGIN, Deadline
from taopt.status import STOPS


class _Rows:
    """Sparse rows ``a·xb + b·xc (>= | ==) rhs`` grouped in labelled families."""

    def __init__(self) -> None:
        self.families: list[dict[str, Any]] = []
        self._current: dict[str, Any] | None = None

    def family(self, label: str, sense: str, implements: str) -> None:
        self._current = {"label": label, "sense": sense, "implements": implements, "rows": []}
        self.families.append(self._current)

    def row(self, terms: list[tuple[str, int, float]], rhs: float) -> None:
        """terms: (``"b"`` or ``"c"``, column, coefficient)."""
        assert self._current is not None
        self._current["rows"].append((terms, float(rhs)))


@dataclass
class FleetMilp:
    """The built model: the cvxpy problem, its two variable vectors and the index maps."""

    problem: cp.Problem
    xb: cp.Variable
    xc: cp.Variable
    index: dict[str, dict[tuple[int, ...], tuple[str, int]]]
    positions: int
    sorties: list[tuple[int, int, int]]  # σ -> (k, d, slot)
    families: list[dict[str, Any]] = field(default_factory=list)
    big_m: float = 0.0


def _horizon(problem: FleetProblem, upper: float, positions: int) -> float:
    tt_max = float(problem.truck_time.max())
    span = float(np.hypot(*(np.ptp(np.vstack([problem.customers, problem.stops]), axis=0))))
    fly = min(problem.flight_range, 2.0 * span) / problem.v_drone
    return upper + positions * tt_max + 2.0 * (fly + 2.0 * problem.service_time) + 1.0


def build(problem: FleetProblem, upper: float) -> FleetMilp:
    """Build the model (module docstring) with big-M from ``upper``, a feasible objective.

    Raises
    ------
    InstanceError
        ``upper`` is not finite.
    """
    if not math.isfinite(upper):
        raise InstanceError("the fleet MILP needs a finite upper bound (a feasible plan)")
    n, s, K = problem.n, problem.s, problem.K
    c = problem.capacity
    P = 1 + 2 * n
    tt = problem.truck_time
    fs = problem.flight_stop
    fc = problem.flight_customer
    vd, tau = problem.v_drone, problem.service_time
    H = _horizon(problem, upper, P)
    drone_js = [j for j in range(n) if problem.drone_servable(j)]
    truck_js = [j for j in range(n) if problem.truck_servable(j)]
    S = len(drone_js)
    index: dict[str, dict[tuple[int, ...], tuple[str, int]]] = {}
    counts = {"b": 0, "c": 0}

    def var(name: str, key: tuple[int, ...], kind: str) -> tuple[str, int]:
        block = index.setdefault(name, {})
        block[key] = (kind, counts[kind])
        counts[kind] += 1
        return block[key]

    for k in range(K):
        for p in range(P):
            var("A", (k, p), "c")
            var("Dep", (k, p), "c")
            if p + 1 < P:
                var("delta", (k, p), "c")
            for w in range(s):
                var("y", (k, p, w), "b")
            for j in truck_js:
                var("x", (k, p, j), "b")
    for j in range(n):
        var("t", (j,), "c")
    var("f", (), "c")
    sorties = [(k, d, q) for k in range(K) for d in range(problem.drones[k]) for q in range(S)]
    for g, _ in enumerate(sorties):
        var("u", (g,), "b")
        for name in ("L", "B", "R", "out", "back"):
            var(name, (g,), "c")
        for p in range(P):
            var("lp", (g, p), "b")
            var("rp", (g, p), "b")
        for w in range(s):
            var("ls", (g, w), "b")
            var("rs", (g, w), "b")
        for i in range(c):
            var("T", (g, i), "c")
            if i > 0:
                var("mid", (g, i), "c")
            for j in drone_js:
                var("z", (g, i, j), "b")

    def v(name: str, *key: int) -> tuple[str, int]:
        return index[name][tuple(key)]

    def term(name: str, key: tuple[int, ...], coef: float) -> tuple[str, int, float]:
        kind, col = index[name][key]
        return (kind, col, coef)

    rows = _Rows()
    # ---- trucks ---------------------------------------------------------------------------
    rows.family("(F1) one stop per position", "==", "Σ_w y[k,p,w] = 1, y[k,0,depot] = 1")
    for k in range(K):
        for p in range(P):
            rows.row([term("y", (k, p, w), 1.0) for w in range(s)], 1.0)
        rows.row([term("y", (k, 0, problem.depot), 1.0)], 1.0)
    rows.family(
        "(F2) drive between positions", ">=", "δ[k,p] >= tt[w,w'] (y[k,p,w] + y[k,p+1,w'] − 1)"
    )
    for k in range(K):
        for p in range(P - 1):
            for w in range(s):
                for w2 in range(s):
                    if w != w2 and tt[w, w2] > 0:
                        rows.row(
                            [
                                term("delta", (k, p), 1.0),
                                term("y", (k, p, w), -tt[w, w2]),
                                term("y", (k, p + 1, w2), -tt[w, w2]),
                            ],
                            -tt[w, w2],
                        )
    rows.family("(F3) truck times", ">=", "A[k,p+1] >= Dep[k,p] + δ[k,p], Dep >= A, A[k,0] = 0")
    for k in range(K):
        for p in range(P):
            rows.row([term("Dep", (k, p), 1.0), term("A", (k, p), -1.0)], 0.0)
            if p + 1 < P:
                rows.row(
                    [
                        term("A", (k, p + 1), 1.0),
                        term("Dep", (k, p), -1.0),
                        term("delta", (k, p), -1.0),
                    ],
                    0.0,
                )
        rows.row([term("A", (k, 0), -1.0)], 0.0)
    # ---- every customer once ----------------------------------------------------------------
    rows.family("(F4) every customer served once", "==", "Σ x[k,p,j] + Σ z[σ,i,j] = 1")
    for j in range(n):
        terms = []
        if problem.truck_servable(j):
            terms += [term("x", (k, p, j), 1.0) for k in range(K) for p in range(P)]
        if problem.drone_servable(j):
            terms += [term("z", (g, i, j), 1.0) for g in range(len(sorties)) for i in range(c)]
        rows.row(terms, 1.0)
    rows.family(
        "(F5) a truck serves at the customer's stop",
        ">=",
        "x <= y[k,p,stop_j], t_j >= A[k,p] − H(1 − x), Dep[k,p] >= t_j − H(1 − x)",
    )
    for k in range(K):
        for p in range(P):
            for j in truck_js:
                w = problem.truck_stop(j)
                rows.row([term("y", (k, p, w), 1.0), term("x", (k, p, j), -1.0)], 0.0)
                rows.row(
                    [term("t", (j,), 1.0), term("A", (k, p), -1.0), term("x", (k, p, j), -H)], -H
                )
                rows.row(
                    [term("Dep", (k, p), 1.0), term("t", (j,), -1.0), term("x", (k, p, j), -H)],
                    -H,
                )
    # ---- sorties ----------------------------------------------------------------------------
    rows.family(
        "(F6) a flown sortie has one launch and one recovery, in order",
        "==",
        "Σ_p lp = u, Σ_p rp = u",
    )
    for g in range(len(sorties)):
        rows.row([term("lp", (g, p), 1.0) for p in range(P)] + [term("u", (g,), -1.0)], 0.0)
        rows.row([term("rp", (g, p), 1.0) for p in range(P)] + [term("u", (g,), -1.0)], 0.0)
    rows.family(
        "(F6') recovery not before launch; a drone's sorties in order",
        ">=",
        "Σ p rp[σ] >= Σ p lp[σ]; Σ p lp[σ+1] >= Σ p rp[σ] − P(1 − u[σ+1]); u[σ+1] <= u[σ]",
    )
    for g, (k, d, q) in enumerate(sorties):
        rows.row(
            [term("rp", (g, p), float(p)) for p in range(P)]
            + [term("lp", (g, p), -float(p)) for p in range(P)],
            0.0,
        )
        if q + 1 < S:
            h = g + 1
            rows.row(
                [term("lp", (h, p), float(p)) for p in range(P)]
                + [term("rp", (g, p), -float(p)) for p in range(P)]
                + [term("u", (h,), -float(P))],
                -float(P),
            )
            rows.row([term("u", (g,), 1.0), term("u", (h,), -1.0)], 0.0)
        if q == 0 and d + 1 < problem.drones[k]:  # drones of a truck used in order (symmetry)
            rows.row([term("u", (g,), 1.0), term("u", (g + S,), -1.0)], 0.0)
    rows.family(
        "(F7) customer slots filled from the first",
        ">=",
        "Σ_j z[σ,0,j] = u[σ], Σ_j z[σ,i,j] >= Σ_j z[σ,i+1,j]",
    )
    for g in range(len(sorties)):
        rows.row([term("z", (g, 0, j), 1.0) for j in drone_js] + [term("u", (g,), -1.0)], 0.0)
        rows.row([term("z", (g, 0, j), -1.0) for j in drone_js] + [term("u", (g,), 1.0)], 0.0)
        for i in range(c - 1):
            rows.row(
                [term("z", (g, i, j), 1.0) for j in drone_js]
                + [term("z", (g, i + 1, j), -1.0) for j in drone_js],
                0.0,
            )
    rows.family(
        "(F8) launch and recovery stops",
        ">=",
        "ls[σ,w] >= lp[σ,p] + y[k,p,w] − 1 (same for rs), Σ_w ls = Σ_w rs = u",
    )
    for g, (k, _, _) in enumerate(sorties):
        for name, pos in (("ls", "lp"), ("rs", "rp")):
            rows.row([term(name, (g, w), -1.0) for w in range(s)] + [term("u", (g,), 1.0)], 0.0)
            rows.row([term(name, (g, w), 1.0) for w in range(s)] + [term("u", (g,), -1.0)], 0.0)
            for p in range(P):
                for w in range(s):
                    rows.row(
                        [
                            term(name, (g, w), 1.0),
                            term(pos, (g, p), -1.0),
                            term("y", (k, p, w), -1.0),
                        ],
                        -1.0,
                    )
    rows.family(
        "(F9) launch time",
        ">=",
        "L >= A[k,p] − H(1 − lp), Dep[k,p] >= L − H(1 − lp), L[σ+1] >= R[σ] − H(1 − u[σ+1])",
    )
    for g, (k, _, q) in enumerate(sorties):
        for p in range(P):
            rows.row([term("L", (g,), 1.0), term("A", (k, p), -1.0), term("lp", (g, p), -H)], -H)
            rows.row([term("Dep", (k, p), 1.0), term("L", (g,), -1.0), term("lp", (g, p), -H)], -H)
        if q + 1 < S:
            rows.row([term("L", (g + 1,), 1.0), term("R", (g,), -1.0), term("u", (g + 1,), -H)], -H)
    rows.family(
        "(F10) first customer of a sortie",
        ">=",
        "T[σ,0] >= L + fs(w,j)/v_d + τ − H(2 − z[σ,0,j] − ls[σ,w])",
    )
    for g in range(len(sorties)):
        for j in drone_js:
            for w in range(s):
                rows.row(
                    [
                        term("T", (g, 0), 1.0),
                        term("L", (g,), -1.0),
                        term("z", (g, 0, j), -H),
                        term("ls", (g, w), -H),
                    ],
                    fs[j, w] / vd + tau - 2 * H,
                )
    rows.family(
        "(F11) next customer of a sortie",
        ">=",
        "T[σ,i] >= T[σ,i−1] + fc(j',j)/v_d + τ − H(2 − z[σ,i−1,j'] − z[σ,i,j])",
    )
    for g in range(len(sorties)):
        for i in range(1, c):
            for j1 in drone_js:
                for j2 in drone_js:
                    if j1 == j2:
                        continue
                    rows.row(
                        [
                            term("T", (g, i), 1.0),
                            term("T", (g, i - 1), -1.0),
                            term("z", (g, i - 1, j1), -H),
                            term("z", (g, i, j2), -H),
                        ],
                        fc[j1, j2] / vd + tau - 2 * H,
                    )
    rows.family(
        "(F12) a drone customer's service time is its slot's",
        ">=",
        "t_j >= T[σ,i] − H(1 − z), T[σ,i] >= t_j − H(1 − z)",
    )
    for g in range(len(sorties)):
        for i in range(c):
            for j in drone_js:
                rows.row(
                    [term("t", (j,), 1.0), term("T", (g, i), -1.0), term("z", (g, i, j), -H)], -H
                )
                rows.row(
                    [term("T", (g, i), 1.0), term("t", (j,), -1.0), term("z", (g, i, j), -H)], -H
                )
    rows.family(
        "(F13) back at the recovery stop",
        ">=",
        "B >= T[σ,i] + fs(j,w)/v_d − H(2 − z[σ,i,j] − rs[σ,w])",
    )
    for g in range(len(sorties)):
        for i in range(c):
            for j in drone_js:
                for w in range(s):
                    rows.row(
                        [
                            term("B", (g,), 1.0),
                            term("T", (g, i), -1.0),
                            term("z", (g, i, j), -H),
                            term("rs", (g, w), -H),
                        ],
                        fs[j, w] / vd - 2 * H,
                    )
    rows.family(
        "(F14) recovery",
        ">=",
        "R >= B + τ − H(1 − u), R >= A[k,p] + τ − H(1 − rp), Dep[k,p] >= R − H(1 − rp)",
    )
    for g, (k, _, _) in enumerate(sorties):
        rows.row([term("R", (g,), 1.0), term("B", (g,), -1.0), term("u", (g,), -H)], tau - H)
        for p in range(P):
            rows.row(
                [term("R", (g,), 1.0), term("A", (k, p), -1.0), term("rp", (g, p), -H)], tau - H
            )
            rows.row([term("Dep", (k, p), 1.0), term("R", (g,), -1.0), term("rp", (g, p), -H)], -H)
    if math.isfinite(problem.flight_range):
        span = float(fs.max()) + float(fc.max() if n > 1 else 0.0)
        rows.family(
            "(F15) flight range (5.6) over all legs",
            ">=",
            "out + Σ_i mid[σ,i] + back <= range; legs >= distance of the chosen pair",
        )
        for g in range(len(sorties)):
            for j in drone_js:
                for w in range(s):
                    rows.row(
                        [
                            term("out", (g,), 1.0),
                            term("z", (g, 0, j), -fs[j, w]),
                            term("ls", (g, w), -fs[j, w]),
                        ],
                        -fs[j, w],
                    )
                    for i in range(c):
                        # the last used slot: z[σ,i,j] = 1 and slot i+1 empty
                        nxt = (
                            [term("z", (g, i + 1, j2), fs[j, w]) for j2 in drone_js]
                            if i + 1 < c
                            else []
                        )
                        rows.row(
                            [
                                term("back", (g,), 1.0),
                                term("z", (g, i, j), -fs[j, w]),
                                term("rs", (g, w), -fs[j, w]),
                            ]
                            + nxt,
                            -fs[j, w],
                        )
            for i in range(1, c):
                for j1 in drone_js:
                    for j2 in drone_js:
                        if j1 != j2:
                            rows.row(
                                [
                                    term("mid", (g, i), 1.0),
                                    term("z", (g, i - 1, j1), -fc[j1, j2]),
                                    term("z", (g, i, j2), -fc[j1, j2]),
                                ],
                                -fc[j1, j2],
                            )
            rows.row(
                [term("out", (g,), -1.0), term("back", (g,), -1.0)]
                + [term("mid", (g, i), -1.0) for i in range(1, c)],
                -problem.flight_limit,
            )
        del span
    rows.family("(F16) precedence (5.7) across the fleet", ">=", "t_j >= t_r")
    for r, j in problem.precedences:
        rows.row([term("t", (j,), 1.0), term("t", (r,), -1.0)], 0.0)
    if problem.objective == "return":
        rows.family(
            "(F17) objective: every truck back",
            ">=",
            "f >= Dep[k,P−1] + Σ_w tt[w,depot] y[k,P−1,w]",
        )
        for k in range(K):
            rows.row(
                [term("f", (), 1.0), term("Dep", (k, P - 1), -1.0)]
                + [term("y", (k, P - 1, w), -tt[w, problem.depot]) for w in range(s)],
                0.0,
            )
    else:
        rows.family("(F17) objective (5.1): the last service", ">=", "f >= t_j")
        for j in range(n):
            rows.row([term("f", (), 1.0), term("t", (j,), -1.0)], 0.0)
    xb = cp.Variable(counts["b"], boolean=True, name="binary")
    xc = cp.Variable(counts["c"], nonneg=True, name="time")
    constraints: list[cp.Constraint] = []
    families = []
    for fam in rows.families:
        if not fam["rows"]:
            continue
        data: dict[str, tuple[list[int], list[int], list[float]]] = {
            "b": ([], [], []),
            "c": ([], [], []),
        }
        rhs = []
        for r, (terms, value) in enumerate(fam["rows"]):
            for kind, col, coef in terms:
                data[kind][0].append(r)
                data[kind][1].append(col)
                data[kind][2].append(coef)
            rhs.append(value)
        m = len(rhs)
        lhs: cp.Expression = cp.Constant(0)  # what `0 + expression` builds
        for kind, x in (("b", xb), ("c", xc)):
            rr, cc, vv = data[kind]
            if rr:
                lhs = lhs + sp.csr_matrix((vv, (rr, cc)), shape=(m, counts[kind])) @ x
        con = lhs == np.array(rhs) if fam["sense"] == "==" else lhs >= np.array(rhs)
        con.set_label(fam["label"])
        constraints.append(con)
        families.append({"label": fam["label"], "rows": m, "implements": fam["implements"]})
    objective = cp.Minimize(xc[v("f")[1]])
    return FleetMilp(
        cp.Problem(objective, constraints), xb, xc, index, P, sorties, families, big_m=H
    )


def decode(model: FleetMilp, problem: FleetProblem) -> FleetPlan:
    """The plan at the model's current point (routes with every position, truck services,
    each drone's flown sorties in order)."""
    xb = np.round(np.asarray(model.xb.value)).astype(int)

    def on(name: str, *key: int) -> bool:
        return bool(xb[model.index[name][tuple(key)][1]])

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
    ``rows``, ``big_m``, ``model_objective``, ``nodes``, ``stopped_by``.
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
    known: tuple[float, FleetPlan] | None = None
    if incumbent is not None:
        plan = as_plan(incumbent)
        known = (evaluate_fleet(problem, plan), plan)
    else:
        plan = _one_by_one(problem)
        known = (evaluate_fleet(problem, plan), plan)
    upper = known[0]
    model = build(problem, upper)
    limit = None
    remaining = deadline.remaining()
    if remaining is not None:  # deadline.limited
        limit = max(remaining - MARGIN, 1e-3)
    run = solve_highs(
        model.problem,
        time_limit=limit,
        mip_rel_gap=1e-9,
        objective_bound=upper * (1 + 1e-6) + 1e-9,
        verbose=verbose,
        extra={"mip_feasibility_tolerance": 1e-9, "primal_feasibility_tolerance": 1e-9},
    )
    if run.solver_status == "solver_error":
        raise SolverError(f"HiGHS failed on the fleet MILP: {run.message}")
    info: dict[str, Any] = {
        "binaries": int(model.xb.size),
        "rows": int(sum(f["rows"] for f in model.families)),
        "big_m": model.big_m,
        "nodes": run.nodes,
    }
    plan, objective = known[1], known[0]
    model_objective = float("nan")
    if run.has_point and run.status in (OPTIMAL, TIME_LIMIT, "feasible"):
        decoded = decode(model, problem)
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
    bound = None if bound is None else min(float(bound), objective)
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


def _one_by_one(problem: FleetProblem) -> FleetPlan:
    """A feasible plan for the big-M: truck 0 (with a drone if it has one, else the first truck
    with one) serves the customers in a topological order, each by itself at its stop or by a
    sortie from and back to the stop nearest the customer."""
    import networkx as nx

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
    upper = evaluate_fleet(problem, _one_by_one(problem))
    return build(problem, upper).families


__all__ = ["FleetMilp", "build", "decode", "describe", "solve_fleet_milp"]
