"""Minimum-time navigation by shooting on the navigation law (2.6) — the thesis's route.

Lemma 2.2 gives the optimal heading's rate of change

    psi_dot = -dvcx/dy cos^2 psi + (dvcx/dx - dvcy/dy) sin psi cos psi + dvcy/dx sin^2 psi   (2.6)

so an optimal path is fixed by its initial heading ``psi(0)`` and its duration
``T``. Integrating (2.1) together with (2.6) from ``(start, psi(0))`` over
``[0, T]`` and asking to end at the goal is the two-point boundary value
problem (2.10): two equations in the two unknowns ``(psi(0), T)``. We solve it
by damped Newton, with the Jacobian from CasADi's forward sensitivities through
a CVODES integrator (relative and absolute tolerances 1e-12).

This is the independent cross-check of the collocation solver: it never sees
the NLP, only the necessary conditions. It finds *an* extremal; in strong or
strongly sheared fields several extremals may join the same points and Newton
may land on a slower one, so collocation (a direct method) stays the default.

References
----------
Thesis §2.3.2, Lemma 2.2, (2.6)-(2.10).
"""

from __future__ import annotations

import math
import threading
import time as _time
from typing import Any

import casadi as ca
import numpy as np

from taopt.errors import ConvergenceError
from taopt.fields import Field
from taopt.navigation.path import Path, as_field, as_point, as_speed, trivial_path
from taopt.navigation.uniform import net_speed


def navigation_law(field: Field, xy: Any, heading: Any) -> np.ndarray:
    """Right-hand side of (2.6): the optimal ``psi_dot`` at points ``xy`` with headings ``heading``.

    Vectorised: ``xy`` (N, 2), ``heading`` (N,) -> (N,).
    """
    jac = field.jacobian(xy)  # J[k, a, b] = d v_c[a] / d xy[b]
    c, s = np.cos(heading), np.sin(heading)
    return -jac[:, 0, 1] * c * c + (jac[:, 0, 0] - jac[:, 1, 1]) * s * c + jac[:, 1, 0] * s * s


