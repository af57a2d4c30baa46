"""The one chapter 5 scorer: check a :class:`Plan` against (5.2)–(5.7) and time it.

Timing semantics (shared by the DP scheduler, the MILP and this scorer). The truck
and the drone start together at the depot at time 0, drone aboard. Sortie p serves
customer ``j = order[p]`` from launch stop ``i = launch[p]`` to landing stop
``k = landing[p]``. With ``R_{-1} = 0`` and ``prev_{-1} = depot``::

    S_p = R_{p-1} + truck_time[prev_{p-1}, i]                 launch
    t_j = S_p + flight_time[j, i] + τ                          customer served
    R_p = max(t_j + flight_time[j, k], S_p + truck_time[i, k]) + τ   recovery at k
    prev_p = k

The objective (5.1) is the makespan ``f = max_j t_j``, the time of the last sortie's
service (times increase along the order).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.errors import FeasibilityError


@dataclass(frozen=True)
class Timeline:
    """Per-sortie times of a plan (all arrays in sortie order).

    Attributes
    ----------
    launch_time : (n,) S_p, when the drone leaves the truck at ``launch[p]``.
    service_time : (n,) t_j of the customer ``order[p]`` (served when its landing ends).
    drone_return : (n,) when the drone reaches the landing stop (before τ).
    truck_arrival : (n,) when the truck reaches the landing stop.
    recovery_time : (n,) R_p, when the drone is back aboard and the truck may leave.
    truck_legs : list of (from_stop, to_stop, depart, arrive, kind) with kind
        ``"reposition"`` (drone aboard, prev -> launch) or ``"carry"`` (drone out,
        launch -> landing). Zero-length legs are kept (from == to).
    makespan : float, (5.1).
    """

    launch_time: np.ndarray
    service_time: np.ndarray
    drone_return: np.ndarray
    truck_arrival: np.ndarray
    recovery_time: np.ndarray
    truck_legs: list[tuple[int, int, float, float, str]]
    makespan: float


def _as_plan(plan: Any) -> Plan:
    if isinstance(plan, Plan):
        return plan
    if hasattr(plan, "plan") and hasattr(plan, "objective"):
        plan = plan.plan
        if isinstance(plan, Plan):
            return plan
    if isinstance(plan, dict):
        return Plan.from_dict(plan)
    raise FeasibilityError(f"expected a Plan, got {type(plan).__name__}")


def check_plan(instance: DeliveryInstance, plan: Plan, complete: bool = True) -> None:
    """Raise :class:`FeasibilityError` naming the first violated constraint of (5.2)–(5.7).

    Parameters
    ----------
    complete : bool
        If True (default) every customer must be served exactly once (5.2); if False
        (partial plans during construction) each listed customer at most once, and
        precedences are checked only between listed customers.
    """
    plan = _as_plan(plan)
    n, s = instance.n, instance.s
    order = np.asarray(plan.order, dtype=np.int64)
    launch = np.asarray(plan.launch, dtype=np.int64)
    landing = np.asarray(plan.landing, dtype=np.int64)
    # indices
    for p, j in enumerate(plan.order):
        if not 0 <= j < n:
            raise FeasibilityError(f"(5.2) sortie {p}: customer {j} does not exist (0..{n - 1})")
    for name, stops in (("launch", plan.launch), ("landing", plan.landing)):
        for p, w in enumerate(stops):
            if not 0 <= w < s:
                raise FeasibilityError(
                    f"(5.3)/(5.5) sortie {p}: {name} stop {w} is not a stop (0..{s - 1})"
                )
    # (5.2) each customer exactly once
    counts = np.bincount(order, minlength=n) if len(order) else np.zeros(n, dtype=np.int64)
    twice = np.flatnonzero(counts > 1)
    if twice.size:
        j = int(twice[0])
        raise FeasibilityError(f"(5.2) customer {j} is served {int(counts[j])} times")
    if complete:
        missing = np.flatnonzero(counts == 0)
        if missing.size:
            raise FeasibilityError(
                f"(5.2) customer {int(missing[0])} is never served "
                f"({missing.size} of {n} customers missing)"
            )
    # (5.6) flight range
    if len(order):
        fd = instance.flight_distance
        flown = fd[order, launch] + fd[order, landing]
        over = np.flatnonzero(flown > instance.flight_limit)
        if over.size:
            p = int(over[0])
            raise FeasibilityError(
                f"(5.6) sortie {p} to customer {int(order[p])}: flight {launch[p]} -> "
                f"customer -> {landing[p]} is {flown[p]:.6g} > L = {instance.flight_range:.6g}"
            )
    # (5.7) precedences
    position = np.full(n, -1, dtype=np.int64)
    position[order] = np.arange(len(order))
    for r, j in instance.precedences:
        if position[r] < 0 or position[j] < 0:
            continue  # only possible when complete=False
        if position[r] > position[j]:
            raise FeasibilityError(
                f"(5.7) precedence ({r}, {j}) violated: customer {r} must be served before "
                f"customer {j}, but is served at sortie {position[r]} after sortie {position[j]}"
            )
    if not complete:
        for r, j in instance.precedences:
            if position[j] >= 0 and position[r] < 0:
                raise FeasibilityError(
                    f"(5.7) precedence ({r}, {j}) violated: customer {j} is served but its "
                    f"predecessor {r} is not in the plan"
                )


def timeline(instance: DeliveryInstance, plan: Any, check: bool = True) -> Timeline:
    """Times of every sortie and the truck legs under the module's timing semantics.

    Parameters
    ----------
    check : bool
        Check (5.2)–(5.7) first (default). Partial plans are allowed here only with
        ``check=False``.
    """
    plan = _as_plan(plan)
    if check:
        check_plan(instance, plan)
    tt = instance.truck_time
    ft = instance.flight_time
    tau = instance.service_time
    m = len(plan.order)
    S = np.zeros(m)
    t = np.zeros(m)
    back = np.zeros(m)
    truck = np.zeros(m)
    R = np.zeros(m)
    legs: list[tuple[int, int, float, float, str]] = []
    ready = 0.0
    prev = instance.depot
    for p, (j, i, k) in enumerate(zip(plan.order, plan.launch, plan.landing, strict=True)):
        # the same floating-point operations, in the same order, as the DP scheduler
        S[p] = ready + tt[prev, i]
        legs.append((prev, i, ready, float(S[p]), "reposition"))
        t[p] = S[p] + ft[j, i] + tau
        back[p] = t[p] + ft[j, k]
        truck[p] = S[p] + tt[i, k]
        legs.append((i, k, float(S[p]), float(truck[p]), "carry"))
        R[p] = max(back[p], truck[p]) + tau
        ready = float(R[p])
        prev = k
    makespan = float(t.max()) if m else 0.0
    return Timeline(S, t, back, truck, R, legs, makespan)


def evaluate_plan(instance: DeliveryInstance, plan: Any) -> float:
    """The makespan (5.1) of a plan, after checking (5.2)–(5.7).

    Parameters
    ----------
    instance : DeliveryInstance
    plan : Plan, a Solution carrying one, or a dict with order/launch/landing

    Returns
    -------
    float
        ``f = max_j t_j``, the time the last customer is served.

    Raises
    ------
    FeasibilityError
        Naming the violated constraint: (5.2) a customer missing or served twice,
        (5.3)/(5.5) a launch or landing index that is not a stop, (5.6) a sortie longer
        than L, (5.7) a precedence served in the wrong order.

    Example
    -------
    >>> from taopt.delivery.instance import DeliveryInstance, Plan
    >>> inst = DeliveryInstance.grid([[0, 100]], k=2, side=100, v_drone=10, v_truck=5,
    ...                              flight_range=150)
    >>> evaluate_plan(inst, Plan((0,), (2,), (2,)))  # drive 100 m (20 s), fly 0 m
    20.0
    """
    return timeline(instance, plan, check=True).makespan


__all__ = ["evaluate_plan", "timeline", "check_plan", "Timeline"]
