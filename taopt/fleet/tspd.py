"""The shipped TSP-D instances (``taopt/data/tspd``, CC BY-SA 4.0) and their published optima.

See ``taopt/data/tspd/README.md`` for the source and citation; the reader itself is
:meth:`taopt.fleet.problem.FleetProblem.from_tspd`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from taopt.errors import InstanceError

#: The folder of the shipped instances.
TSPD_FOLDER = Path(__file__).resolve().parents[1] / "data" / "tspd"

#: Our generated instances (no published optimum), written by :func:`write_tspd`.
GENERATED_FOLDER = TSPD_FOLDER / "generated"


def generate_tspd(
    nodes: int,
    seed: int,
    maxfly: float | None = None,
    novisit: Iterable[int] = (),
) -> str:
    """The text of a TSP-D instance in the Agatz–Bouman–Schmidt ``uniform`` format and
    distribution: truck cost 1.0 and drone cost 0.5 per unit of distance, the depot uniform in
    [0, 1)², the other ``nodes - 1`` locations with integer coordinates uniform in 0..99 (as
    in the 80 published files), optional ``#MAXFLY r`` and ``#NOVISIT i j ...`` lines.

    Seeded: the same (nodes, seed) gives the same text.

    Raises
    ------
    InstanceError
        Fewer than 2 nodes, or a ``novisit`` node outside 1..nodes-1 (naming it).
    """
    if nodes < 2:
        raise InstanceError(f"a TSP-D instance needs at least 2 nodes, got {nodes}")
    novisit = sorted(set(int(i) for i in novisit))
    for node in novisit:
        if not 1 <= node < nodes:
            raise InstanceError(f"#NOVISIT node {node} is not a location 1..{nodes - 1}")
    rng = np.random.default_rng(seed)
    depot = rng.random(2)
    points = rng.integers(0, 100, size=(nodes - 1, 2))
    lines = [
        "/*The speed of the Truck*/",
        "1.0",
        "/*The speed of the Drone*/",
        "0.5",
        "/*Number of Nodes*/",
        str(nodes),
        "/*The Depot*/",
        f"{float(depot[0])!r} {float(depot[1])!r} depot",
        "/*The Locations (x_coor y_coor name)*/",
    ]
    lines += [f"{float(x)} {float(y)} loc{i + 1}" for i, (x, y) in enumerate(points)]
    if maxfly is not None:
        lines.append(f"#MAXFLY {float(maxfly)!r}")
    if novisit:
        lines.append("#NOVISIT " + " ".join(map(str, novisit)))
    return "\n".join(lines) + "\n"


def write_tspd(
    path: str | os.PathLike[str],
    nodes: int,
    seed: int,
    maxfly: float | None = None,
    novisit: Iterable[int] = (),
) -> Path:
    """Write :func:`generate_tspd` ``(nodes, seed, maxfly, novisit)`` to ``path``; returns it.

    ``python -m taopt.fleet.tspd FOLDER`` writes the shipped ``generated/`` set:
    ``gen-<seed>-n<nodes>.txt`` for nodes 14..17 and seeds 1..3, seed = 1000 * id + nodes.
    """
    path = Path(path)
    path.write_text(generate_tspd(nodes, seed, maxfly, novisit), encoding="utf-8")
    return path


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


def generated_instances() -> list[Path]:
    """Our shipped generated instances (``generated/gen-<id>-n<N>.txt``), by size then id."""

    def key(path: Path) -> tuple[int, int]:
        m = re.fullmatch(r"gen-(\d+)-n(\d+)", path.stem)
        return (int(m.group(2)), int(m.group(1))) if m else (0, 0)

    return sorted(GENERATED_FOLDER.glob("gen-*.txt"), key=key)


def _main(folder: str) -> None:
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    for nodes in range(14, 18):
        for ident in range(1, 4):
            write_tspd(out / f"gen-{ident}-n{nodes}.txt", nodes, 1000 * ident + nodes)


if __name__ == "__main__":
    import sys

    _main(sys.argv[1] if len(sys.argv) > 1 else str(GENERATED_FOLDER))


__all__ = [
    "GENERATED_FOLDER",
    "TSPD_FOLDER",
    "generate_tspd",
    "generated_instances",
    "published_optimum",
    "tspd_instances",
    "write_tspd",
]