class ShootingSolver:
    """Shooting on (2.10) for one field; reusable for any start, goal and speed.

    Parameters
    ----------
    field : Field or None
    tol : float
        Newton stops when the miss distance is below ``tol * |goal - start|``.
    samples : int
        Points of the decoded path.
    """

    def __init__(self, field: Field | None, tol: float = 1e-11, samples: int = 101) -> None:
        self.field = as_field(field)
        self.tol = float(tol)
        self.samples = int(samples)
        self._lock = threading.Lock()
        # Any: casadi's stubs type MX and SX each alone, not code written for either
        sym: Any = ca.MX if self.field.kind == "gridded" else ca.SX
        x, y, psi = sym.sym("x"), sym.sym("y"), sym.sym("psi")
        duration, v = sym.sym("T"), sym.sym("v")
        state = ca.vertcat(x, y, psi)
        par = ca.vertcat(duration, v)
        vcx, vcy = self.field.casadi(x, y)
        drift = ca.vertcat(vcx, vcy)
        J = ca.jacobian(drift, ca.vertcat(x, y))
        c, s = ca.cos(psi), ca.sin(psi)
        law = -J[0, 1] * c**2 + (J[0, 0] - J[1, 1]) * s * c + J[1, 0] * s**2  # (2.6)
        # (2.1) and (2.6) on tau in [0, 1], t = T tau
        ode = duration * ca.vertcat(v * c + vcx, v * s + vcy, law)
        dae = {"x": state, "p": par, "ode": ode}
        opts = {"abstol": 1e-12, "reltol": 1e-12}
        self._flow = ca.integrator("flow", "cvodes", dae, 0.0, 1.0, opts)
        grid = np.linspace(0.0, 1.0, self.samples)
        self._trajectory = ca.integrator("trajectory", "cvodes", dae, 0.0, grid[1:], opts)
        self._grid = grid
        # residual of (2.10) and its Jacobian in z = (psi0, T)
        unknown = ca.MX.sym("unknown", 2)
        data = ca.MX.sym("data", 5)  # start (2), goal (2), v
        final = self._flow(x0=ca.vertcat(data[0:2], unknown[0]), p=ca.vertcat(unknown[1], data[4]))[
            "xf"
        ]
        miss = final[0:2] - data[2:4]
        self._residual = ca.Function(
            "residual", [unknown, data], [miss, ca.jacobian(miss, unknown)]
        )
        self._miss = ca.Function("miss", [unknown, data], [miss])

    def guesses(
        self, start: np.ndarray, goal: np.ndarray, speed: float
    ) -> list[tuple[float, float]]:
        """Initial ``(psi0, T)``: uniform-field solutions with the drift at start, midpoint, end."""
        out = []
        delta = goal - start
        dist = float(np.linalg.norm(delta))
        direction = delta / dist
        for where in (start, (start + goal) / 2, goal):
            drift = self.field.velocity(where)[0]
            vnet = float(net_speed(drift, direction, speed))
            if np.isfinite(vnet) and vnet > 0:
                thrust = vnet * direction - drift
                out.append((float(np.arctan2(thrust[1], thrust[0])), dist / vnet))
        out.append((float(np.arctan2(direction[1], direction[0])), dist / speed))
        return out

    def solve(self, start: Any, goal: Any, speed: float = 1.0, max_iter: int = 50) -> Path:
        """Solve (2.10) by damped Newton from each guess in turn.

        Raises
        ------
        ConvergenceError
            No guess led Newton to a miss distance below tolerance.
        """
        start = as_point(start, "start")
        goal = as_point(goal, "goal")
        speed = as_speed(speed)
        if np.array_equal(start, goal):
            return trivial_path(start, speed, "shooting")
        tic = _time.perf_counter()
        data = np.concatenate([start, goal, [speed]])
        dist = float(np.linalg.norm(goal - start))
        target = self.tol * max(dist, 1e-300)
        total = 0
        best: tuple[np.ndarray, float] | None = None
        with self._lock:
            for guess in self.guesses(start, goal, speed):
                z, miss, iterations = self._newton(np.array(guess), data, target, max_iter)
                total += iterations
                if best is None or miss < best[1]:
                    best = (z, miss)
                if miss <= target:
                    return self._decode(
                        start, goal, speed, z, miss, total, _time.perf_counter() - tic
                    )
        raise ConvergenceError(
            f"shooting did not converge from {tuple(start)} to {tuple(goal)}: "
            f"best miss distance {math.nan if best is None else best[1]:.3g} m after {total} "
            "Newton steps"
        )

    def _newton(
        self, z: np.ndarray, data: np.ndarray, target: float, max_iter: int
    ) -> tuple[np.ndarray, float, int]:
        miss_vec, jac = (np.asarray(a) for a in self._residual(z, data))
        miss = float(np.linalg.norm(miss_vec))
        for iteration in range(1, max_iter + 1):
            if miss <= target:
                return z, miss, iteration - 1
            try:
                step = np.linalg.solve(jac, -miss_vec.ravel())
            except np.linalg.LinAlgError:
                return z, miss, iteration
            alpha = 1.0
            while alpha > 1e-4:
                trial = z + alpha * step
                if trial[1] > 0:
                    trial_vec = np.asarray(self._miss(trial, data))
                    trial_miss = float(np.linalg.norm(trial_vec))
                    if trial_miss < (1 - 1e-4 * alpha) * miss or trial_miss <= target:
                        break
                alpha /= 2
            else:
                return z, miss, iteration
            z = trial
            miss_vec, jac = (np.asarray(a) for a in self._residual(z, data))
            miss = float(np.linalg.norm(miss_vec))
        return z, miss, max_iter

    def _decode(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        speed: float,
        z: np.ndarray,
        miss: float,
        iterations: int,
        wall: float,
    ) -> Path:
        psi0, duration = float(z[0]), float(z[1])
        traj = np.asarray(self._trajectory(x0=np.r_[start, psi0], p=np.r_[duration, speed])["xf"])
        states = np.column_stack([np.r_[start, psi0], traj]).T  # (samples, 3)
        xy, heading = states[:, :2], states[:, 2]
        return Path(
            start=start,
            goal=goal,
            speed=speed,
            time=duration,
            t=self._grid * duration,
            xy=xy,
            heading=heading,
            heading_rate=navigation_law(self.field, xy, heading),
            method="shooting",
            status="converged",
            success=True,
            iterations=iterations,
            info={"miss_distance": miss, "initial_heading": psi0, "wall_time": wall},
        )


_CACHE: dict[str, ShootingSolver] = {}


def get_shooting_solver(field: Field | None) -> ShootingSolver:
    """A cached :class:`ShootingSolver` keyed by ``repr(field.to_dict())``."""
    field = as_field(field)
    key = repr(field.to_dict())
    if key not in _CACHE:
        if len(_CACHE) >= 8:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = ShootingSolver(field)
    return _CACHE[key]


def shooting_path(field: Field | None, start: Any, goal: Any, speed: float = 1.0) -> Path:
    """Minimum-time path by shooting on (2.10); see :class:`ShootingSolver`."""
    return get_shooting_solver(field).solve(start, goal, speed)
