"""Minimum-time navigation by direct collocation (CasADi + IPOPT), thesis §2.3.

The default and reference method of :func:`taopt.navigation.min_time_path`.
One parametric NLP is built per (field, grid) and reused for every start/goal
pair: start, goal and speed are NLP parameters ``p``, so a whole travel-time
matrix costs one symbolic build and N(N-1) warm IPOPT solves.

Formulation (scaled so that every pair gives the same well-scaled NLP)
-----------------------------------------------------------------------
Let ``D = |goal - start|`` and ``d = (goal - start) / D``. Positions are written
``x = start + D * xi`` with the dimensionless state ``xi`` running from ``0``
to ``d``; time is ``t = T * tau`` with ``tau in [0, 1]`` and ``T = s * D / v``,
so ``s`` is the travel time in units of the still-water time ``D / v``. The
kinematics (2.1) with thrust direction ``u = (cos psi, sin psi)`` become

    d xi / d tau = s * (u + v_c(start + D xi) / v),            (2.1) scaled

and the problem is: minimise ``s`` subject to those dynamics, ``|u|^2 <= 1``,
``xi(0) = 0`` and ``xi(1) = d``.

Why ``|u| <= 1`` is exact. The relaxation lets the vehicle thrust slower than
``v``. Pontryagin's principle for the relaxed problem has the Hamiltonian
``H = 1 + lambda . (v u + v_c)`` (2.7) with ``H = 0`` along a minimum-time
trajectory (free final time, autonomous dynamics). Then ``lambda != 0`` at every
instant (otherwise ``H = 1``), and minimising the linear function ``lambda . u``
over the disc ``|u| <= 1`` puts ``u = -lambda / |lambda|`` on the circle. So
every relaxed optimum thrusts at full speed and solves the original problem,
and the convex disc constraint (instead of an angle or ``|u| = 1``) gives IPOPT
a much easier problem. Under Assumption 2.1 (``v > |v_c|``) thrusting slower
never helps: the vehicle can always make headway towards the goal.

Discretisation: ``K`` intervals of Legendre (default) or Radau collocation of
degree ``d``; states at interval ends and collocation points, controls at the
collocation points (so the heading is a degree ``d - 1`` polynomial per
interval and converges to the navigation law (2.6) as the grid is refined).
For smooth fields the travel time converges very fast: on the thesis's field
``K = 4, d = 3`` already agrees with a ``K = 32`` solve to about 1e-8.

References
----------
Thesis §2.3 (Lemma 2.2, (2.1), (2.6)-(2.10)); CasADi's ``direct_collocation.py``
and ``race_car.py`` examples for the layout.
"""

from __future__ import annotations

import threading
import time as _time
from typing import Any

import casadi as ca
import numpy as np

from taopt.errors import ConvergenceError
from taopt.fields import Field, field_from_dict
from taopt.navigation.path import Path, as_field, as_point, as_speed, trivial_path
from taopt.navigation.uniform import net_speed

DEFAULT_INTERVALS = 4
DEFAULT_DEGREE = 3
DEFAULT_TOL = 1e-10

# Bounds on the scaled time s = T v / D. Since |v_net| <= v + |v_c| < 2 v, s > 1/2;
# the upper bound only keeps IPOPT away from nonsense (Assumption 2.1 keeps s finite).
_S_MIN, _S_MAX = 0.25, 1e4


