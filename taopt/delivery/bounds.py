"""Proposition 5.3: a lower bound on the optimal makespan from a min-cost arborescence.

G^d has the customers and the depot w_0 as vertices, the edges E^d allowed by the
precedences (:func:`taopt.delivery.costs.feasible_edges`) and the weights t* (5.11)
(:func:`taopt.delivery.costs.drone_cost_matrix`). The serving order of any feasible
plan is a Hamiltonian path w_0 -> c_π1 -> ... -> c_πn in G^d, which is an
arborescence rooted at w_0, and its weight is at most the makespan because t*
never exceeds the time between consecutive services. So the min-cost arborescence
(Edmonds' algorithm, :func:`taopt.arborescence.min_arborescence`) is a valid lower
bound f_a <= f_o.

:func:`path_bound` strengthens it (issue 16, item 2): the serving order is a Hamiltonian
*path*, so out-degrees are at most one; a Held–Karp-type Lagrangian relaxation of those
degree rows (:func:`taopt.arborescence.degree_penalised_arborescence`) gives a bound
that is never below f_a and, on the 120-customer tables, 8–11 % above it.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import breadth_first_order

from taopt.arborescence import (
    DEFAULT_ITERATIONS,
    degree_penalised_arborescence,
    greedy_path_weight,
    min_arborescence,
)
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


def service_gap_matrix(
    instance: DeliveryInstance, truck_metric: str = "street", include_service: bool = True
) -> np.ndarray:
    """t**: a lower bound on t_j − t_r for consecutive services, never below t* (5.11).

    Returns
    -------
    (n + 1, n + 1) array in the layout of :func:`taopt.delivery.costs.drone_cost_matrix`
    (depot = node n, its row t*(w_0, ·), column n inf, diagonal 0), with the customer block
    ``max(t*, t**)``.

    Notes
    -----
    For consecutive sorties r (launch i, landing k) and j (launch i'), the timing
    semantics of :mod:`taopt.delivery.evaluate` give exactly
    ``t_j − t_r = max(ft[r, k], tt[i, k] − ft[r, i] − τ) + τ + tt[k, i'] + ft[j, i'] + τ``
    (the recovery waits for the truck carrying from i to k), with (i, k) satisfying (5.6)
    for c_r, i ∈ V_r and i' ∈ V_j. Minimising over all such (i, k, i')::

        h_r(k)   = min_{i ∈ V_r, d(i, c_r) + d(c_r, k) <= L} max(ft[r, k], tt[i, k] − ft[r, i] − τ) + τ
        g_j(k)   = min_{i' ∈ V_j} tt[k, i'] + ft[j, i'] + τ
        t**(r, j) = min_k h_r(k) + g_j(k)

    is a valid lower bound on t_j − t_r. t* (5.11) is the same minimum with the truck
    term dropped and k only required within L_{c_r} of c_r, so t** >= t*; they differ when
    the landing stop the drone wants is out of the truck's reach (short ranges: +1–2 % on
    the bound at L/L0 = 0.15 on pairs120, nothing at L/L0 >= 0.6). O(n s^2 + n^2 s) time.
    The street metric is the true truck time; "euclidean" (a lower bound on it) is
    allowed as for t*.
    """
    from taopt.delivery.costs import _truck_times

    D = drone_cost_matrix(instance, truck_metric, include_service)
    n = instance.n
    fd, ft = instance.flight_distance, instance.flight_time
    tt = _truck_times(instance, truck_metric)
    tau = instance.service_time if include_service else 0.0
    limit = instance.flight_limit
    viable = fd + fd.min(axis=1, keepdims=True) <= limit  # (n, s): V_j
    landing = np.full(fd.shape, np.inf)  # h_r(k)
    for r in range(n):
        pair = (fd[r][:, None] + fd[r][None, :] <= limit) & viable[r][:, None]  # [i, k]
        gap = np.maximum(ft[r][None, :], tt - ft[r][:, None] - tau)
        landing[r] = np.where(pair, gap, np.inf).min(axis=0) + tau
    to_next = (tt[:, None, :] + np.where(viable, ft, np.inf)[None, :, :]).min(axis=2) + tau
    block = (landing[:, :, None] + to_next[None, :, :]).min(axis=1)  # (n, n)
    out = D.copy()
    out[:n, :n] = np.maximum(D[:n, :n], block)
    np.fill_diagonal(out, 0.0)
    return out


def path_bound(
    instance: DeliveryInstance,
    iterations: int = DEFAULT_ITERATIONS,
    truck_metric: str = "street",
    include_service: bool = True,
) -> float:
    """A valid lower bound on the optimal makespan (5.1), never below Proposition 5.3's.

    Held–Karp-type Lagrangian bound on the serving order as a Hamiltonian path of G^d
    with the weights max(t*, t**) (:func:`service_gap_matrix`, never below t* (5.11)).

    Parameters
    ----------
    instance : DeliveryInstance
    iterations : int
        Subgradient iterations (default 300: the value moves by < 0.1 % after that on the
        pairs120 instances). Any count gives a valid bound; 0 gives the plain
        arborescence on the "consecutive" edges with these weights.
    truck_metric, include_service
        As in :func:`arborescence_bound` (both choices valid).

    Returns
    -------
    float
        f_h with ``arborescence_bound(instance) <= f_h <= f_o``.

    Notes
    -----
    *Graph.* Vertices: the customers 0..n-1, the depot w_0 (n, the root) and a sink z
    (n + 1). Edges: E^d with the rule "consecutive" (r -> j unless j must precede r or
    some c_x must lie between them: such pairs are never consecutive), weight
    max(t*, t**)(c_r, c_j);
    w_0 -> c_j for customers without predecessors, weight t*(w_0, c_j); c_j -> z with
    weight 0 for customers without successors (only they can be served last).

    *Validity.* Take any feasible plan with order c_π1, ..., c_πn. As in Proposition 5.3,
    t_π1 >= t*(w_0, c_π1) and t_π(p+1) − t_πp >= max(t*, t**)(c_πp, c_π(p+1)) (proofs in
    :func:`taopt.delivery.costs.drone_cost_matrix` and :func:`service_gap_matrix`), so f = t_πn >= w(P) for the path
    P = w_0 -> c_π1 -> ... -> c_πn -> z, whose edges are all in the graph (consecutive
    customers have no customer forced between them; c_π1 has no predecessor; c_πn no
    successor). P is a spanning arborescence rooted at w_0 in which w_0 and every customer
    has out-degree exactly 1. For any π ∈ R^{n+1},
    ``w(P) = w(P) + Σ_v π_v (outdeg_P(v) − 1) = w_π(P) − Σ_v π_v >= Arb(w_π) − Σ_v π_v``
    with ``w_π(u, v) = w(u, v) + π_u``. So every L(π) = Arb(w_π) − Σ π_v is <= f for
    every feasible plan, hence <= f_o, with or without precedences. π = 0 gives the
    arborescence on the "consecutive" edges with weights >= t*, which is >= the "precede"
    arborescence of Proposition 5.3 (fewer edges, larger weights), and the maximum over the iterates is returned, so
    f_a <= f_h. The multipliers follow the subgradient outdeg − 1 with Polyak steps
    towards the t*-weight of a precedence-feasible nearest-neighbour path.

    *Cost.* One O(n^2)–O(n^3) Edmonds call per iteration: median 3.1 s (at worst 32 s)
    over the 60 pairs120 instances (n = 120, 300 iterations, 2 cores shared with other
    jobs).

    *What else was tried* (pairs120, instance 0, L/L0 = 0.3: Prop. 5.3 = 7852, this bound
    8533, SMMA 14095). A state-space relaxation of the exact DP with states (number of
    sorties, landing stop) and the exact timing (the recovery-to-recovery time of a sortie
    is additive, so the relaxed DP is a shortest path over stops), customers allowed to
    repeat, penalised by Lagrange multipliers on "served once": 6996 after 1500
    subgradient iterations (15 s), still below Prop. 5.3, because walks cycle through
    clusters of nearby customers; eliminating 2-cycles multiplies the work by n (~0.4 s
    per iteration) and was not pursued. The LP relaxation of the linear MILP has about
    n s^2 ≈ 1.8 M sortie variables at n = 120, s = 121, out of reach here.

    Example
    -------
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> path_bound(inst)  # the arborescence w0 -> c0 -> c1 is already a path
    20.0

    References
    ----------
    Thesis §5.3.2, Proposition 5.3 (the arborescence this tightens); Held and Karp (1970)
    for the degree multipliers.
    """
    n = instance.n
    D = service_gap_matrix(instance, truck_metric, include_service)
    weights = np.full((n + 2, n + 2), np.inf)
    edges = np.array(feasible_edges(instance, "consecutive"), dtype=np.int64).reshape(-1, 2)
    weights[edges[:, 0], edges[:, 1]] = D[edges[:, 0], edges[:, 1]]
    graph = instance.precedence_graph
    last = [j for j in range(n) if j not in graph or graph.out_degree(j) == 0]
    weights[last, n + 1] = 0.0
    capacity = np.ones(n + 2)
    capacity[n + 1] = 0.0
    equality = np.ones(n + 2, dtype=bool)
    need = [set(graph.predecessors(j)) if j in graph else set() for j in range(n)]
    need += [set(), set(range(n))]
    target = greedy_path_weight(weights, n, need)
    result = degree_penalised_arborescence(
        weights, n, capacity, equality, target=target, iterations=iterations
    )
    if not np.isfinite(result.arborescence):
        return arborescence_bound(instance, "consecutive", truck_metric, include_service)
    return result.value


def _path_graph(instance: DeliveryInstance) -> tuple[np.ndarray, np.ndarray, list[set[int]]]:
    """Edges of the path graph (customers, depot n, sink n + 1) and the predecessor sets."""
    n = instance.n
    allowed = np.zeros((n + 2, n + 2), dtype=bool)
    edges = np.array(feasible_edges(instance, "consecutive"), dtype=np.int64).reshape(-1, 2)
    allowed[edges[:, 0], edges[:, 1]] = True
    graph = instance.precedence_graph
    last = np.array([j for j in range(n) if j not in graph or graph.out_degree(j) == 0])
    allowed[last, n + 1] = True
    need = [set(graph.predecessors(j)) if j in graph else set() for j in range(n)]
    return allowed, last, need + [set(), set(range(n))]


def decomposition_bound(
    instance: DeliveryInstance, iterations: int = DEFAULT_ITERATIONS, patience: int = 10
) -> float:
    """A valid lower bound on f_o that prices the launch and landing stops of each sortie.

    Lagrangian decomposition of the exact timing: the serving order is a Hamiltonian path
    (relaxed to a degree-penalised arborescence, as in :func:`path_bound`), each customer
    chooses one launch stop i and one landing stop k, and the two are tied to the path's
    edges by launch potentials α_j(i) and landing potentials β_j(k) improved by the
    subgradient method together with the degree multipliers π.

    Parameters
    ----------
    instance : DeliveryInstance
    iterations : int
        Subgradient iterations (any count gives a valid bound; the value moves by < 0.1 %
        after ~250 on pairs120).
    patience : int
        Halve the step scale after this many iterations without improvement.

    Returns
    -------
    float
        f_d <= f_o; its first iterate is the arborescence on t** (:func:`service_gap_matrix`)
        on the "consecutive" edges, so f_d >= Proposition 5.3's f_a.

    Notes
    -----
    *Exact timing.* With S_p the launch and R_p the recovery of sortie p (customer j,
    launch i, landing k), :mod:`taopt.delivery.evaluate` gives
    ``R_p − S_p = A_j(i, k) = max(ft[j, i] + τ + ft[j, k], tt[i, k]) + τ`` for (i, k)
    within range (5.6) (then i, k ∈ V_j), ``S_{p+1} − R_p = tt[k, i']`` and
    ``f = t_last = S_last + ft[j_last, i_last] + τ``: the makespan is the additive sum
    ``tt[w_0, i_1] + Σ_{p<n} (A_p + tt[k_p, i_{p+1}]) + ft[j_n, i_n] + τ``.

    *Validity.* For any real α_j(i), β_j(k) write A_j(i, k) >= N_j + α_j(i) + β_j(k) with
    ``N_j = min_{(i, k) in range} A_j(i, k) − α_j(i) − β_j(k)`` and
    ``ft[j, i] + τ >= F_j + α_j(i)`` with ``F_j = min_{i ∈ V_j} ft[j, i] + τ − α_j(i)``.
    Then, for every feasible plan,
    ``f >= Σ_j N_j + w(P)`` where P = w_0 -> c_π1 -> ... -> c_πn -> z on the graph of
    :func:`path_bound` with the weights ``W[w_0, j] = min_i tt[w_0, i] + α_j(i)``,
    ``W[r, j] = min_{k, i} β_r(k) + tt[k, i] + α_j(i)`` and ``W[j, z] = F_j − N_j``
    (the plan's own stops are among those minimised over). P is a spanning arborescence
    with every out-degree 1 (sink 0), so for every π
    ``f >= Σ_j N_j + Arb(W + π ⊗ 1) − Σ_v π_v`` (as in :func:`path_bound`): a valid bound
    for every (α, β, π), with or without precedences. Initial α_j(i) = ft[j, i] + τ and
    β_r(k) = h_r(k) of :func:`service_gap_matrix` make W the t** matrix and N_j >= 0.

    *Subgradients.* For π: out-degree − 1. For α_j: +1 at the launch stop the tree's
    in-edge of j uses, −1 at the node's own launch (its final launch if j -> z is in the
    tree). For β_r: +1 at the landing stop each tree out-edge of r uses, −1 at the node's
    landing unless r -> z is in the tree. Polyak steps towards Σ N + a greedy path's
    weight (first iterate).

    *Cost.* Per iteration O(n s^2 + n^2 s) numpy work plus one Edmonds call: median 6.4 s
    (at worst 16 s) over the 60 pairs120 instances (n = 120, s = 121, 300 iterations, 2
    cores shared with other jobs). On pairs120 it adds 7 % to :func:`path_bound` at
    L/L0 = 0.15 and about 1 % at the longer ranges. On 12 random pick-up/delivery instances (n = 12, v_d/v_t = 1.4, L/L0 =
    0.15 and 0.3; exact optimum by the subset DP) the mean ratio to the optimum is 0.60 for
    Proposition 5.3, 0.69 for :func:`path_bound` and 0.79 for this bound.

    Example
    -------
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> decomposition_bound(inst) <= 30.0  # the optimum (taopt.schedule: 30 s)
    True

    References
    ----------
    Thesis §5.2 (timing (5.1)–(5.7)), §5.3.2 (Proposition 5.3); Held and Karp (1970);
    Guignard and Kim (1987) on Lagrangian decomposition.
    """
    n, s = instance.n, instance.s
    fd, ft, tt = instance.flight_distance, instance.flight_time, instance.truck_time
    tau, limit, depot = instance.service_time, instance.flight_limit, instance.depot
    viable = fd + fd.min(axis=1, keepdims=True) <= limit  # (n, s): V_j
    sortie = np.full((n, s, s), np.inf)  # A_j(i, k) within range
    for j in range(n):
        pair = (fd[j][:, None] + fd[j][None, :] <= limit) & viable[j][:, None]
        sortie[j] = np.where(
            pair, np.maximum(ft[j][:, None] + tau + ft[j][None, :], tt) + tau, np.inf
        )
    lands = np.isfinite(sortie).any(axis=1)  # (n, s): possible landing stops
    final = np.where(viable, ft + tau, np.inf)
    alpha = np.where(viable, ft + tau, 0.0)
    gap = np.maximum(ft[:, None, :], tt[None, :, :] - ft[:, :, None] - tau)
    beta = np.where(lands, np.where(np.isfinite(sortie), gap, np.inf).min(axis=1) + tau, 0.0)
    allowed, _, need = _path_graph(instance)
    rows = np.arange(n)
    pi = np.zeros(n + 2)
    best, target, scale, stall = -np.inf, np.inf, 2.0, 0
    for iteration in range(max(int(iterations), 1)):
        reduced = (sortie - alpha[:, :, None] - beta[:, None, :]).reshape(n, -1)
        node_arg = reduced.argmin(axis=1)
        node = reduced[rows, node_arg]
        node_launch, node_landing = np.divmod(node_arg, s)
        final_reduced = final - alpha
        final_launch = final_reduced.argmin(axis=1)
        final_value = final_reduced[rows, final_launch]
        alpha_in = np.where(viable, alpha, np.inf)
        beta_out = np.where(lands, beta, np.inf)
        via = (beta_out[:, :, None] + tt[None, :, :]).min(axis=1)  # (n, s): min_k β_r(k) + tt[k, i]
        weights = np.full((n + 2, n + 2), np.inf)
        weights[:n, :n] = (via[:, None, :] + alpha_in[None, :, :]).min(axis=2)
        weights[n, :n] = (tt[depot][None, :] + alpha_in).min(axis=1)
        weights[:n, n + 1] = final_value - node
        weights[~allowed] = np.inf
        if iteration == 0:
            target = float(node.sum()) + greedy_path_weight(weights, n, need)
        total, tree = min_arborescence(weights + pi[:, None], n, tree=True)
        if tree is None:  # no Hamiltonian path in the graph: cannot happen on a valid instance
            return arborescence_bound(instance)
        value = float(node.sum()) + total - float(pi[: n + 1].sum())
        if value > best + 1e-12 * abs(value):
            best, stall = value, 0
        else:
            stall += 1
            if stall >= patience:
                scale, stall = scale / 2.0, 0
        if iteration + 1 >= iterations or scale < 1e-7:
            break
        degree = np.bincount(tree[tree >= 0], minlength=n + 2).astype(float)
        g_pi = degree - 1.0
        g_pi[n + 1] = 0.0
        g_alpha = np.zeros((n, s))
        g_beta = np.zeros((n, s))
        parent = tree[:n]
        from_depot = parent == n
        launch_in = np.empty(n, dtype=np.int64)
        launch_in[from_depot] = (tt[depot][None, :] + alpha_in[from_depot]).argmin(axis=1)
        inner = np.flatnonzero(~from_depot)
        launch_in[inner] = (via[parent[inner]] + alpha_in[inner]).argmin(axis=1)
        landing_out = (beta_out[parent[inner]] + tt[:, launch_in[inner]].T).argmin(axis=1)
        np.add.at(g_alpha, (rows, launch_in), 1.0)
        np.add.at(g_beta, (parent[inner], landing_out), 1.0)
        is_last = rows == tree[n + 1]
        np.add.at(g_alpha, (rows, np.where(is_last, final_launch, node_launch)), -1.0)
        np.add.at(g_beta, (rows[~is_last], node_landing[~is_last]), -1.0)
        norm = float(g_pi @ g_pi + (g_alpha**2).sum() + (g_beta**2).sum())
        if norm == 0.0:
            break
        step = scale * max(target - value, 1e-9 * abs(target)) / norm
        pi += step * g_pi
        alpha += step * g_alpha
        beta += step * g_beta
    return float(best)


def delivery_lower(instance: DeliveryInstance, strength: str) -> float:
    """:func:`taopt.bounds.lower` for chapter 5: Proposition 5.3 ("fast"), else the larger of
    :func:`decomposition_bound`, :func:`path_bound` and Proposition 5.3."""
    if strength == "fast":
        return arborescence_bound(instance)
    return float(
        max(decomposition_bound(instance), path_bound(instance), arborescence_bound(instance))
    )


__all__ = [
    "delivery_lower",
    "arborescence_bound",
    "path_bound",
    "service_gap_matrix",
    "decomposition_bound",
]
