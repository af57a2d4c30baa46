"""Proposition 5.3: a lower bound on the optimal makespan from a min-cost arborescence.

G^d has the customers and the depot w_0 as vertices, the edges E^d allowed by the
precedences (:func:`taopt.delivery.costs.feasible_edges`) and the weights t* (5.11)
(:func:`taopt.delivery.costs.drone_cost_matrix`). The serving order of any feasible
plan is a Hamiltonian path w_0 -> c_π1 -> ... -> c_πn in G^d, which is an
arborescence rooted at w_0, and its weight is at most the makespan because t*
never exceeds the time between consecutive services. So the min-cost arborescence
(Edmonds' algorithm, :func:`taopt.arborescence.min_arborescence`) is a valid lower
bound f_a <= f_o.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import breadth_first_order

from taopt.arborescence import min_arborescence
from taopt.delivery.costs import drone_cost_matrix, feasible_edges
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError, SolverError


def arborescence_bound(
    instance: DeliveryInstance,
    rule: str = "precede",
    truck_metric: str = "street",
    include_service: bool = True,
    method: str = "numpy",
) -> float:
    """f_a of Proposition 5.3: the weight of a min-cost arborescence of G^d rooted at w_0.

    Parameters
    ----------
    instance : DeliveryInstance
    rule : {"precede", "consecutive", "thesis"}
        Which E^d (see :func:`taopt.delivery.costs.feasible_edges`). "precede" (default)
        and "consecutive" give valid bounds; "thesis" builds E^d from the sets S_r as
        printed in §5.3.2, which can miss the optimal path's edges, so it is not a
        proven bound (kept to compare with the thesis's q (5.19)).
    truck_metric : {"street", "euclidean"}
        Truck distance inside t* (both valid; "street" is tighter).
    include_service : bool
        Include the landing times τ in t* (valid; no effect when τ = 0).
    method : {"numpy", "networkx"}
        Edmonds' algorithm by :func:`taopt.arborescence.min_arborescence` (dense numpy, ~10 ms for
        120 customers) or by ``networkx.minimum_spanning_arborescence`` (the reference;
        pure Python, ~10 s for 120 customers). Both give the same value.

    Returns
    -------
    float
        f_a <= f_o, the optimal makespan (5.1) (for the valid rules).

    Raises
    ------
    SolverError
        G^d has no arborescence rooted at w_0 (cannot happen for the valid rules on a
        validated instance).

    Notes
    -----
    Edges get weight t* and the depot has no in-edges, so every spanning arborescence
    is rooted at w_0.

    Example
    -------
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> arborescence_bound(inst)  # w0 -> c0 (10 s) -> c1 (10 s)
    20.0

    References
    ----------
    Thesis §5.3.2, Proposition 5.3; (5.19) uses f_a for q = f / f_a.
    """
    n = instance.n
    D = drone_cost_matrix(instance, truck_metric, include_service)
    weights = np.full_like(D, np.inf)
    edges = np.array(feasible_edges(instance, rule), dtype=np.int64).reshape(-1, 2)
    weights[edges[:, 0], edges[:, 1]] = D[edges[:, 0], edges[:, 1]]
    if method == "numpy":
        value = min_arborescence(weights, root=n)
        if not np.isfinite(value):
            reached = breadth_first_order(
                csr_matrix(np.isfinite(weights)), n, return_predecessors=False
            )
            missing = int(np.setdiff1d(np.arange(n + 1), reached)[0])
            raise SolverError(
                f"no arborescence: customer {missing} cannot be reached from the depot"
            )
        return value
    if method != "networkx":
        raise InstanceError(f"method must be 'numpy' or 'networkx', got {method!r}")
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n + 1))
    for u, v in zip(*np.nonzero(np.isfinite(weights)), strict=True):
        if u != v:
            graph.add_edge(int(u), int(v), weight=float(weights[u, v]))
    try:
        tree = nx.minimum_spanning_arborescence(graph, attr="weight", preserve_attrs=True)
    except nx.NetworkXException as exc:
        raise SolverError(f"G^d has no spanning arborescence rooted at the depot ({exc})") from None
    return float(sum(d["weight"] for _, _, d in tree.edges(data=True)))


__all__ = ["arborescence_bound"]
