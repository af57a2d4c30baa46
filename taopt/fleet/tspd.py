"""The shipped TSP-D instances (``taopt/data/tspd``, CC BY-SA 4.0) and their published optima.

See ``taopt/data/tspd/README.md`` for the source and citation; the reader itself is
:meth:`taopt.fleet.problem.FleetProblem.from_tspd`.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from taopt.errors import InstanceError

#: The folder of the shipped instances.
TSPD_FOLDER = Path(__file__).resolve().parents[1] / "data" / "tspd"


def tspd_instances() -> list[Path]:
    """The shipped instance files, by size then id (``uniform-<id>-n<N>.txt``)."""

    def key(path: Path) -> tuple[int, int]:
        m = re.fullmatch(r"uniform-(\d+)-n(\d+)", path.stem)
        return (int(m.group(2)), int(m.group(1))) if m else (0, 0)

    return sorted(TSPD_FOLDER.glob("uniform-*.txt"), key=key)


def published_optimum(path: str | os.PathLike[str]) -> float:
    """The optimum Bouman, Agatz & Schmidt (2018) published for an instance: the last
    ``/* Total cost : X */`` of ``solutions/<stem>-DP.txt`` beside it.

    Raises
    ------
    InstanceError
        No solution file, or none with a total cost (naming the file).
    """
    path = Path(path)
    solution = path.parent / "solutions" / f"{path.stem}-DP.txt"
    try:
        text = solution.read_text(encoding="utf-8")
    except OSError:
        raise InstanceError(f"{solution}: no published solution for {path.name}") from None
    found = re.findall(r"Total cost\s*:\s*([0-9.eE+-]+)", text)
    if not found:
        raise InstanceError(f"{solution}: no '/* Total cost : X */' line")
    return float(found[-1])


__all__ = ["TSPD_FOLDER", "published_optimum", "tspd_instances"]
