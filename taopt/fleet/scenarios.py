"""Fleet instances in the thesis's style: layered precedence DAGs on a residential street network.

Chapter 5's ``dag40`` study puts 40 customers under a layered DAG (Fig. 5.5); its Figs. 5.6–5.7
example is a residential street network. :func:`fleet_scenario` combines the two for the fleet
(§6.2): :func:`taopt.delivery.dags.residential_network` (≈ 1 km across, houses beside the
streets) and :func:`taopt.delivery.dags.layered_dag` (about five customers per layer), with K
trucks of D drones each and drone capacity c.
"""

from __future__ import annotations

import numpy as np

from taopt.delivery.dags import layered_dag, residential_network
from taopt.errors import InstanceError
from taopt.fleet.problem import FleetProblem

#: The two precedence densities of the study: the probability of each extra edge between
#: consecutive layers of :func:`~taopt.delivery.dags.layered_dag` (chapter 5's dag40 uses 0.1).
DENSITIES = {"sparse": 0.05, "dense": 0.3}

#: Speeds (m/s): a truck at 36 km/h in town, a drone at 54 km/h.
V_TRUCK, V_DRONE = 10.0, 15.0

#: The flight range of one sortie, all legs (m), and τ, the landing/loading time (s).
FLIGHT_RANGE, SERVICE_TIME = 800.0, 10.0


def fleet_scenario(
    n: int,
    trucks: int = 1,
    drones: int = 1,
    capacity: int = 1,
    density: str = "sparse",
    seed: int = 0,
    truck_share: float = 0.25,
    objective: str = "last_service",
) -> FleetProblem:
    """A fleet instance: ``n`` houses on a residential network, a layered precedence DAG.

    Parameters
    ----------
    n : int
        Customers (houses beside the streets).
    trucks, drones, capacity : int
        K, D_k (the same for every truck) and c.
    density : {"sparse", "dense"}
        :data:`DENSITIES`; the DAG has ``max(1, n // 5)`` layers (five customers a layer).
    seed : int
        The network, the houses, the DAG and the service modes depend on ``seed`` and ``n``
        only, so the fleets (K, D, c) of one seed share the customers.
    truck_share : float
        The share of customers a truck may serve too (``"both"``, at the stop nearest the
        house); the others are drone-only (chapter 5's rule).
    objective : {"last_service", "return"}

    Returns
    -------
    FleetProblem

    Raises
    ------
    InstanceError
        Unknown density, a share outside [0, 1].

    Example
    -------
    >>> p = fleet_scenario(10, trucks=2, drones=2, capacity=2, seed=1)
    >>> p.n, p.K, p.D, p.capacity
    (10, 2, 4, 2)
    """
    if density not in DENSITIES:
        raise InstanceError(f"density must be one of {sorted(DENSITIES)}, got {density!r}")
    if not 0.0 <= truck_share <= 1.0:
        raise InstanceError(f"truck_share = {truck_share} must lie in [0, 1]")
    rng = np.random.default_rng([int(seed), int(n)])
    customers, stops, graph = residential_network(int(n), seed=rng)
    pairs = layered_dag(int(n), layers=max(1, int(n) // 5), density=DENSITIES[density], seed=rng)
    both = rng.random(int(n)) < truck_share
    nearest = [int(np.argmin(np.hypot(*(stops - c).T))) for c in customers]
    depot = int(np.argmin(np.hypot(*(stops - stops.mean(axis=0)).T)))
    return FleetProblem(
        customers=customers,
        stops=stops,
        graph=graph,
        depot=depot,
        drones=[int(drones)] * int(trucks),
        capacity=int(capacity),
        flight_range=FLIGHT_RANGE,
        v_truck=V_TRUCK,
        v_drone=V_DRONE,
        service=["both" if b else "drone" for b in both],
        customer_stop=[nearest[j] if both[j] else None for j in range(int(n))],
        precedences=pairs,
        service_time=SERVICE_TIME,
        objective=objective,
        name=f"fleet-n{n}-K{trucks}-D{drones}-c{capacity}-{density}-s{seed}",
    )


__all__ = ["DENSITIES", "fleet_scenario"]
