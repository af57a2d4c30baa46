"""The one TSPLIB reader, and the cost of a path on a matrix.

TSPLIB95 files (Reinelt 1991) are a header of ``KEY: value`` lines followed by
sections; taopt reads the explicit-matrix kinds, asymmetric TSP (``.atsp``,
:func:`taopt.routing.tsplib.load_atsp`) and sequential ordering (``.sop``,
:func:`taopt.sop.problem.load_sop`). Both are read here, by :func:`read_tsplib`,
into the header and the numbers of the ``EDGE_WEIGHT_SECTION``; each loader then
checks what its kind requires (``TYPE``, the matrix format, the dimension).

:func:`path_cost` is the length of an open path on a cost matrix: the SOP
objective, and the truck's path on t* in chapter 5.

Example
-------
>>> from taopt.tsplib import path_cost, read_tsplib, tsplib_file
>>> header, weights = read_tsplib(tsplib_file("br17.atsp"))
>>> header["TYPE"], header["DIMENSION"], len(weights)
('ATSP', '17', 289)
>>> path_cost([[0, 2, 9], [1, 0, 4], [7, 3, 0]], [0, 1, 2])
6.0
"""

from __future__ import annotations

from collections.abc import Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from taopt.errors import InstanceError

__all__ = ["read_tsplib", "path_cost", "shipped_tsplib", "tsplib_file"]

_DATA = "taopt.data"


def shipped_tsplib(suffix: str) -> list[str]:
    """Names (without ``suffix``, e.g. ``".sop"``) of the files shipped in ``taopt/data/tsplib``."""
    folder = resources.files(_DATA) / "tsplib"
    return sorted(p.name[: -len(suffix)] for p in folder.iterdir() if p.name.endswith(suffix))


def tsplib_file(name: str) -> Path:
    """Path of the file ``name`` (with its suffix) in ``taopt/data/tsplib``; it may not exist."""
    return Path(str(resources.files(_DATA) / "tsplib" / name))


def read_tsplib(path: str | Path) -> tuple[dict[str, str], list[str] | None]:
    """Read a TSPLIB file's header and the tokens of its ``EDGE_WEIGHT_SECTION``.

    Parameters
    ----------
    path : str or Path
        The file (UTF-8 text).

    Returns
    -------
    header : dict of str to str
        Every ``KEY: value`` line before ``EDGE_WEIGHT_SECTION``, the key upper-cased and both
        sides stripped of blanks.
    weights : list of str, or None
        The whitespace-separated tokens after the ``EDGE_WEIGHT_SECTION`` line, up to ``EOF``
        or the next ``..._SECTION`` line (e.g. ``DISPLAY_DATA_SECTION``); None if the file has
        no ``EDGE_WEIGHT_SECTION``. Kinds are checked by the caller: an ``.sop`` section starts
        with the dimension, an ``.atsp`` section does not.

    Raises
    ------
    InstanceError
        The file cannot be read as UTF-8 text; the message starts with the path.

    Notes
    -----
    One pass over the lines, O(size of the file). Keywords (``EDGE_WEIGHT_SECTION``, ``EOF``)
    are matched without regard to case.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InstanceError(f"{path}: cannot be read as TSPLIB text ({exc})") from None
    header: dict[str, str] = {}
    weights: list[str] | None = None
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped:
            continue
        keyword = stripped.upper()
        if weights is not None:
            if keyword == "EOF" or keyword.endswith("_SECTION"):
                break
            weights.extend(stripped.split())
        elif keyword.startswith("EDGE_WEIGHT_SECTION"):
            weights = []
        elif ":" in stripped:
            key, value = stripped.split(":", 1)
            header[key.strip().upper()] = value.strip()
    return header, weights


def path_cost(cost: Any, order: Sequence[int]) -> float:
    """Sum of ``cost[order[i], order[i+1]]`` along the path (no return arc).

    Parameters
    ----------
    cost : (N, N) array_like
        Arc costs.
    order : sequence of int
        The nodes in path order; fewer than two nodes cost 0.

    Returns
    -------
    float

    Notes
    -----
    O(len(order)), one vectorised gather.
    """
    matrix = np.asarray(cost, dtype=float)
    nodes = np.asarray(order, dtype=np.int64)
    if len(nodes) < 2:
        return 0.0
    return float(matrix[nodes[:-1], nodes[1:]].sum())
