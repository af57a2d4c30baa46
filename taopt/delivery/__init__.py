"""Chapter 5: precedence-constrained truck–drone delivery.

Modules: :mod:`~taopt.delivery.instance` (DeliveryInstance, Plan),
:mod:`~taopt.delivery.evaluate` (the one scorer, timelines),
:mod:`~taopt.delivery.schedule` (exact DP for a fixed order),
:mod:`~taopt.delivery.costs` (t* of (5.8)–(5.11), E^d),
:mod:`~taopt.delivery.bounds` (Proposition 5.3), :mod:`~taopt.delivery.dags`
(precedence generators), :mod:`~taopt.delivery.plot`, :mod:`~taopt.orchestration.studies.delivery`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from taopt.delivery import family as _family  # noqa: F401  (registers the family)
from taopt.delivery.instance import DeliveryInstance, Plan

EXAMPLE_PATH = Path(__file__).resolve().parent.parent / "data" / "delivery_example_20.json"


def build_example_instance(seed: int = 7, flight_range: float = 250.0, n: int = 20) -> Any:
    """Build the 20-customer residential example (Figs. 5.6–5.7 stand-in) from scratch.

    ``n`` gives the same neighbourhood with another number of customers (named
    ``residential-<n>``), as the time-limit tests and benchmarks use.

    A synthetic neighbourhood ≈ 1 km across (:func:`taopt.delivery.dags.residential_network`),
    depot at junction 0 (south-west corner), v_d = 30 km/h, v_t = 40 km/h (in m/s),
    landing time τ = 30 s, L = 250 m, precedences from
    :func:`taopt.delivery.dags.layered_dag` (20 customers, 5 layers, density 0.15). The
    stored file ``taopt/data/delivery_example_20.json`` is this with ``seed=7``.
    """
    from taopt.delivery.dags import layered_dag, residential_network
    from taopt.delivery.instance import DeliveryInstance

    customers, stops, graph = residential_network(n, seed=seed)
    stops = stops.round(1)
    # Rounding the stops can move two ends of a straight street apart by up to 0.14 m; a
    # street is never shorter than its chord, so lengths are raised to the rounded chord
    # (a no-op for seed 7, the shipped example).
    for u, v, data in graph.edges(data=True):
        chord = float(np.hypot(*(stops[u] - stops[v])))
        data["length"] = max(float(data["length"]), chord)
    return DeliveryInstance(
        customers=customers.round(1),
        stops=stops,
        graph=graph,
        depot=0,
        v_drone=30 / 3.6,
        v_truck=40 / 3.6,
        flight_range=flight_range,
        precedences=layered_dag(n, layers=5, density=0.15, seed=seed),
        service_time=30.0,
        name=f"residential-{n}",
    )


def example_instance(L: float = 250.0) -> Any:
    """The stored 20-customer residential example with flight range ``L`` (250 or 300 m)."""
    from taopt.delivery.instance import DeliveryInstance

    inst = DeliveryInstance.load(EXAMPLE_PATH)
    return inst if L == inst.flight_range else inst.replace(flight_range=float(L))


__all__ = [
    "DeliveryInstance",
    "Plan",
    "example_instance",
    "build_example_instance",
    "EXAMPLE_PATH",
]
