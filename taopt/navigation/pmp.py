"""All ordered pairs at once: vectorised Pontryagin shooting on (2.6)/(2.10), thesis §2.3.

Lemma 2.2 fixes the optimal heading's rate of change (2.6); a minimum-time
path from ``a`` to ``b`` is therefore fixed by two numbers, its initial heading
``psi(0)`` and its duration ``T``, which solve the two-point boundary problem
(2.10): integrate (2.1) with (2.6) from ``(a, psi(0))`` for ``T`` seconds and
end at ``b``. This module solves (2.10) for *every* pair of a travel-time matrix
simultaneously: all states are numpy arrays over pairs, one Runge-Kutta stage
advances all pairs, and Newton updates all ``(psi(0), T)`` together.

Method chosen, and why
----------------------
*Integrator.* The 12-stage, order-8 Runge-Kutta tableau of Dormand and Prince
(carried by :class:`scipy.integrate.DOP853`) used with a *fixed* number of
equal steps per pair. Fields of interest are smooth and weak on the scale of one
trip (``T |grad v_c| <= 1`` for the thesis's field on its 1000 m square), so one
or two order-8 steps give the end point to about 1e-12 relative; a fixed step
count keeps every pair in the same array operation, which an adaptive per-pair
step could not. The step count keeps ``T * rate / steps <= STEP_REACH``, where
``rate`` is the local rate scale of the flow (:func:`_local_rate`: the drift's
Jacobian, and its Hessian, which drives the variational equations). It is
picked from a bound over the points' box, re-checked against the rates met along
each extremal, and the end point is then *verified*: the converged solution is
re-integrated with twice the steps and the new miss distance (an estimate of the
true integration error; order 8 makes it about 256 times smaller) must be below
``tol * |b - a|``; pairs that fail are re-solved with more steps. The accuracy
is measured, not assumed.

*Jacobian.* Newton on the miss ``r(psi0, T) = x(T) - b`` needs ``dr/dpsi0`` and
``dr/dT``. The first comes from the variational equations of (2.1)+(2.6)
integrated alongside the state by the same Runge-Kutta stages (so it is the
exact derivative of the discrete flow); the second is the velocity (2.1) at the
end point. Newton steps are capped (``|dpsi| <= 1`` rad, ``T`` at most halved)
and backtracked per pair until the miss decreases.

*Warm start.* The uniform-field closed form (3.4) with the drift at the
segment's midpoint (:mod:`taopt.navigation.uniform`); on the thesis's field
Newton then converges in three or four iterations.

*Why not the alternatives.* Batched collocation (the reference) solves an NLP
per pair: even batched, milliseconds per pair. Per-pair CVODES shooting
(:mod:`taopt.navigation.shooting`) pays Python and CasADi overhead per pair.
An affine field would even allow a closed-form costate and a quadrature, but
one integrator for every smooth field is simpler to trust and fast enough.

Which extremal: guards, and why affine fields need none
-------------------------------------------------------
Newton returns *an* extremal: a path satisfying Pontryagin's necessary
conditions, not necessarily the fastest.

*Affine fields* (``v_c = A x + c``, uniform and linear, the thesis's case):
every extremal is the minimum. The dynamics are linear with a convex control
set, so the reachable set ``R(T)`` is convex, and a path following (2.6) is
thrust along ``n(t)`` with ``n' = -A^T n`` (test_navigation's costate check),
which is exactly the control that maximises ``<n(T), x(T)>`` over ``R(T)``: its
end point lies on the boundary of ``R(T)``. If ``b`` were reachable at some
``t < T``, the vehicle could hold station there (``|v_c(b)| < v``, Assumption
2.1) with thrust to spare, which puts ``b`` in the *interior* of ``R(T)``.
So ``T`` is the minimum time, whichever extremal Newton found.

*Other smooth fields* (a B-spline :class:`~taopt.fields.GriddedField`) can have
several extremals. Every solution is checked before it is accepted; a pair that
fails a check is restarted from other initial headings (``RESTART_OFFSETS``
around the rejected one, fastest accepted solution wins); if it still fails it
is marked with its reason, and :func:`taopt.navigation.travel_time_matrix`
re-solves it by collocation and reports its ``(i, j)``:

1. *Converged and accurate*: Newton converged (relative miss below ``tol / 100``,
   or below ``sqrt(tol / 100) / 10`` followed by one last full step, whose miss
   quadratic convergence puts far below ``tol``), enough steps for the rates
   met, and the miss re-integrated with twice the steps below ``tol``.
2. *No conjugate point (Jacobi condition)*: along an extremal ``dx/dpsi0`` is
   orthogonal to the costate while the velocity is not (``H = 0``), so
   ``det[dx/dpsi0, x_dot]`` is negative for small ``t`` and vanishes only where
   the extremals from ``a`` focus (a conjugate point); beyond it the extremal is
   not even locally optimal. The determinant is checked at every step end and at
   ``T`` (where it is also Newton's Jacobian). Example: against a jet current,
   the straight path on the jet's axis is an extremal past its conjugate point;
   collocation converges to it too, the restarts find the faster path that
   leaves the axis (tests/navigation/test_navigation_pmp.py).
3. *Not slower than the straight line*: flying the segment ``a -> b`` with the
   heading that keeps the net velocity on it (3.4) is feasible under Assumption
   2.1; its time (a 32-point Gauss-Legendre quadrature of ``1 / v_net``) bounds
   the optimum from above, and a longer extremal is rejected.
4. *Triangle inequality* (in :func:`taopt.navigation.travel_time_matrix`): a
   solution of (2.10) is a real trajectory, so its time is never below the
   optimum; if ``t(i, k) > t(i, j) + t(j, k)`` the entry ``(i, k)`` must be a
   slower extremal, and it is re-solved by collocation.

Outside affine fields checks 2-4 do not prove global optimality (nothing cheap
does), but a slower extremal would have to be locally optimal, beat the straight
line and be consistent with every detour through the other points.

References
----------
Thesis §2.3.2, Lemma 2.2, (2.1), (2.6)-(2.10), (3.4), Assumption 2.1; Lemma 2.3
(the triangle inequality).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import DOP853

from taopt.errors import ConvergenceError, InstanceError
from taopt.fields import Field, GriddedField, LinearField, UniformField
from taopt.navigation.path import Path, as_field, as_point, as_speed, trivial_path
from taopt.navigation.uniform import net_speed

DEFAULT_TOL = 1e-10  # accepted relative miss |x(T) - b| / |b - a| (~ relative error of T)
MAX_ITER = 30  # Newton iterations (integrations) per step count
MAX_STEPS = 256  # Runge-Kutta steps per pair before giving up
STEP_REACH = 0.5  # each step covers at most this much of T * (local rate scale)
LINE_NODES = 32  # Gauss-Legendre nodes of the straight-line bound
RESTART_OFFSETS = (0.5, -0.5, 1.0, -1.0, 1.5, -1.5)  # rad added to psi(0) for restarts
CHUNK = 8192  # most pairs per vectorised batch (measured fastest); batches are the unit of threads

# Dormand-Prince order-8 tableau (scipy's DOP853 carries it), used with fixed steps.
_RK_A = np.asarray(DOP853.A, dtype=float)
_RK_B = np.asarray(DOP853.B, dtype=float)
_RK_STAGES = int(DOP853.n_stages)

# reasons a pair is not accepted (PairTimes.reason)
OK = ""
NOT_CONVERGED = "Newton did not converge"
INACCURATE = "integration not accurate within max_steps"
CONJUGATE = "conjugate point: extremal is not locally optimal"
SLOWER_THAN_LINE = "extremal slower than the straight line"


# -------------------------------------------------------------------- drift models


@dataclass(frozen=True)
class DriftModel:
    """The drift and its first two derivatives, vectorised over points.

    Attributes
    ----------
    evaluate : callable
        ``evaluate(xy, second)`` with ``xy`` of shape (2, P) returns the velocity
        (2, P), the Jacobian ``J[a, b] = d v_c[a] / d xy[b]`` (2, 2, P or 1) and,
        if ``second``, the Hessian ``H[a, b, q] = d J[a, b] / d xy[q]``
        (2, 2, 2, P or 1), else None. None also stands for a zero Hessian.
    velocity : callable
        ``velocity(xy)`` (2, P) -> (2, P), the drift alone.
    rate_bound : callable
        ``rate_bound(lo, hi, speed)``: the largest local rate scale (1/s) of the
        flow over the box ``[lo, hi]``: the spectral norm of a constant Jacobian,
        else ``max(|J|, sqrt(|H| (v + |v_c|)))`` sampled on a 41 x 41 grid (see
        :func:`_local_rate`). It only sets the first step count; the rates met
        along each extremal and the end point's accuracy are checked afterwards.
    thread_safe : bool
        Whether ``evaluate`` may run in several threads at once (numpy: yes;
        CasADi functions share work memory: no).
    constant_jacobian : bool
        The drift is affine (its Jacobian is the same everywhere).
    """

    evaluate: Callable[[np.ndarray, bool], tuple[np.ndarray, np.ndarray, np.ndarray | None]]
    velocity: Callable[[np.ndarray], np.ndarray]
    rate_bound: Callable[[np.ndarray, np.ndarray, float], float]
    thread_safe: bool = True
    constant_jacobian: bool = False


@functools.singledispatch
def is_smooth(field: Field) -> bool:
    """Whether the navigation law (2.6) and its variational equations apply to ``field``.

    They need a twice-differentiable drift. Unknown field classes answer False
    (register them with ``is_smooth.register`` and :func:`drift_model`).
    """
    return False


@is_smooth.register
def _(field: UniformField) -> bool:
    return True


@is_smooth.register
def _(field: LinearField) -> bool:
    return True


@is_smooth.register
def _(field: GriddedField) -> bool:
    return field.method == "bspline"  # piecewise bilinear has a discontinuous Jacobian


@functools.singledispatch
def is_analytic(field: Field) -> bool:
    """Whether the drift is smooth to every order, so the order-8 steps keep their order.

    :func:`taopt.navigation.travel_time_matrix` uses "pmp" by default only for
    these fields. A B-spline :class:`~taopt.fields.GriddedField` is only twice
    differentiable: the heading law (2.6) (first derivatives) is then only once
    differentiable across the knots, every step over a knot loses the order, and
    reaching ``tol`` takes tens to hundreds of steps per pair (measured: 8-64
    steps for 1e-8 on a 21 x 21 grid), slower than collocation. "pmp" still
    works there when asked for.
    """
    return False


@is_analytic.register
def _(field: UniformField) -> bool:
    return True


@is_analytic.register
def _(field: LinearField) -> bool:
    return True


@functools.singledispatch
def drift_model(field: Field) -> DriftModel:
    """The :class:`DriftModel` of ``field``; by default derived from ``field.casadi``.

    The default differentiates the field's symbolic CasADi expression twice and
    evaluates it over all points with one mapped CasADi call.
    """
    import casadi as ca

    point = ca.MX.sym("xy", 2)
    vcx, vcy = field.casadi(point[0], point[1])
    velocity = ca.vertcat(vcx, vcy)
    jacobian = ca.jacobian(velocity, point)
    hessian = ca.jacobian(ca.vec(jacobian), point)  # rows J00, J10, J01, J11 (column-major)
    first = ca.Function("drift_first", [point], [velocity, ca.vec(jacobian)])
    second = ca.Function("drift_second", [point], [velocity, ca.vec(jacobian), ca.vec(hessian)])
    only_velocity = ca.Function("drift_velocity", [point], [velocity])
    maps: dict[tuple[str, int], Any] = {}

    def mapped(name: str, function: Any, size: int) -> Any:
        if (name, size) not in maps:
            if len(maps) > 32:
                maps.clear()
            maps[(name, size)] = function.map(size)
        return maps[(name, size)]

    def evaluate(xy: np.ndarray, want_second: bool) -> tuple[Any, Any, Any]:
        size = xy.shape[1]
        if want_second:
            v, j, h = mapped("second", second, size)(xy)
        else:
            v, j = mapped("first", first, size)(xy)
            h = None
        vel = np.asarray(v)
        jac = np.asarray(j).reshape(2, 2, size, order="F")  # vec is column-major: J[a, b]
        if h is None:
            return vel, jac, None
        # vec(hessian) is column-major over (4, 2): index q * 4 + (b * 2 + a)
        hess = np.asarray(h).reshape(2, 2, 2, size, order="F")
        return vel, jac, hess

    def drift(xy: np.ndarray) -> np.ndarray:
        return np.asarray(mapped("velocity", only_velocity, xy.shape[1])(xy))

    def bound(lo: np.ndarray, hi: np.ndarray, speed: float) -> float:
        gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 41), np.linspace(lo[1], hi[1], 41))
        vel, jac, hess = evaluate(np.vstack([gx.ravel(), gy.ravel()]), True)
        return float(np.max(_local_rate(vel, jac, hess, speed)))

    return DriftModel(evaluate, drift, bound, thread_safe=False)


@drift_model.register
def _(field: LinearField) -> DriftModel:
    A = field.A.copy()
    b = field.b.copy()
    jac = A[:, :, None]
    norm = float(np.linalg.norm(A, ord=2))

    def drift(xy: np.ndarray) -> np.ndarray:
        return np.stack(
            [A[0, 0] * xy[0] + A[0, 1] * xy[1] + b[0], A[1, 0] * xy[0] + A[1, 1] * xy[1] + b[1]]
        )

    def evaluate(xy: np.ndarray, want_second: bool) -> tuple[np.ndarray, np.ndarray, None]:
        return drift(xy), jac, None  # the Hessian of an affine field is zero

    return DriftModel(evaluate, drift, lambda lo, hi, speed: norm, constant_jacobian=True)


@drift_model.register
def _(field: UniformField) -> DriftModel:
    vel = np.array([[field.vx], [field.vy]])
    jac = np.zeros((2, 2, 1))

    def drift(xy: np.ndarray) -> np.ndarray:
        return np.broadcast_to(vel, xy.shape)

    def evaluate(xy: np.ndarray, want_second: bool) -> tuple[np.ndarray, np.ndarray, None]:
        return drift(xy), jac, None

    return DriftModel(evaluate, drift, lambda lo, hi, speed: 0.0, constant_jacobian=True)


# -------------------------------------------------------------------- the flow


def _local_rate(
    vel: np.ndarray, jac: np.ndarray, hess: np.ndarray | None, speed: float
) -> np.ndarray:
    """Local rate scale ``max(|J|, sqrt(|H| (v + |v_c|)))`` (1/s, Frobenius norms) per point.

    ``|J|`` is how fast (2.1) and (2.6) change the state; ``sqrt(|H| v_net)`` is
    how fast the variational equations can rotate (focusing towards a conjugate
    point, even where ``J = 0``).
    """
    local = np.sqrt(np.sum(jac * jac, axis=(0, 1)))
    if hess is not None:
        curvature = np.sqrt(np.sum(hess * hess, axis=(0, 1, 2)))
        local = np.maximum(local, np.sqrt(curvature * (speed + np.hypot(vel[0], vel[1]))))
    return local


def _rates(
    model: DriftModel,
    speed: float,
    start: np.ndarray,
    state: np.ndarray,
    out: np.ndarray,
    stiffness: np.ndarray,
) -> None:
    """``out = d state / dt``: (2.1), (2.6) and, for 6 rows, their variational equations.

    ``state`` rows: ``x - a_x, y - a_y, psi`` and optionally ``dx/dpsi0, dy/dpsi0,
    dpsi/dpsi0``; positions are relative to the start ``a`` (so round-off scales
    with the trip, not with the coordinates). With ``c2 = cos 2 psi`` and
    ``s2 = sin 2 psi``, (2.6) reads ``((J10 - J01) + (J00 - J11) s2 - (J01 + J10) c2) / 2``.

    For a drift whose Jacobian varies, ``stiffness`` (P,) is raised to the local
    rate scale ``max(|J|, sqrt(|H| (v + |v_c|)))`` (1/s; Frobenius norms), which
    sets how many steps the state and its variational equations need.
    """
    variational = state.shape[0] == 6
    vel, jac, hess = model.evaluate(state[:2] + start, variational)
    if not model.constant_jacobian:
        np.maximum(stiffness, _local_rate(vel, jac, hess, speed), out=stiffness)
    c, s = np.cos(state[2]), np.sin(state[2])
    s2 = 2.0 * s * c
    c2 = c * c - s * s
    half_curl = 0.5 * (jac[1, 0] - jac[0, 1])
    half_stretch = 0.5 * (jac[0, 0] - jac[1, 1])
    half_shear = 0.5 * (jac[0, 1] + jac[1, 0])
    np.add(speed * c, vel[0], out=out[0])  # (2.1)
    np.add(speed * s, vel[1], out=out[1])
    out[2] = half_curl + half_stretch * s2 - half_shear * c2  # (2.6)
    if not variational:
        return
    dx, dy, dpsi = state[3], state[4], state[5]
    out[3] = jac[0, 0] * dx + jac[0, 1] * dy - (speed * dpsi) * s
    out[4] = jac[1, 0] * dx + jac[1, 1] * dy + (speed * dpsi) * c
    law_psi = 2.0 * (half_stretch * c2 + half_shear * s2)  # d(2.6)/d psi
    rate = law_psi * dpsi
    if hess is not None:
        cc, ss, sc = c * c, s * s, s * c
        for q, d in ((0, dx), (1, dy)):
            law_q = -hess[0, 1, q] * cc + (hess[0, 0, q] - hess[1, 1, q]) * sc + hess[1, 0, q] * ss
            rate = rate + law_q * d
    out[5] = rate


def _combine(
    out: np.ndarray,
    state: np.ndarray,
    scale: np.ndarray,
    weights: np.ndarray,
    k: np.ndarray,
    scratch: np.ndarray,
) -> None:
    """``out = state + scale * sum_j weights[j] k[j]`` over the non-zero weights, in place.

    ``scale`` (P,) is the per-pair step ``T / steps``. (In-place scaled additions
    stream each stage once; ``tensordot`` over the stage axis was several times
    slower on these short, wide arrays.)
    """
    np.copyto(out, state)
    for j in np.flatnonzero(weights):
        np.multiply(k[j], weights[j] * scale, out=scratch)
        out += scratch


@dataclass
class _Flow:
    end: np.ndarray  # (rows, P) state at t = T
    velocity: np.ndarray  # (2, P) (2.1) at the end
    worst_det: np.ndarray  # (P,) max over step ends of det[dx/dpsi0, x_dot] (variational only)
    stiffness: np.ndarray  # (P,) largest local rate scale met (see _rates; 0 if J is constant)
    samples: np.ndarray | None = None  # (steps + 1, rows, P) if recorded


def _integrate(
    model: DriftModel,
    speed: float,
    start: np.ndarray,
    psi0: np.ndarray,
    duration: np.ndarray,
    steps: int,
    variational: bool,
    record: bool = False,
) -> _Flow:
    """Fixed-step order-8 Runge-Kutta over ``[0, T]`` (``steps`` steps of ``T / steps``)."""
    rows = 6 if variational else 3
    size = psi0.shape[0]
    state = np.zeros((rows, size))
    state[2] = psi0
    if variational:
        state[5] = 1.0
    k = np.empty((_RK_STAGES, rows, size))
    stage, scratch = np.empty_like(state), np.empty_like(state)
    scale = duration / steps
    worst = np.full(size, -np.inf)
    stiffness = np.zeros(size)
    samples = [state.copy()] if record else None
    for n in range(steps):
        for i in range(_RK_STAGES):
            if i:
                _combine(stage, state, scale, _RK_A[i, :i], k, scratch)
            _rates(model, speed, start, state if i == 0 else stage, k[i], stiffness)
        if variational and n > 0:  # det at this step's start, from its first stage
            np.maximum(worst, state[3] * k[0, 1] - state[4] * k[0, 0], out=worst)
        _combine(stage, state, scale, _RK_B, k, scratch)
        state, stage = stage, state
        if samples is not None:
            samples.append(state.copy())
    end_rate = np.empty((rows, size))
    _rates(model, speed, start, state, end_rate, stiffness)
    velocity = end_rate[:2]
    if variational:
        np.maximum(worst, state[3] * velocity[1] - state[4] * velocity[0], out=worst)
    return _Flow(state, velocity, worst, stiffness, np.array(samples) if record else None)


# -------------------------------------------------------------------- Newton


def _newton(
    model: DriftModel,
    speed: float,
    start: np.ndarray,
    offset: np.ndarray,
    dist: np.ndarray,
    psi: np.ndarray,
    duration: np.ndarray,
    steps: int,
    tol: float,
    max_iter: int,
    final: float = 0.0,
) -> tuple[np.ndarray, ...]:
    """Damped Newton on (2.10) for all pairs.

    Returns ``psi0, T, converged, worst det, stiffness, iterations``: the det of
    the converged integration and the largest local rate met in any iteration
    (see :func:`_integrate`).

    ``offset = b - a`` (2, P), ``dist = |b - a|``. Each iteration integrates the
    pairs still running once (with their variational equations); a trial whose
    miss does not decrease is halved back towards the last accepted point. A
    pair converges when its relative miss is at most ``tol``, or, once it is at
    most ``final``, after one more full Newton step without integrating again
    (Newton converges quadratically: the next miss is about the square of this
    one); the caller then measures the miss of that last step itself.
    """
    size = psi.shape[0]
    base_psi, base_T = psi.copy(), duration.copy()
    trial_psi, trial_T = psi.copy(), duration.copy()
    step_psi, step_T = np.zeros(size), np.zeros(size)
    alpha = np.ones(size)
    base_miss = np.full(size, np.inf)
    converged = np.zeros(size, dtype=bool)
    worst_det = np.full(size, np.nan)
    stiffness = np.zeros(size)
    iterations = np.zeros(size, dtype=int)
    running = np.arange(size)
    for _ in range(max_iter):
        if running.size == 0:
            break
        iterations[running] += 1
        flow = _integrate(
            model, speed, start[:, running], trial_psi[running], trial_T[running], steps, True
        )
        miss_vec = flow.end[:2] - offset[:, running]
        miss = np.hypot(miss_vec[0], miss_vec[1]) / dist[running]
        finite = np.isfinite(miss) & np.all(np.isfinite(flow.end), axis=0)
        done = finite & (miss <= tol)
        accept = finite & (done | (miss < (1.0 - 1e-4 * alpha[running]) * base_miss[running]))
        # accepted trials become the base point
        acc = running[accept]
        base_psi[acc], base_T[acc], base_miss[acc] = trial_psi[acc], trial_T[acc], miss[accept]
        converged[running[done]] = True
        worst_det[running[done]] = flow.worst_det[done]
        np.maximum(stiffness[running], flow.stiffness, out=flow.stiffness)
        stiffness[running] = flow.stiffness
        # a new Newton step where accepted but not yet converged
        new = accept & ~done
        rx, ry = miss_vec[0, new], miss_vec[1, new]
        ax, ay = flow.end[3, new], flow.end[4, new]  # d x(T) / d psi0
        ex, ey = flow.velocity[0, new], flow.velocity[1, new]  # d x(T) / d T
        det = ax * ey - ay * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            d_psi = -(rx * ey - ry * ex) / det
            d_T = -(ax * ry - ay * rx) / det
            cap = np.minimum(1.0, 1.0 / np.abs(d_psi))
            cap = np.minimum(cap, np.where(d_T < 0, 0.5 * base_T[running[new]] / -d_T, 1.0))
        idx = running[new]
        step_psi[idx], step_T[idx], alpha[idx] = d_psi, d_T, cap
        last = np.zeros(running.size, dtype=bool)
        last[new] = (miss[new] <= final) & (cap == 1.0)
        fin = running[last]
        base_psi[fin] += step_psi[fin]
        base_T[fin] += step_T[fin]
        converged[fin] = True
        worst_det[fin] = flow.worst_det[last]
        # rejected trials: halve the step from the base point
        rej = running[~accept]
        alpha[rej] *= 0.5
        # next trial points; give up on pairs whose step vanished or is not finite
        nxt = running[~done & ~last]
        trial_psi[nxt] = base_psi[nxt] + alpha[nxt] * step_psi[nxt]
        trial_T[nxt] = base_T[nxt] + alpha[nxt] * step_T[nxt]
        alive = (
            (alpha[nxt] > 1e-3)
            & np.isfinite(trial_psi[nxt])
            & np.isfinite(trial_T[nxt])
            & (trial_T[nxt] > 0)
        )
        running = nxt[alive]
    return base_psi, base_T, converged, worst_det, stiffness, iterations


# -------------------------------------------------------------------- bounds and warm start


def straight_line_times(
    model: DriftModel, starts: np.ndarray, goals: np.ndarray, speed: float
) -> np.ndarray:
    """Time to fly each segment ``a -> b`` along the segment (3.4): an upper bound on ``t(a, b)``.

    ``integral_0^D ds / v_net(a + s d)`` by Gauss-Legendre quadrature; ``inf``
    where some node has no net speed along the segment (Assumption 2.1 fails).
    ``starts``, ``goals``: (2, P).
    """
    nodes, weights = np.polynomial.legendre.leggauss(LINE_NODES)
    nodes, weights = (nodes + 1.0) / 2.0, weights / 2.0
    offset = goals - starts
    dist = np.hypot(offset[0], offset[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        direction = offset / dist
    points = starts[:, :, None] + offset[:, :, None] * nodes  # (2, P, Q)
    drift = model.velocity(points.reshape(2, -1)).reshape(points.shape)
    along = direction[:, :, None] * np.ones_like(nodes)
    vnet = net_speed(np.moveaxis(drift, 0, -1), np.moveaxis(along, 0, -1), speed)  # (P, Q)
    times = dist * np.sum(weights / vnet, axis=1)
    return np.where(np.isnan(times), np.inf, times)


def warm_start(
    model: DriftModel, starts: np.ndarray, goals: np.ndarray, speed: float
) -> tuple[np.ndarray, np.ndarray]:
    """Initial ``(psi0, T)``: the uniform-field closed form (3.4) with the midpoint's drift."""
    offset = goals - starts
    dist = np.hypot(offset[0], offset[1])
    direction = offset / dist
    drift = model.velocity((starts + goals) / 2)
    vnet = net_speed(drift.T, direction.T, speed)
    good = np.isfinite(vnet) & (vnet > 0)
    vnet = np.where(good, vnet, speed)
    thrust = np.where(good, vnet * direction - drift, direction)
    return np.arctan2(thrust[1], thrust[0]), dist / vnet


