"""Precedence generators for the §5.5 studies and the Fig. 5.6 street example.

* :func:`layered_dag` — a layered DAG like Fig. 5.5 (40 customers; the figure's
  edges are not in the text, so this is our own generator, shape documented below).
* :func:`paired_precedences` — every customer has exactly one partner, as in the
  dial-a-ride setting of Tables 5.3–5.6 (Remark 5.2).
* :func:`residential_network` — a synthetic residential street network about 1 km
  across with customers beside the streets, for the Figs. 5.6–5.7 example.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from taopt.errors import InstanceError
from taopt.streets import cycle_path  # re-exported: the one precedence-cycle check


def layered_dag(
    n: int, layers: int = 8, density: float = 0.1, seed: int | np.random.Generator | None = 0
) -> tuple[tuple[int, int], ...]:
    """Random layered precedence DAG on customers 0..n-1, transitively reduced.

    Shape: the customers are shuffled and split into ``layers`` consecutive layers of
    (nearly) equal size. Every customer of layer l >= 1 gets one parent drawn uniformly
    from layer l−1 (so every customer except the first layer's is constrained and the
    longest chain has ``layers`` customers); each other pair (u in layer l−1, v in
    layer l) becomes an edge with probability ``density``, and each pair two layers
    apart with probability ``density / 2`` (these are often redundant). The result is
    the transitive reduction (Fig. 5.2 (b) style). With n = 40, layers = 8,
    density = 0.1 it has 5 customers per layer and 50–60 precedences, which is the
    look of Fig. 5.5 (a tall DAG over all 40 customers).

    Returns
    -------
    tuple of (r, j) pairs, sorted: r must be served before j.
    """
    n, layers = int(n), int(layers)
    if n < 1 or layers < 1:
        raise InstanceError(f"layered_dag needs n >= 1 and layers >= 1, got {n}, {layers}")
    if not 0.0 <= density <= 1.0:
        raise InstanceError(f"density = {density} must lie in [0, 1]")
    rng = np.random.default_rng(seed)
    layers = min(layers, n)
    groups = np.array_split(rng.permutation(n), layers)
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n))
    for level in range(1, layers):
        above, here = groups[level - 1], groups[level]
        for v in here:
            graph.add_edge(int(rng.choice(above)), int(v))
            for u in above:
                if rng.random() < density:
                    graph.add_edge(int(u), int(v))
            if level >= 2:
                for u in groups[level - 2]:
                    if rng.random() < density / 2:
                        graph.add_edge(int(u), int(v))
    return tuple(sorted(nx.transitive_reduction(graph).edges))


def paired_precedences(
    n: int, seed: int | np.random.Generator | None = 0
) -> tuple[tuple[int, int], ...]:
    """Dial-a-ride-like pairs: a random perfect matching of customers 0..n-1 (n even),
    each pair (r, j) oriented at random — r (the pick-up) before j (the destination).

    Every customer appears in exactly one pair (Remark 5.2, Tables 5.3–5.6).
    """
    n = int(n)
    if n < 2 or n % 2:
        raise InstanceError(f"paired_precedences needs an even n >= 2, got {n}")
    perm = np.random.default_rng(seed).permutation(n)
    return tuple(sorted((int(perm[2 * i]), int(perm[2 * i + 1])) for i in range(n // 2)))


def residential_network(
    n_customers: int = 20,
    seed: int | np.random.Generator | None = 0,
    blocks: tuple[int, int] = (7, 6),
    spacing: float = 160.0,
) -> tuple[np.ndarray, np.ndarray, nx.Graph]:
    """A synthetic residential neighbourhood (Figs. 5.6–5.7 stand-in).

    An irregular street grid of ``blocks`` = (columns, rows) junctions ``spacing``
    metres apart (≈ 1 km across with the defaults), jittered by up to 15 % of the
    spacing; about 15 % of the streets are removed (dead ends, blocks without a through
    road; the network stays connected) and a diagonal avenue crosses it. Street
    lengths are the straight-line lengths times a curvature factor in [1.0, 1.15].
    Customers (houses) sit beside a random street, 15–45 m off its centre line, so the
    nearest junction is at most ~0.6 × spacing away.

    Returns
    -------
    customers (n, 2), stops (s, 2), graph (networkx.Graph with "length").
    """
    rng = np.random.default_rng(seed)
    cols, rows = blocks
    gx, gy = np.meshgrid(np.arange(cols), np.arange(rows))
    stops = np.column_stack([gx.ravel(), gy.ravel()]) * spacing
    stops = stops + rng.uniform(-0.15, 0.15, stops.shape) * spacing
    graph = nx.Graph()
    graph.add_nodes_from(range(len(stops)))
    for r in range(rows):
        for c in range(cols):
            a = r * cols + c
            if c + 1 < cols:
                graph.add_edge(a, a + 1)
            if r + 1 < rows:
                graph.add_edge(a, a + cols)
    for k in range(min(cols, rows) - 1):  # the diagonal avenue
        graph.add_edge(k * cols + k, (k + 1) * cols + k + 1)
    for u, v in list(rng.permutation(list(graph.edges))):
        if rng.random() < 0.15:
            graph.remove_edge(int(u), int(v))
            if not nx.is_connected(graph):
                graph.add_edge(int(u), int(v))
    for u, v in graph.edges:
        straight = float(np.hypot(*(stops[u] - stops[v])))
        graph.edges[u, v]["length"] = straight * rng.uniform(1.0, 1.15)
    edges = list(graph.edges)
    customers = []
    for _ in range(int(n_customers)):
        u, v = edges[int(rng.integers(len(edges)))]
        a, b = stops[u], stops[v]
        along = rng.uniform(0.2, 0.8)
        direction = (b - a) / np.linalg.norm(b - a)
        normal = np.array([-direction[1], direction[0]])
        offset = rng.uniform(15.0, 45.0) * rng.choice([-1.0, 1.0])
        customers.append(a + along * (b - a) + offset * normal)
    return np.array(customers), stops, graph


__all__ = ["cycle_path", "layered_dag", "paired_precedences", "residential_network"]
