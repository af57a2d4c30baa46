"""Fleet instances in the thesis's style: chapter 5's residential street network and layered
precedence DAGs (:mod:`taopt.delivery.dags`), with K trucks, D drones each, capacity c."""

from __future__ import annotations

from taopt.fleet.problem import FleetProblem


def residential_fleet(
    n: int,
    trucks: int = 2,
    drones: int = 2,
    capacity: int = 2,
    density: float = 0.15,
    layers: int | None = None,
    seed: int = 0,
    flight_range: float = 400.0,
    objective: str = "last_service",
) -> FleetProblem:
    """n drone-only customers beside the streets of :func:`taopt.delivery.dags.residential_network`
    (≈ 1 km across, 42 junctions), depot at junction 0, v_d = 30 km/h, v_t = 40 km/h,
    τ = 30 s, range ``flight_range`` m per sortie (all legs), precedences a
    :func:`taopt.delivery.dags.layered_dag` (``layers`` default ``max(2, n // 3)``; ``density``
    0 gives each customer past the first layer one parent only), as chapter 5's dag40.
    """
    from taopt.delivery.dags import layered_dag, residential_network

    customers, stops, graph = residential_network(n, seed=seed)
    layers = max(2, n // 3) if layers is None else layers
    return FleetProblem(
        customers=customers.round(1),
        stops=stops,
        graph=graph,
        depot=0,
        drones=[drones] * trucks,
        capacity=capacity,
        flight_range=flight_range,
        v_truck=40 / 3.6,
        v_drone=30 / 3.6,
        precedences=layered_dag(n, layers=layers, density=density, seed=seed) if layers else (),
        service_time=30.0,
        objective=objective,
        name=f"fleet-n{n}-K{trucks}-D{drones}-c{capacity}-s{seed}",
    )


__all__ = ["residential_fleet"]
