"""Order ideals of a precedence DAG as bitmasks: enumeration by size and count.

An *order ideal* (a down-set) of a DAG is a set of nodes closed under predecessors: with a
node it holds every node that must come before it. Chapter 5's exact DP runs over the
ideals of G^p (:func:`taopt.delivery.ideal_dp.ideal_dp`) and the SOP's over those of its
precedence closure (:func:`taopt.models.sop_dp.solve_sop_dp`): the sets a partial
schedule or path may have served, never all 2^n subsets. Both families take the ideals
from here.

Representation: node ``j`` is bit ``j`` of a ``uint64`` mask, so at most :data:`MAX_BITS`
nodes; ``need[j]`` is the mask of every node that must precede ``j``. A layer is a sorted
array of distinct masks of one size.

Example
-------
>>> import numpy as np
>>> need = predecessor_masks(3, [(0, 1)])  # 0 before 1; 2 free
>>> [[int(m) for m in layer] for layer in ideal_layers(need, 3, cap=100)]
[[0], [1, 4], [3, 5], [7]]
>>> count_ideals(need, 3)
(6, False)

References
----------
Thesis §5.3 (the DP over the served sets); Davey and Priestley, *Introduction to Lattices
and Order* (down-sets).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

#: Ideals are uint64 bitmasks: at most this many nodes.
MAX_BITS = 64

_ONE = np.uint64(1)


def bits(n: int) -> np.ndarray:
    """``bits[j] = 1 << j`` as uint64, for j < n."""
    return np.left_shift(_ONE, np.arange(n, dtype=np.uint64))


def predecessor_masks(n: int, pairs: Iterable[tuple[int, int]]) -> np.ndarray:
    """``need[j]``: the mask of every ``r`` with a pair ``(r, j)`` (r must precede j).

    Pass the transitive closure's pairs for a closed relation; ideals are the same either
    way (closure under the given pairs implies closure under their transitive closure).
    """
    need = np.zeros(n, dtype=np.uint64)
    for r, j in pairs:
        need[j] |= _ONE << np.uint64(r)
    return need


def distinct(masks: np.ndarray) -> np.ndarray:
    """Sorted distinct values (``np.unique`` of numpy 2.4 hashes unsigned arrays, 10-20x
    slower than sorting them here)."""
    masks = np.sort(masks)
    if masks.size:
        masks = masks[np.concatenate(([True], masks[1:] != masks[:-1]))]
    return masks


def ideal_layers(
    need: np.ndarray,
    n: int,
    cap: int,
    deadline: Any = None,
    first: int = 0,
) -> list[np.ndarray] | None:
    """The order ideals containing ``first``, by size: one sorted uint64 array per size.

    Parameters
    ----------
    need : (n,) uint64 array
        ``need[j]``: the nodes that must precede j (:func:`predecessor_masks`).
    n : int
        Nodes (at most :data:`MAX_BITS`).
    cap : int
        Give up (None) once more than ``cap`` ideals are found.
    deadline : taopt.runtime.Deadline, optional
        Give up (None) when it expires, or when the next layer's candidates alone prove more
        than ``cap`` ideals (checked before they are merged, which is the slow step).
    first : int
        The mask every ideal contains (the first layer), 0 for the empty set; it must be an
        ideal itself.

    Returns
    -------
    list of arrays, or None
        Layer k holds the ideals of ``popcount(first) + k`` nodes; None past ``cap`` or the
        deadline.

    Notes
    -----
    Breadth-first over sizes: layer k+1 is every ideal of layer k plus one node all of
    whose predecessors it holds. O(n · ideals) numpy work; duplicates are merged early so
    memory stays O(ideals of two layers) even near the cap.
    """
    layers = [np.array([first], dtype=np.uint64)]
    total = 1
    limited = deadline is not None and deadline.limited
    for k in range(n - int(first).bit_count()):
        cur = layers[-1]
        parts = []
        size = 0
        for j in range(n):
            bit = _ONE << np.uint64(j)
            part = cur[((cur & bit) == 0) & ((cur & need[j]) == need[j])] | bit
            parts.append(part)
            size += part.size
            if limited and deadline.expired():
                return None
            if size > 2 * (cap - total) + 1024:  # merge duplicates early, stop past the cap
                parts = [distinct(np.concatenate(parts))]
                size = parts[0].size
                if size > cap - total:
                    return None
        if limited and total + -(-size // (k + 1)) > cap:
            # an ideal of the next layer is grown from at most k + 1 of this one's, so there
            # are at least size / (k + 1): past the cap without the merge (a single one took
            # 0.12 s on ESC47, over 1 s under load, between two looks at the clock)
            return None
        layers.append(distinct(np.concatenate(parts)))
        total += layers[-1].size
        if total > cap or (limited and deadline.expired()):
            return None
    return layers


def count_ideals(
    need: np.ndarray, n: int, cap: int = 10_000_000, first: int = 0, deadline: Any = None
) -> tuple[int, bool]:
    """The number of order ideals containing ``first`` (the empty and full sets included).

    ``deadline`` (a :class:`taopt.runtime.Deadline`, optional) stops the count when it
    expires (see :func:`ideal_layers`).

    Returns
    -------
    count : int
        The exact number, or ``cap + 1`` when ``capped``.
    capped : bool
        True when there are more than ``cap`` ideals, or more than :data:`MAX_BITS` nodes, or
        the deadline came first (the true number is then larger or unknown).

    Example
    -------
    >>> count_ideals(predecessor_masks(4, [(0, 1), (1, 2), (2, 3)]), 4)  # a chain: n + 1
    (5, False)
    """
    if n > MAX_BITS:
        return cap + 1, True
    layers = ideal_layers(need, n, cap, deadline=deadline, first=first)
    if layers is None:
        return cap + 1, True
    return sum(int(layer.size) for layer in layers), False


__all__ = ["MAX_BITS", "bits", "predecessor_masks", "distinct", "ideal_layers", "count_ideals"]
