"""Shared fixtures: named reference instances with known answers, and the bound-validity rule.

The instances come from :mod:`reference` (tests/reference.py), where each optimum is computed
by hand, by an independent brute force, or taken from TSPLIB95, never from a solver under
test. Each fixture is session-scoped: the problems are immutable, build them once.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

import reference  # noqa: E402  (tests/ is on sys.path: pytest's rootdir conftest insertion)

#: The repository's root (tests/conftest.py sits one level below it); the tests in the
#: sub-folders of tests/ compute their paths from it, never from their own ``__file__``.
ROOT = Path(__file__).resolve().parents[1]
#: The instance files shipped with the package (examples of every kind, TSPLIB, the demo).
DATA = ROOT / "taopt" / "data"


def valid_lower_bounds(family: Any) -> dict[str, Callable[..., float]]:
    """``name -> bound`` for every bound the family's spec marks a valid lower bound (never
    above the optimum); ``"lower"`` takes ``(problem, strength)``, the others ``(problem)``."""
    return {name: b.func for name, b in family.bounds.items() if b.valid and b.side == "lower"}


def upper_bounds(family: Any) -> dict[str, Callable[[Any], float]]:
    """``name -> bound(problem)`` for the bounds the family's spec declares as upper bounds
    (valid, or as printed: Lemma 3.6's f^da needs the triangle inequality, which the
    reference problems have)."""
    return {name: b.func for name, b in family.bounds.items() if b.side == "upper"}


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """Folder of the instance files the package ships (``taopt/data``: ``examples/<kind>.json``
    of every file kind, ``tsplib/``, ``demo.json``)."""
    return DATA


# -- named reference instances -----------------------------------------------------------------
@pytest.fixture(scope="session")
def ref_routing_small() -> reference.Reference:
    """Chapter 2 on a line: targets at 1, 2, 4, vehicles at 0 and 5 (symmetric |x_i - x_j|);
    optimum 3 by the routes [[0, 1], [2]] (by hand)."""
    return reference.routing_line()


@pytest.fixture(scope="session")
def ref_routing_quick_tour() -> reference.Reference:
    """The package docstring's matrix [[0, 2, 9], [1, 0, 9], [4, 3, 0]], 2 targets and 1
    vehicle; optimum 4 by the route [1, 0] (by hand)."""
    return reference.routing_quick_tour()


@pytest.fixture(scope="session")
def ref_routing_one_way() -> reference.Reference:
    """One vehicle, two targets, 0 -> 1 costs 1 but 1 -> 0 costs 100: direction matters;
    optimum 2 by [0, 1] (by hand)."""
    return reference.routing_one_way()


@pytest.fixture(scope="session")
def ref_routing_idle_vehicle() -> reference.Reference:
    """Targets at 1, 2, 3, vehicles at 0 and 100 on a line: the far vehicle stays idle;
    optimum 3 by [[0, 1, 2], []] (by hand)."""
    return reference.routing_idle_vehicle()


@pytest.fixture(scope="session")
def ref_routing_asymmetric() -> reference.Reference:
    """A random asymmetric 5-target, 2-vehicle matrix (seed 11); optimum by brute force over
    every assignment and visiting order."""
    return reference.routing_asymmetric()


@pytest.fixture(scope="session")
def ref_capability() -> reference.Reference:
    """Chapter 3: 4 targets (one demanding two capabilities), 3 vehicles of capabilities a, a,
    b; optimum by brute force per capability class (the §3.6 split)."""
    return reference.capability_small()


@pytest.fixture(scope="session")
def ref_comm() -> reference.Reference:
    """Chapter 4: 5 targets of two attributes, 3 vehicles, r = 30 m; the "optimum" is f_o, the
    full-information optimum by brute force per class (every simulation drives at least it)."""
    return reference.comm_small()


@pytest.fixture(scope="session")
def ref_delivery() -> reference.Reference:
    """Chapter 5: 5 customers on a 3 x 3 street grid, precedences 0 -> 1 and 2 -> 3; optimum
    by scheduling every topological order with the exact DP."""
    return reference.delivery_small()


@pytest.fixture(scope="session")
def ref_sop() -> reference.Reference:
    """TSPLIB's ESC07 sequential ordering problem (9 nodes); optimum 2125
    (TSPLIB95)."""
    return reference.sop_esc07()


@pytest.fixture(scope="session")
def ref_sop_esc12() -> reference.Reference:
    """TSPLIB's ESC12 sequential ordering problem (14 nodes); optimum 1675 (TSPLIB95)."""
    return reference.sop_esc12()