def _collocation_matrices(degree: int, scheme: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points ``tau_0 = 0, tau_1..tau_d``, derivative matrix ``C`` and end weights ``D``.

    ``C[r, j]`` is the derivative at ``tau_j`` of the Lagrange basis polynomial of
    ``tau_r``; ``D[r]`` is that basis polynomial at ``tau = 1``.
    """
    tau = np.array([0.0] + list(ca.collocation_points(degree, scheme)))
    n = degree + 1
    C = np.zeros((n, n))
    D = np.zeros(n)
    for r in range(n):
        basis = np.poly1d([1.0])
        for q in range(n):
            if q != r:
                basis *= np.poly1d([1.0, -tau[q]]) / (tau[r] - tau[q])
        D[r] = basis(1.0)
        deriv = np.polyder(basis)
        for j in range(n):
            C[r, j] = deriv(tau[j])
    return tau, C, D


def _control_basis(points: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lagrange basis through ``points`` (values and derivatives) evaluated at ``at``."""
    n = len(points)
    values = np.zeros((len(at), n))
    derivs = np.zeros((len(at), n))
    for r in range(n):
        basis = np.poly1d([1.0])
        for q in range(n):
            if q != r:
                basis *= np.poly1d([1.0, -points[q]]) / (points[r] - points[q])
        values[:, r] = basis(at)
        derivs[:, r] = np.polyder(basis)(at) if n > 1 else 0.0
    return values, derivs


class CollocationSolver:
    """A parametric minimum-time NLP for one field and one grid, reusable for any pair.

    Parameters
    ----------
    field : Field or None
        The drift; None is still water.
    intervals : int
        Number of collocation intervals ``K``.
    degree : int
        Collocation degree ``d`` (points per interval).
    scheme : {"legendre", "radau"}
        Collocation points.
    tol : float
        IPOPT tolerance.

    Example
    -------
    >>> from taopt.fields import thesis_field
    >>> solver = CollocationSolver(thesis_field(1e-2))
    >>> path = solver.solve((10, 20), (80, 60))
    >>> path.success, round(path.time, 3) > 0
    (True, True)

    Notes
    -----
    The NLP has ``2 K d + 2 (K - 1) + 2 K d + 1`` variables; building it costs a
    few tens of milliseconds, each solve a few milliseconds (about 5 IPOPT
    iterations from the straight-line guess). Use :func:`get_solver` to share
    instances.
    """

    def __init__(
        self,
        field: Field | None,
        intervals: int = DEFAULT_INTERVALS,
        degree: int = DEFAULT_DEGREE,
        scheme: str = "legendre",
        tol: float = DEFAULT_TOL,
    ) -> None:
        self.field = as_field(field)
        self.intervals = int(intervals)
        self.degree = int(degree)
        self.scheme = scheme
        self.tol = float(tol)
        if self.intervals < 1 or self.degree < 1:
            raise ValueError("intervals and degree must be positive")
        self._lock = threading.Lock()
        self._build()

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        K, d = self.intervals, self.degree
        tau, C, D = _collocation_matrices(d, self.scheme)
        self._tau = tau
        h = 1.0 / K
        # GriddedField interpolants need MX; analytic fields are faster in SX. (Any: casadi's
        # stubs type each class alone, not code written for either.)
        sym: Any = ca.MX if self.field.kind == "gridded" else ca.SX

        # --- parameters: p = (start_x, start_y, goal_x, goal_y, v)
        p = sym.sym("p", 5)
        start, goal, v = p[0:2], p[2:4], p[4]
        dist = ca.norm_2(goal - start)
        direction = (goal - start) / dist

        # --- variables: scaled time s, states at collocation points and interior
        # interval ends (xi(0) = 0 is not a variable), thrust u at collocation points
        s = sym.sym("s")
        X = sym.sym("xi", 2, K * d + K - 1)
        U = sym.sym("u", 2, K * d)
        w = ca.vertcat(s, ca.vec(X), ca.vec(U))

        # --- objective: the travel time in units of D / v
        objective = s

        g = []
        # --- dynamics (2.1), collocation equations and continuity
        node = ca.DM.zeros(2)  # xi(0) = 0: boundary condition built in
        for k in range(K):
            states = [node] + [X[:, k * d + j] for j in range(d)]
            for j in range(1, d + 1):
                slope = sum(C[r, j] * states[r] for r in range(d + 1))
                position = start + dist * states[j]
                vcx, vcy = self.field.casadi(position[0], position[1])
                rate = s * (U[:, k * d + j - 1] + ca.vertcat(vcx, vcy) / v)
                g.append(slope - h * rate)
            end = sum(D[r] * states[r] for r in range(d + 1))
            if k < K - 1:
                node = X[:, K * d + k]
                g.append(end - node)  # continuity
            else:
                # --- boundary condition xi(1) = d
                g.append(end - direction)
        n_equal = sum(int(gi.shape[0]) for gi in g)
        # --- path constraints: |u|^2 <= 1 (exact relaxation of |u| = 1, see module doc)
        for j in range(K * d):
            g.append(ca.sumsqr(U[:, j]))

        self._n_w = int(w.shape[0])
        self.lbg = np.concatenate([np.zeros(n_equal), np.full(K * d, -np.inf)])
        self.ubg = np.concatenate([np.zeros(n_equal), np.ones(K * d)])
        self.lbx = np.full(self._n_w, -np.inf)
        self.ubx = np.full(self._n_w, np.inf)
        self.lbx[0], self.ubx[0] = _S_MIN, _S_MAX

        options: dict[str, Any] = {
            "print_time": False,
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "ipopt.tol": self.tol,
            # The straight-line guess is close to optimal: start the barrier small.
            "ipopt.mu_init": 1e-6,
            "ipopt.bound_push": 1e-8,
            "ipopt.bound_frac": 1e-8,
            "ipopt.max_iter": 200,
            # IPOPT relaxes bounds by 1e-8 by default, which would let |u| exceed 1 by that much.
            "ipopt.bound_relax_factor": 0.0,
        }
        nlp = {"x": w, "f": objective, "g": ca.vertcat(*g), "p": p}
        self.options = options
        self.nlp = ca.nlpsol("min_time", "ipopt", nlp, options)
        self._batches: dict[int, Any] = {}

        # decode helpers: all sample times (interval ends and collocation points)
        coll = tau[1:]
        self._taus = np.concatenate(
            [np.concatenate([[k * h], (k + coll) * h]) for k in range(K)] + [np.array([1.0])]
        )
        values, derivs = _control_basis(coll, np.concatenate([[0.0], coll, [1.0]]))
        self._u_values = values  # (d + 2, d): controls at [0, coll..., 1] of an interval
        self._u_derivs = derivs / h  # derivative with respect to tau

    # ------------------------------------------------------------ initial guess
    def initial_guess(self, start: np.ndarray, goal: np.ndarray, speed: float) -> np.ndarray:
        """Straight line at the closed-form (3.4) net speed of the drift at the midpoint."""
        K, d = self.intervals, self.degree
        dist = float(np.linalg.norm(goal - start))
        direction = (goal - start) / dist
        drift = self.field.velocity((start + goal) / 2)[0]
        vnet = float(net_speed(drift, direction, speed))
        if np.isfinite(vnet) and vnet > 0:
            thrust = (vnet * direction - drift) / speed
            s = speed / vnet
        else:
            thrust, s = direction, 1.0
        thrust = 0.9999 * thrust / max(np.linalg.norm(thrust), 1e-12)
        s = min(max(s, 1.01 * _S_MIN), _S_MAX)
        coll_tau = (np.arange(K)[:, None] + self._tau[None, 1:]).ravel() / K
        node_tau = np.arange(1, K) / K
        states = np.concatenate([coll_tau, node_tau])[:, None] * direction[None, :]
        return np.concatenate([[s], states.ravel(), np.tile(thrust, K * d)])

    # ------------------------------------------------------------------ solve
    def solve_raw(
        self, start: np.ndarray, goal: np.ndarray, speed: float, guess: np.ndarray | None = None
    ) -> tuple[float, np.ndarray, dict[str, Any]]:
        """Solve one pair; returns (travel time, raw decision vector, IPOPT stats)."""
        if guess is None:
            guess = self.initial_guess(start, goal, speed)
        with self._lock:
            result = self.nlp(
                x0=guess,
                p=np.concatenate([start, goal, [speed]]),
                lbx=self.lbx,
                ubx=self.ubx,
                lbg=self.lbg,
                ubg=self.ubg,
            )
            stats = self.nlp.stats()
        w = np.asarray(result["x"]).ravel()
        travel_time = float(w[0]) * float(np.linalg.norm(goal - start)) / speed
        return travel_time, w, stats

    def _batch_nlp(self, size: int) -> Any:
        """One NLP holding ``size`` independent pairs (objective: the sum of their ``s``).

        The pairs share nothing, so the optimum of the sum is the optimum of each;
        one IPOPT call amortises its per-call and per-iteration overhead.
        """
        if size not in self._batches:
            pair = self.nlp.oracle()  # (w, p) -> (f, g) of one pair
            sym: Any = ca.MX if self.field.kind == "gridded" else ca.SX
            w = sym.sym("w", self._n_w, size)
            p = sym.sym("p", 5, size)
            objective: Any = 0
            constraints = []
            for b in range(size):
                f_b, g_b = pair(w[:, b], p[:, b])
                objective += f_b
                constraints.append(g_b)
            nlp = {"x": ca.vec(w), "p": ca.vec(p), "f": objective, "g": ca.vertcat(*constraints)}
            self._batches[size] = ca.nlpsol(f"min_time_batch{size}", "ipopt", nlp, self.options)
        return self._batches[size]

    def solve_batch(
        self, starts: np.ndarray, goals: np.ndarray, speed: float, size: int = 32
    ) -> np.ndarray:
        """Travel times of many pairs, ``size`` pairs per IPOPT call.

        Returns rows ``(time, success, iterations)``. A batch IPOPT does not solve
        is re-solved pair by pair, so one hard pair cannot spoil its neighbours.
        Starts must differ from goals.
        """
        n = len(starts)
        out = np.empty((n, 3))
        size = max(1, min(size, n))
        solver = self._batch_nlp(size)
        lbx, ubx = np.tile(self.lbx, size), np.tile(self.ubx, size)
        lbg, ubg = np.tile(self.lbg, size), np.tile(self.ubg, size)
        for lo in range(0, n, size):
            rows = np.arange(lo, min(lo + size, n))
            padded = np.concatenate([rows, np.full(size - len(rows), rows[-1])])
            guess = np.concatenate([self.initial_guess(starts[r], goals[r], speed) for r in padded])
            par = np.column_stack([starts[padded], goals[padded], np.full(size, speed)]).ravel()
            with self._lock:
                result = solver(x0=guess, p=par, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
                stats = solver.stats()
            if stats["success"]:
                w = np.asarray(result["x"]).reshape(size, self._n_w)[: len(rows)]
                dist = np.linalg.norm(goals[rows] - starts[rows], axis=1)
                out[rows, 0] = w[:, 0] * dist / speed
                out[rows, 1] = 1.0
                out[rows, 2] = stats["iter_count"]
            else:
                for r in rows:
                    travel_time, _, single = self.solve_raw(starts[r], goals[r], speed)
                    out[r] = (travel_time, float(bool(single["success"])), single["iter_count"])
        return out

    def solve(
        self, start: Any, goal: Any, speed: float = 1.0, guess: np.ndarray | None = None
    ) -> Path:
        """Minimum-time path from ``start`` to ``goal`` (no retry; check ``path.success``)."""
        start = as_point(start, "start")
        goal = as_point(goal, "goal")
        speed = as_speed(speed)
        if np.array_equal(start, goal):
            return trivial_path(start, speed, "collocation")
        tic = _time.perf_counter()
        travel_time, w, stats = self.solve_raw(start, goal, speed, guess)
        return self.decode(start, goal, speed, travel_time, w, stats, _time.perf_counter() - tic)

    # ----------------------------------------------------------------- decode
    def decode(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        speed: float,
        travel_time: float,
        w: np.ndarray,
        stats: dict[str, Any],
        wall: float = 0.0,
    ) -> Path:
        """Turn the decision vector into a :class:`Path` (positions, headings, rates)."""
        K, d = self.intervals, self.degree
        dist = float(np.linalg.norm(goal - start))
        states = w[1 : 1 + 2 * (K * d + K - 1)].reshape(-1, 2)
        coll_states = states[: K * d].reshape(K, d, 2)
        nodes = np.vstack([np.zeros((1, 2)), states[K * d :], [(goal - start) / dist]])
        thrust = w[1 + 2 * (K * d + K - 1) :].reshape(K, d, 2)
        xi = []
        u_samples = []
        du_samples = []
        for k in range(K):
            xi.append(nodes[k : k + 1])
            xi.append(coll_states[k])
            # the interval's control polynomial at [start, collocation points]
            u_samples.append(self._u_values[:-1] @ thrust[k])
            du_samples.append(self._u_derivs[:-1] @ thrust[k])
        xi.append(nodes[K:])
        u_samples.append(self._u_values[-1:] @ thrust[K - 1])
        du_samples.append(self._u_derivs[-1:] @ thrust[K - 1])
        xi_all = np.vstack(xi)
        u = np.vstack(u_samples)
        du = np.vstack(du_samples) / travel_time  # d u / d t
        heading = np.arctan2(u[:, 1], u[:, 0])
        heading_rate = (u[:, 0] * du[:, 1] - u[:, 1] * du[:, 0]) / np.sum(u * u, axis=1)
        return Path(
            start=start,
            goal=goal,
            speed=speed,
            time=travel_time,
            t=self._taus * travel_time,
            xy=start + dist * xi_all,
            heading=heading,
            heading_rate=heading_rate,
            method="collocation",
            status=str(stats.get("return_status", "")),
            success=bool(stats.get("success", False)),
            iterations=int(stats.get("iter_count", 0)),
            info={
                "intervals": K,
                "degree": d,
                "scheme": self.scheme,
                "thrust_norm_min": float(np.min(np.linalg.norm(thrust, axis=2))),
                "wall_time": wall,
            },
        )


_CACHE: dict[tuple[str, int, int, str, float], CollocationSolver] = {}
_CACHE_LOCK = threading.Lock()
_CACHE_SIZE = 16


def get_solver(
    field: Field | None,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
    scheme: str = "legendre",
    tol: float = DEFAULT_TOL,
) -> CollocationSolver:
    """A cached :class:`CollocationSolver`, keyed by ``repr(field.to_dict())`` and the grid."""
    field = as_field(field)
    key = (repr(field.to_dict()), int(intervals), int(degree), scheme, float(tol))
    with _CACHE_LOCK:
        solver = _CACHE.get(key)
        if solver is None:
            if len(_CACHE) >= _CACHE_SIZE:
                _CACHE.pop(next(iter(_CACHE)))
            solver = CollocationSolver(field, intervals, degree, scheme, tol)
            _CACHE[key] = solver
    return solver


def solver_from_dict(field_dict: dict[str, Any] | None, **grid: Any) -> CollocationSolver:
    """Rebuild a cached solver from ``field.to_dict()`` (for worker processes)."""
    field = None if field_dict is None else field_from_dict(field_dict)
    return get_solver(field, **grid)


def collocation_path(
    field: Field | None,
    start: Any,
    goal: Any,
    speed: float = 1.0,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
    scheme: str = "legendre",
    tol: float = DEFAULT_TOL,
) -> Path:
    """Solve by collocation, retrying on a finer grid; raise if that fails too.

    Raises
    ------
    ConvergenceError
        Neither the requested grid nor one four times finer converged.
    """
    path = get_solver(field, intervals, degree, scheme, tol).solve(start, goal, speed)
    if path.success:
        return path
    finer = get_solver(field, 4 * intervals, degree, scheme, tol).solve(start, goal, speed)
    if finer.success:
        return finer
    raise ConvergenceError(
        f"collocation did not converge from {tuple(path.start)} to {tuple(path.goal)} "
        f"(IPOPT: {path.status}; on {4 * intervals} intervals: {finer.status})"
    )
