"""The built chapter 3 model shared by the printed and joint formulations (thesis §3.2.1):
the cvxpy problem and the meaning of each σ, and the input check of every formulation."""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np

from taopt.capability.problem import CapabilityProblem
from taopt.errors import require


@dataclass
class CapabilityModel:
    """A built chapter 3 model: the cvxpy problem and the meaning of each σ.

    Attributes
    ----------
    problem : cvxpy.Problem
    arc_use : cvxpy.Variable
        One binary per arc.
    tails, heads : (A,) int arrays
        Arc ``a`` runs from point ``tails[a]`` to target ``heads[a]``.
    labels : (A,) int array
        "printed": the vehicle k of ``σ_ijk``; "joint": the class index q (position in
        ``problem.capabilities``).
    formulation : str
    order : cvxpy.Variable or None
        MTZ positions (joint, ``sec="mtz"``).
    cuts : list of (q, subset)
        DFJ cuts present (joint, ``sec="dfj"``).
    """

    problem: cp.Problem
    arc_use: cp.Variable
    tails: np.ndarray
    heads: np.ndarray
    labels: np.ndarray
    formulation: str
    order: cp.Variable | None = None
    cuts: list[tuple[int, tuple[int, ...]]] = field(default_factory=list)


def _class_index(problem: CapabilityProblem) -> dict[Hashable, int]:
    return {cap: q for q, cap in enumerate(problem.capabilities)}


def _check(problem: Any) -> None:
    require(
        problem,
        CapabilityProblem,
        "solve_capability",
        "chapter 2 problems are solved by taopt.models.solve_routing",
    )
