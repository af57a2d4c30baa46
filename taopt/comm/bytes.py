"""The ONE byte model of chapter 4: what every message carries, and what a number costs.

Every message of CAA, DAA and HDA is counted here and nowhere else. The engine calls
:func:`message_numbers` for each ``group.send(kind, rounds)`` of a policy; a synchronous
round sends one message from every vehicle of the group to each of its direct neighbours,
so a round of a group with ``E`` links costs ``2E`` messages.

Message contents (the thesis's algorithm lines, sizes *as printed*)
-------------------------------------------------------------------
The thesis sizes its matrices with n rows (``X_j ∈ R^{n×(n+4)}`` for DAA,
``R^{n×(3n+3)}`` for CAA) although a row describes a vehicle, and its vectors
(``u_j``, ``R^c_j``, ``s_j``, ``c_j``, ``β_j``) as n-tuples. We count the messages exactly as
printed, fixed-size (a vehicle does not know m; the zero rows are sent too): that is what
reproduces the ratio of Table 4.2's CAA and DAA rows where both only exchange the first
message (|A| = m: 11.93 / 4.3152 = 2.765 = (3n + 4) / (n + 4) at n = 30).

==================  ==========================================  ======================
kind                content (algorithm line)                     numbers per message
==================  ==========================================  ======================
``consensus``       X_j(:, 1:n+2), R^c_j, s_j (Alg. 4 l. 3)      n(n + 2) + 2n
``positions``       X_j(:, n+3:n+4) (Alg. 4 l. 18)               2n
``cooperative``     β_j (Alg. 4 l. 34)                           n
``bid``             c_j, β_j (Alg. 5 l. 18)                      2n
``check``           X_j(:, n+4) (Alg. 6 l. 10)                   n
``collect``         X_s, R^c_s (Alg. 3 l. 3)                     n(3n + 3) + n
``distribute``      X_j (Alg. 3 l. 37)                           n(3n + 3)
``keep``            "keep your route" (Alg. 3 l. 33)             1
``significance``    HDA: (significance, vehicle id) and          4 n_a
                    (marginal significance, vehicle id) for
                    each of the n_a targets of the sender's
                    ability a
``release``         HDA: the release proposals known to the      3m
                    sender (gain, target, vehicle per vehicle)
==================  ==========================================  ======================

HDA is not written out in the thesis (§4.1, §4.4.2 describe Zhao, Meng & Chung 2016): its
rows are our reading — fixed-size vectors over the targets the sender can visit (the
thesis: HDA exchanges bids "only on the targets that can be visited by the vehicles"), and
the table of release proposals (one per vehicle, fixed size m).

What a number costs
-------------------
:data:`NUMBER_BYTES` = 8: every id, label, flag, coordinate, distance and time is one IEEE
double (the thesis ran MATLAB, whose numbers are doubles). ``Solution.info`` reports both
``numbers`` and ``bytes`` (= 8 × numbers), so another encoding is one multiplication away:
the thesis's space analysis (Theorem 4.5(iv)) codes a number in ``log10 n`` bytes.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: Bytes per number sent (an IEEE double).
NUMBER_BYTES = 8

_SIZES: dict[str, Callable[[int, int, np.ndarray], int | np.ndarray]] = {
    "consensus": lambda n, m, per_class: n * (n + 2) + 2 * n,
    "positions": lambda n, m, per_class: 2 * n,
    "cooperative": lambda n, m, per_class: n,
    "bid": lambda n, m, per_class: 2 * n,
    "check": lambda n, m, per_class: n,
    "collect": lambda n, m, per_class: n * (3 * n + 3) + n,
    "distribute": lambda n, m, per_class: n * (3 * n + 3),
    "keep": lambda n, m, per_class: 1,
    "significance": lambda n, m, per_class: 4 * per_class,
    "release": lambda n, m, per_class: 3 * m,
}

#: Message kinds and their algorithm lines (for reports).
MESSAGE_KINDS = {
    "consensus": "DAA/HDA Alg. 4 l. 3: X_j(:, 1:n+2), R^c_j, s_j",
    "positions": "DAA/HDA Alg. 4 l. 18: X_j(:, n+3:n+4)",
    "cooperative": "DAA/HDA Alg. 4 l. 34: beta_j",
    "bid": "DAA Alg. 5 l. 18: c_j, beta_j",
    "check": "DAA Alg. 6 l. 10: X_j(:, n+4)",
    "collect": "CAA Alg. 3 l. 3: X_s, R^c_s",
    "distribute": "CAA Alg. 3 l. 37: X_j",
    "keep": "CAA Alg. 3 l. 33: keep the previous route",
    "significance": "HDA: (significance, id), (marginal significance, id) per target of its ability",
    "release": "HDA: release proposals (gain, target, vehicle) of every vehicle",
}


def message_numbers(kind: str, n: int, m: int, targets_of_ability: np.ndarray) -> int | np.ndarray:
    """Numbers in one message of ``kind`` sent by each vehicle of a group.

    Parameters
    ----------
    kind : str
        One of :data:`MESSAGE_KINDS`.
    n : int
        Number of targets of the problem.
    m : int
        Number of vehicles of the problem.
    targets_of_ability : (k,) int array
        For each sender, how many targets have its ability (used by HDA's ``significance``).

    Returns
    -------
    int or (k,) int array
        The same count for every sender, or one per sender.

    Raises
    ------
    KeyError
        An unknown kind (a policy bug, never user input).
    """
    return _SIZES[kind](int(n), int(m), np.asarray(targets_of_ability, dtype=np.int64))


__all__ = ["NUMBER_BYTES", "MESSAGE_KINDS", "message_numbers"]