# -- named instances several test files build the same way --------------------------------------
# Session-scoped: the problems are immutable; a test that needs a variant calls ``replace``.


@pytest.fixture(scope="session")
def assignment_example_file() -> Path:
    """The shipped chapter-2 example file (``taopt/data/examples/assignment_problem.json``;
    certified optimum 10.5), the file ``example:assignment_problem`` names."""
    return DATA / "examples" / "assignment_problem.json"


@pytest.fixture(scope="session")
def solution_example_file() -> Path:
    """The shipped certificate of the assignment example (``solution.json``: the exact
    method's routes, optimal 10.5), the file the ``taopt verify`` tests tamper with."""
    return DATA / "examples" / "solution.json"


@pytest.fixture(scope="session")
def assignment_example(assignment_example_file: Path) -> Any:
    """The problem of the shipped chapter-2 example file, loaded."""
    from taopt.routing.problem import AssignmentProblem

    return AssignmentProblem.load(assignment_example_file)


@pytest.fixture(scope="session")
def budgeted_example_file() -> Path:
    """The shipped §6.2 example file (``budgeted_problem.json``: n = 8, m = 3, capacities and
    travel-time limits that bind: its optimum is above the unlimited one)."""
    return DATA / "examples" / "budgeted_problem.json"


@pytest.fixture(scope="session")
def delivery_example() -> Any:
    """Chapter 5's stored 20-customer residential example at flight range L = 250 m
    (``taopt.delivery.example_instance(250.0)``, Fig. 5.6's setup; certified optimum
    1793.7145 by the ideal DP)."""
    from taopt.delivery import example_instance

    return example_instance(250.0)


@pytest.fixture(scope="session")
def capability_9x2() -> Any:
    """A small §3.7 scenario (``thesis_scenario(9, 2, 2, seed=4)``: 9 targets, 2 vehicles, 2
    capabilities, obstacles): the capability model's worker and option tests."""
    from taopt.capability.instances import thesis_scenario

    return thesis_scenario(9, 2, 2, seed=4).problem


@pytest.fixture(scope="session")
def sop_esc25() -> Any:
    """TSPLIB's ESC25 (27 nodes; optimum 1681, TSPLIB95): large enough that a small state cap
    or a 0.2 s limit stops the DP before it proves the optimum."""
    from taopt.sop.problem import SopProblem

    return SopProblem.load("ESC25")


@pytest.fixture(scope="session")
def sop_esc47() -> Any:
    """TSPLIB's ESC47 (49 nodes; optimum 1288, TSPLIB95): seconds to prove, so a limit of
    a second or less always binds."""
    from taopt.sop.problem import SopProblem

    return SopProblem.load("ESC47")


#: The settings of :func:`delivery_tiny_study` (chapter 5's study, setup "small").
DELIVERY_TINY: dict[str, Any] = dict(instances=2, ratios=(0.3, 0.9), seed=3, progress=False)


@pytest.fixture(scope="session")
def delivery_tiny_study(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """Chapter 5's study on its "small" setup (:data:`DELIVERY_TINY`: 2 instances x 2 ratios)
    with NIA and the subset DP, run once: ``(folder, rows)``. A test that writes to the folder
    copies it first (``shutil.copytree``); the rows carry the bounds, the optimum and q."""
    from taopt.orchestration.studies.delivery import delivery_study

    folder = tmp_path_factory.mktemp("delivery-tiny") / "study"
    rows = delivery_study("small", methods=("NIA", "subset-dp"), out_dir=folder, **DELIVERY_TINY)
    return folder, rows