# -------------------------------------------------------------------- public API


@dataclass(frozen=True)
class PairTimes:
    """Result of :func:`pmp_travel_times`, one entry per pair.

    Attributes
    ----------
    time : (P,) ndarray
        Travel time ``t(a, b)``; ``nan`` where the pair is not accepted.
    heading : (P,) ndarray
        Initial heading ``psi(0)`` of the extremal (last Newton iterate if not accepted).
    accepted : (P,) bool ndarray
        Converged, accurate and passed the guards (module docstring).
    reason : (P,) object ndarray
        ``""`` where accepted, else why not (the module's reason constants).
    iterations : (P,) int ndarray
        Newton iterations (one integration each), summed over step counts.
    steps : (P,) int ndarray
        Runge-Kutta steps of the accepted solution.
    miss : (P,) ndarray
        Relative miss ``|x(T) - b| / |b - a|`` re-integrated with twice the steps.
    line_time : (P,) ndarray
        The straight-line upper bound (check 3).
    extremal_time : (P,) ndarray
        ``T`` of the extremal Newton converged to, also where it was rejected
        (``nan`` where Newton did not converge).
    restarted : (P,) bool ndarray
        Accepted only after the restarts from other initial headings.
    """

    time: np.ndarray
    heading: np.ndarray
    accepted: np.ndarray
    reason: np.ndarray
    iterations: np.ndarray
    steps: np.ndarray
    miss: np.ndarray
    line_time: np.ndarray
    extremal_time: np.ndarray
    restarted: np.ndarray

    @property
    def failed(self) -> np.ndarray:
        """Indices of the pairs that were not accepted."""
        return np.flatnonzero(~self.accepted)


