"""Closed-form minimum time in a uniform drift (Lemma 2.3's proof, (3.4)).

In a spatially constant drift the navigation law (2.6) gives ``psi_dot = 0``:
the heading is constant, the path is the straight segment, and the net speed
``v_net`` along the unit direction ``d`` solves the quadratic (3.4),

    v_net**2 - 2 (v_c . d) v_net - (v**2 - |v_c|**2) = 0,

whose positive root is ``v_net = v_c . d + sqrt(v**2 - |v_c|**2 + (v_c . d)**2)``.
The root exists iff the discriminant is non-negative, which is (3.5); under
Assumption 2.1 (``v > |v_c|``) it always does and ``v_net > 0``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from taopt.navigation.path import Path, as_point, as_speed


def net_speed(drift: Any, direction: Any, speed: float) -> np.ndarray:
    """Net speed ``v_net`` along unit ``direction`` (..., 2) in drift ``drift`` (..., 2), (3.4).

    Returns ``nan`` where (3.5) fails (no heading makes the vehicle move along
    ``direction``) and where the positive root is not positive.

    Notes
    -----
    (3.4)'s root is homogeneous of degree 1 in ``(v, v_c)``, so speeds above 1e100 are
    divided by ``s = max(v, |v_c|)`` and the root multiplied back: squaring a speed of
    1.3e154 would overflow, the scaled squares never do.
    """
    drift = np.asarray(drift, dtype=float)
    direction = np.asarray(direction, dtype=float)
    speed = float(speed)
    scale = max(abs(speed), float(np.max(np.abs(drift), initial=0.0)))
    if not np.isfinite(scale) or scale < 1e100:  # ordinary speeds: the same bits as unscaled
        scale = 1.0
    drift, speed = drift / scale, speed / scale
    along = np.sum(drift * direction, axis=-1)
    disc = speed**2 - np.sum(drift * drift, axis=-1) + along**2
    with np.errstate(invalid="ignore", over="ignore"):
        vnet = (along + np.sqrt(disc)) * scale
    return np.where((disc >= 0) & (vnet > 0), vnet, np.nan)


def uniform_travel_times(drift: Any, starts: Any, goals: Any, speed: float = 1.0) -> np.ndarray:
    """Vectorised closed-form travel times ``|goal - start| / v_net`` (3.4).

    Parameters
    ----------
    drift : (2,) array_like
        The constant drift ``v_c``.
    starts, goals : (..., 2) array_like
        Broadcastable start and goal points.
    speed : float
        Vehicle speed ``v``.

    Returns
    -------
    ndarray
        Times, 0 where start equals goal, ``inf`` where (3.5) fails.

    Example
    -------
    >>> float(uniform_travel_times([0.5, 0.0], [0, 0], [3, 0], speed=1.0))
    2.0
    """
    delta = np.asarray(goals, dtype=float) - np.asarray(starts, dtype=float)
    dist = np.linalg.norm(delta, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = delta / dist[..., None]
        vnet = net_speed(
            np.broadcast_to(np.asarray(drift, dtype=float), delta.shape), direction, speed
        )
        times = dist / vnet
    times = np.where(np.isnan(times), np.inf, times)
    return np.where(dist == 0, 0.0, times)


def uniform_heading(drift: Any, start: Any, goal: Any, speed: float = 1.0) -> float:
    """Constant optimal heading: ``v (cos psi, sin psi) = v_net d - v_c``."""
    drift = np.asarray(drift, dtype=float)
    delta = np.asarray(goal, dtype=float) - np.asarray(start, dtype=float)
    direction = delta / np.linalg.norm(delta)
    vnet = float(net_speed(drift, direction, speed))
    thrust = vnet * direction - drift
    return float(np.arctan2(thrust[1], thrust[0]))


def closed_form_path(
    drift: Any, start: Any, goal: Any, speed: float = 1.0, samples: int = 21
) -> Path:
    """The straight-line minimum-time path in a uniform drift (closed form)."""
    start = as_point(start, "start")
    goal = as_point(goal, "goal")
    speed = as_speed(speed)
    time = float(uniform_travel_times(drift, start, goal, speed))
    frac = np.linspace(0.0, 1.0, samples)
    heading = uniform_heading(drift, start, goal, speed) if time > 0 else 0.0
    return Path(
        start=start,
        goal=goal,
        speed=speed,
        time=time,
        t=frac * time,
        xy=start + frac[:, None] * (goal - start),
        heading=np.full(samples, heading),
        heading_rate=np.zeros(samples),
        method="closed_form",
        status="closed_form" if np.isfinite(time) else "infeasible",
        success=bool(np.isfinite(time)),
    )
