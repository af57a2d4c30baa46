"""TSPLIB sequential ordering problem (SOP) files: loader and the shipped instances.

The sequential ordering problem is the precedence-constrained Hamiltonian path
that chapter 5's ordering step solves on the drone cost matrix t* (5.11): find
the cheapest path ``start -> ... -> end`` through every node of an asymmetric
cost matrix such that every precedence pair ``(r, j)`` has r before j
(precedences as in (5.7)). TSPLIB's SOP instances, with their proven optima,
certify the exact solver :func:`taopt.models.solve_sop`.

TSPLIB .sop convention (TSPLIB95 documentation §3.4, checked on the files):

* ``EDGE_WEIGHT_FORMAT: FULL_MATRIX``; the ``EDGE_WEIGHT_SECTION`` starts with
  an extra token repeating the dimension, then n·n integers (read as a token
  stream, never line by line).
* ``C[j][r] == -1`` means r must come BEFORE j (the row is the later node).
* Node 0 is first (column 0 is -1 in every other row), node n-1 is last (row
  n-1 is -1 everywhere else); ``C[0][n-1] = 1000000`` forbids start -> end.
  These structural -1 are not returned as precedences.
* The objective is the length of the Hamiltonian PATH 0 -> ... -> n-1 (no
  return arc); the diagonal is ignored.

Shipped files (unmodified copies of TSPLIB95 via ``pdrozdowski/TSPLib.Net@5cb1449``;
provenance and optimum sources in the project's ``shared/benchmarks/tsplib/README.md``):
see :data:`KNOWN_OPTIMA`.

Example
-------
>>> cost, precedences, start, end, name = load_sop("ESC07")
>>> cost.shape, start, end, len(precedences)
((9, 9), 0, 8, 7)
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

from taopt.errors import InstanceError

__all__ = ["KNOWN_OPTIMA", "load_sop", "shipped_sop", "sop_path", "path_cost"]

#: Proven optima of the shipped .sop files (TSPLIB95 DOC.PS Table 3; confirmed by
#: xgillard/ddo and IsaacRudich/ImprovedPnB, and by a Held–Karp DP for all but ESC25).
KNOWN_OPTIMA: dict[str, int] = {
    "ESC07": 2125,
    "ESC11": 2075,
    "ESC12": 1675,
    "ESC25": 1681,
    "br17.10": 55,
    "br17.12": 55,
}

_DATA = "taopt.data"


def shipped_sop() -> list[str]:
    """Names (without ``.sop``) of the SOP files shipped in ``taopt/data/tsplib``."""
    folder = resources.files(_DATA) / "tsplib"
    return sorted(p.name[: -len(".sop")] for p in folder.iterdir() if p.name.endswith(".sop"))


def sop_path(name: str) -> Path:
    """Path of a shipped SOP file, e.g. ``sop_path("ESC07")``."""
    stem = name[: -len(".sop")] if name.endswith(".sop") else name
    path = Path(str(resources.files(_DATA) / "tsplib" / f"{stem}.sop"))
    if not path.is_file():
        raise InstanceError(f"no shipped SOP file {stem!r}; shipped: {shipped_sop()}")
    return path


def load_sop(path_or_name: str | Path) -> tuple[np.ndarray, list[tuple[int, int]], int, int, str]:
    """Read a TSPLIB .sop file.

    Parameters
    ----------
    path_or_name : str or Path
        A file path, or the name of a shipped instance ("ESC07", "br17.10").

    Returns
    -------
    cost : (n, n) float array
        ``cost[i, j]`` = cost of arc i -> j. Entries that are -1 in the file
        (arcs into an earlier node, never usable) become ``inf``, as does
        ``cost[start, end]``; the diagonal is 0.
    precedences : list of (r, j)
        r must be visited before j, from ``C[j][r] == -1``, excluding the
        structural ones involving the start and end nodes. The file's
        relation is transitively closed, so this list is too.
    start, end : int
        0 and n-1.
    name : str
        The ``NAME`` field (without a trailing ``.sop``).

    Raises
    ------
    InstanceError
        The file is not FULL_MATRIX SOP, has the wrong number of weights, or
        its -1 entries are not consistent with node 0 first and n-1 last.
    """
    path = Path(path_or_name)
    if not path.is_file():
        path = sop_path(str(path_or_name))
    header: dict[str, str] = {}
    tokens: list[str] = []
    in_section = False
    for line in path.read_text().splitlines():
        text = line.strip()
        if not text:
            continue
        if in_section:
            if text.upper() == "EOF":
                break
            tokens.extend(text.split())
        elif text.upper().startswith("EDGE_WEIGHT_SECTION"):
            in_section = True
        elif ":" in text:
            key, value = text.split(":", 1)
            header[key.strip().upper()] = value.strip()
    if header.get("TYPE", "").upper() != "SOP":
        raise InstanceError(f"{path.name}: TYPE is {header.get('TYPE')!r}, expected SOP")
    if header.get("EDGE_WEIGHT_FORMAT", "").upper() != "FULL_MATRIX":
        raise InstanceError(f"{path.name}: only EDGE_WEIGHT_FORMAT FULL_MATRIX is supported")
    n = int(header["DIMENSION"])
    if len(tokens) != n * n + 1:
        raise InstanceError(
            f"{path.name}: EDGE_WEIGHT_SECTION holds {len(tokens)} numbers, expected "
            f"{n * n + 1} (the leading dimension token plus {n}x{n})"
        )
    if int(float(tokens[0])) != n:
        raise InstanceError(f"{path.name}: leading token {tokens[0]} is not the dimension {n}")
    raw = np.array([float(t) for t in tokens[1:]]).reshape(n, n)
    start, end = 0, n - 1
    minus = raw == -1
    np.fill_diagonal(minus, False)
    if not (minus[1:, start].all() and minus[end, :end].all() and not minus[start].any()):
        raise InstanceError(f"{path.name}: node 0 is not first or node {end} is not last")
    precedences = [
        (int(r), int(j)) for j, r in zip(*np.nonzero(minus), strict=True) if r != start and j != end
    ]
    if (raw[~minus] < 0).any():
        raise InstanceError(f"{path.name}: negative weight other than -1")
    cost = np.where(minus, np.inf, raw)
    np.fill_diagonal(cost, 0.0)
    cost[start, end] = np.inf
    name = header.get("NAME", path.stem)
    name = name[: -len(".sop")] if name.endswith(".sop") else name
    return cost, precedences, start, end, name


def path_cost(cost: np.ndarray, order) -> float:
    """Length of the path ``order[0] -> order[1] -> ...`` on ``cost`` (no return arc)."""
    order = np.asarray(order, dtype=int)
    return float(np.asarray(cost)[order[:-1], order[1:]].sum())