def _as_pairs(values: Any, what: str) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be a (P, 2) array of numbers") from None
    if arr.ndim == 1 and arr.size == 2:
        arr = arr.reshape(1, 2)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InstanceError(f"{what} must have shape (P, 2), got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise InstanceError(f"{what} row {int(bad[0])} is not finite: {arr[bad[0]].tolist()}")
    return arr


def _solve_chunk(
    model: DriftModel,
    speed: float,
    start: np.ndarray,
    goal: np.ndarray,
    first: tuple[np.ndarray, np.ndarray],
    bound: float,
    tol: float,
    max_iter: int,
    max_steps: int,
    callback: Callable[[int], None] | None,
) -> tuple[np.ndarray, ...]:
    """Solve (2.10) for the pairs ``start -> goal`` (each (2, P)); see :func:`pmp_travel_times`.

    Returns ``T, psi0, accepted, reason, iterations, steps, miss, line_time`` per pair.
    """
    offset = goal - start
    dist = np.hypot(offset[0], offset[1])
    psi, duration = first
    first_psi, first_T = psi.copy(), duration.copy()
    steps = np.clip(np.ceil(bound * duration / STEP_REACH), 1, max_steps).astype(int)
    newton_tol = tol / 100.0

    count = start.shape[1]
    done = np.zeros(count, dtype=bool)
    ok = np.zeros(count, dtype=bool)
    why = np.full(count, NOT_CONVERGED, dtype=object)
    iters = np.zeros(count, dtype=int)
    det = np.full(count, np.nan)
    miss2 = np.full(count, np.nan)
    while not done.all():
        n_steps = int(steps[~done].min())
        group = np.flatnonzero(~done & (steps == n_steps))
        g_psi, g_T, conv, g_det, g_stiff, g_iter = _newton(
            model,
            speed,
            start[:, group],
            offset[:, group],
            dist[group],
            psi[group],
            duration[group],
            n_steps,
            newton_tol,
            max_iter,
            0.1 * np.sqrt(newton_tol),
        )
        psi[group], duration[group], iters[group] = g_psi, g_T, iters[group] + g_iter
        det[group] = g_det
        # enough steps for the rates met on the way? If not, try again with more
        # (a pair that did not converge starts again from its first guess)
        needed = np.ceil(np.maximum(bound, g_stiff) * g_T / STEP_REACH)
        coarse = np.isfinite(needed) & (needed > n_steps)
        if n_steps < max_steps:
            redo = group[coarse]
            steps[redo] = np.minimum(np.maximum(needed[coarse], 2 * n_steps), max_steps)
            restart = group[coarse & ~conv]
            psi[restart], duration[restart] = first_psi[restart], first_T[restart]
        else:
            done[group[coarse]] = True
            why[group[coarse & conv]] = INACCURATE
        done[group[~conv & ~coarse]] = True  # why stays NOT_CONVERGED
        conv_idx = group[conv & ~coarse]
        if conv_idx.size:
            # accuracy check: the true flow (estimated with twice the steps) must also hit b
            check = _integrate(
                model,
                speed,
                start[:, conv_idx],
                psi[conv_idx],
                duration[conv_idx],
                2 * n_steps,
                False,
            )
            miss_vec = check.end[:2] - offset[:, conv_idx]
            miss2[conv_idx] = np.hypot(miss_vec[0], miss_vec[1]) / dist[conv_idx]
            accurate = miss2[conv_idx] <= tol
            good = conv_idx[accurate]
            done[good], ok[good], why[good] = True, True, OK
            redo = conv_idx[~accurate]
            if 2 * n_steps > max_steps:
                done[redo], why[redo] = True, INACCURATE
            else:
                steps[redo] = 2 * n_steps
        if callback is not None:
            callback(int(np.count_nonzero(done[group])))

    # guards against a non-optimal extremal (module docstring, checks 2 and 3)
    conjugate = ok & ~(det < 0)
    ok[conjugate], why[conjugate] = False, CONJUGATE
    line = straight_line_times(model, start, goal, speed)
    slower = ok & (duration > line * (1.0 + max(10.0 * tol, 1e-9)))
    ok[slower], why[slower] = False, SLOWER_THAN_LINE

    return duration, psi, ok, why, iters, steps, miss2, line


def pmp_travel_times(
    field: Field | None,
    starts: Any,
    goals: Any,
    speed: float = 1.0,
    *,
    tol: float = DEFAULT_TOL,
    max_iter: int = MAX_ITER,
    max_steps: int = MAX_STEPS,
    callback: Callable[[int], None] | None = None,
    jobs: int = 1,
    initial: tuple[Any, Any] | None = None,
    restarts: bool = True,
) -> PairTimes:
    """Minimum travel times of many pairs by vectorised shooting on (2.10).

    Parameters
    ----------
    field : Field or None
        A smooth drift (:func:`is_smooth`); None is still water.
    starts, goals : (P, 2) array_like
        The pairs ``a -> b``.
    speed : float
        Vehicle speed ``v`` relative to the field (2.1).
    tol : float
        Accepted relative miss ``|x(T) - b| / |b - a|``, measured with twice the
        Runge-Kutta steps of the solution; about the relative error of ``T``.
    max_iter : int
        Newton iterations per step count.
    max_steps : int
        Largest number of Runge-Kutta steps tried per pair.
    callback : callable, optional
        Called with the number of pairs just finished (for progress bars).
    jobs : int
        Threads. The pairs are cut into an even number of batches of at most
        ``CHUNK`` whatever ``jobs`` is, so the result does not depend on it;
        numpy releases the GIL inside its array loops, so batches run in
        parallel. Fields evaluated by CasADi use one thread.
    initial : (psi0, T) pair of (P,) array_like, optional
        Newton's starting points instead of :func:`warm_start` (for multi-start
        studies of the extremals).
    restarts : bool
        Re-solve each pair that was not accepted from ``RESTART_OFFSETS`` added to
        its rejected extremal's initial heading (or the first guess's), keeping the
        fastest accepted solution (``restarted``). Never triggers on an affine
        field, where every extremal is the optimum (module docstring).

    Returns
    -------
    PairTimes
        Times, headings, and per pair whether it was accepted and why not.
        Pairs with ``a == b`` get time 0.

    Raises
    ------
    InstanceError
        Bad input, or a field the navigation law cannot be applied to.

    Example
    -------
    >>> from taopt.fields import thesis_field
    >>> out = pmp_travel_times(thesis_field(1e-2), [[10, 80], [90, 15]], [[90, 15], [10, 80]])
    >>> out.accepted.tolist(), bool(out.time[0] < out.time[1])
    ([True, True], True)

    Notes
    -----
    Cost: about five integrations of ``12 * steps`` vectorised stage
    evaluations per pair (three or four Newton iterations with the variational
    equations, the doubled-step accuracy check) and the straight-line
    quadrature: about 16 microseconds of CPU per pair on the thesis's field
    (one or two steps). The module docstring lists the checks a solution passes
    before it is accepted.

    References
    ----------
    Thesis §2.3.2, Lemma 2.2, (2.6)-(2.10).
    """
    field = as_field(field)
    speed = as_speed(speed)
    if not is_smooth(field):
        raise InstanceError(
            f"method 'pmp' needs a smooth (twice differentiable) field, got {field!r}"
        )
    a = _as_pairs(starts, "starts")
    b = _as_pairs(goals, "goals")
    if a.shape != b.shape:
        raise InstanceError(f"starts and goals differ in shape: {a.shape} vs {b.shape}")
    if not (tol > 0 and max_iter >= 1 and max_steps >= 1):
        raise InstanceError("tol, max_iter and max_steps must be positive")
    size = len(a)
    guess = None
    if initial is not None:
        try:
            guess = np.array(
                [np.broadcast_to(np.asarray(x, dtype=float), (size,)) for x in initial]
            )
        except (TypeError, ValueError):
            guess = np.zeros(0)
        if guess.shape != (2, size) or not np.isfinite(guess).all() or (guess[1] <= 0).any():
            raise InstanceError(f"initial must be two finite (P,) arrays with T > 0, P = {size}")
    out = {
        "time": np.zeros(size),
        "heading": np.zeros(size),
        "accepted": np.ones(size, dtype=bool),
        "reason": np.full(size, OK, dtype=object),
        "iterations": np.zeros(size, dtype=int),
        "steps": np.zeros(size, dtype=int),
        "miss": np.zeros(size),
        "line_time": np.zeros(size),
        "extremal_time": np.zeros(size),
        "restarted": np.zeros(size, dtype=bool),
    }
    moving = np.flatnonzero(np.any(a != b, axis=1))
    if callback is not None and size - moving.size:
        callback(size - moving.size)
    if moving.size == 0:
        return PairTimes(**out)

    model = drift_model(field)
    lo = np.minimum(a[moving].min(axis=0), b[moving].min(axis=0))
    hi = np.maximum(a[moving].max(axis=0), b[moving].max(axis=0))
    margin = 0.25 * np.max(hi - lo)  # extremals bend out of the points' box
    bound = model.rate_bound(lo - margin, hi + margin, speed)
    if guess is None:
        first_psi, first_T = warm_start(model, a[moving].T.copy(), b[moving].T.copy(), speed)
    else:
        first_psi, first_T = guess[0, moving], guess[1, moving]
    threads = max(1, int(jobs)) if model.thread_safe else 1

    def run(rows: np.ndarray, psi0: np.ndarray, T0: np.ndarray, report: Any) -> list[np.ndarray]:
        # fixed chunks (independent of jobs, so the result is too), solved in threads:
        # numpy releases the GIL inside its array loops
        # an even number of batches (two threads share them evenly), none empty
        count = max(1, min(rows.size, 2 * -(-rows.size // (2 * CHUNK))))
        pieces = np.array_split(np.arange(rows.size), count)

        def solve(piece: np.ndarray) -> tuple[np.ndarray, ...]:
            r = rows[piece]
            first = (psi0[piece].copy(), T0[piece].copy())
            start, goal = a[r].T.copy(), b[r].T.copy()
            limits = (bound, tol, max_iter, max_steps)
            return _solve_chunk(model, speed, start, goal, first, *limits, report)

        if threads == 1 or len(pieces) == 1:
            parts = [solve(piece) for piece in pieces]
        else:
            with ThreadPoolExecutor(max_workers=min(threads, len(pieces))) as pool:
                parts = list(pool.map(solve, pieces))
        return [np.concatenate(column) for column in zip(*parts, strict=True)]

    duration, psi, ok, why, iters, steps, miss2, line = run(moving, first_psi, first_T, callback)
    extremal = np.where(why != NOT_CONVERGED, duration, np.nan)
    restarted = np.zeros(moving.size, dtype=bool)
    bad = np.flatnonzero(~ok)
    if restarts and bad.size:
        # other initial headings around the rejected extremal (or the first guess)
        offsets = np.asarray(RESTART_OFFSETS)
        converged = why[bad] != NOT_CONVERGED
        base_psi = np.where(converged, psi[bad], first_psi[bad])
        base_T = np.where(converged, duration[bad], first_T[bad])
        r_T, r_psi, r_ok, _, r_iter, r_steps, r_miss, _ = run(
            np.repeat(moving[bad], offsets.size),
            (base_psi[:, None] + offsets).ravel(),
            np.repeat(base_T, offsets.size),
            None,
        )
        times = np.where(r_ok, r_T, np.inf).reshape(bad.size, offsets.size)
        pick = np.argmin(times, axis=1)
        flat = np.arange(bad.size) * offsets.size + pick
        found = np.isfinite(times[np.arange(bad.size), pick])
        iters[bad] += r_iter.reshape(bad.size, offsets.size).sum(axis=1)
        win, flat = bad[found], flat[found]
        duration[win], psi[win] = r_T[flat], r_psi[flat]
        steps[win], miss2[win], extremal[win] = r_steps[flat], r_miss[flat], r_T[flat]
        ok[win], why[win], restarted[win] = True, OK, True

    out["time"][moving] = np.where(ok, duration, np.nan)
    out["heading"][moving] = psi
    out["accepted"][moving] = ok
    out["reason"][moving] = why
    out["iterations"][moving] = iters
    out["steps"][moving] = steps
    out["miss"][moving] = miss2
    out["line_time"][moving] = line
    out["extremal_time"][moving] = extremal
    out["restarted"][moving] = restarted
    return PairTimes(**out)


def triangle_violations(matrix: np.ndarray, rtol: float = 1e-9) -> list[tuple[int, int]]:
    """Entries ``(i, k)`` with ``t(i, k) > (t(i, j) + t(j, k)) (1 + rtol)`` for some ``j`` (Lemma 2.3).

    A time from (2.10) belongs to a real trajectory, so it is never below the
    optimum; a violated triangle therefore marks ``(i, k)`` as a slower
    extremal. O(N^3) in N vectorised (N, N) steps.
    """
    T = np.asarray(matrix, dtype=float)
    n = T.shape[0]
    best = np.full((n, n), np.inf)
    for j in range(n):
        via = T[:, j : j + 1] + T[j : j + 1, :]
        via[j, :] = np.inf
        via[:, j] = np.inf
        np.minimum(best, via, out=best)
    bad = T > best * (1.0 + rtol)
    np.fill_diagonal(bad, False)
    return [(int(i), int(k)) for i, k in np.argwhere(bad)]


def pmp_path(
    field: Field | None, start: Any, goal: Any, speed: float = 1.0, samples: int = 101
) -> Path:
    """Minimum-time path by :func:`pmp_travel_times`, sampled at ``samples`` instants.

    Raises
    ------
    ConvergenceError
        The pair was not accepted; the message gives the reason.
    """
    from taopt.navigation.shooting import navigation_law

    field = as_field(field)
    start = as_point(start, "start")
    goal = as_point(goal, "goal")
    speed = as_speed(speed)
    if np.array_equal(start, goal):
        return trivial_path(start, speed, "pmp")
    out = pmp_travel_times(field, start[None], goal[None], speed)
    if not out.accepted[0]:
        raise ConvergenceError(
            f"pmp did not solve the pair from {tuple(start)} to {tuple(goal)}: {out.reason[0]}"
        )
    duration = float(out.time[0])
    steps = max(int(samples) - 1, int(out.steps[0]))
    flow = _integrate(
        drift_model(field),
        speed,
        start[:, None],
        out.heading[:1],
        np.array([duration]),
        steps,
        False,
        record=True,
    )
    assert flow.samples is not None  # record=True
    states = flow.samples[:, :, 0]
    pick = np.round(np.linspace(0, steps, int(samples))).astype(int)
    xy = states[pick, :2] + start
    heading = states[pick, 2]
    return Path(
        start=start,
        goal=goal,
        speed=speed,
        time=duration,
        t=pick / steps * duration,
        xy=xy,
        heading=heading,
        heading_rate=navigation_law(field, xy, heading),
        method="pmp",
        status="converged",
        success=True,
        iterations=int(out.iterations[0]),
        info={
            "miss_distance": float(out.miss[0]) * float(np.linalg.norm(goal - start)),
            "initial_heading": float(out.heading[0]),
            "steps": int(out.steps[0]),
            "straight_line_time": float(out.line_time[0]),
        },
    )
