"""Executable checks of the navigation claims: Lemma 2.3 and the navigation law (2.6).

These check solver output without trusting the solver (STYLE: tests).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.fields import Field
from taopt.navigation.path import Path, as_field
from taopt.navigation.shooting import navigation_law


@dataclass(frozen=True)
class MatrixReport:
    """Asymmetry and triangle-inequality figures of a travel-time matrix (Lemma 2.3).

    Attributes
    ----------
    n : int
        Number of points.
    max_asymmetry, mean_asymmetry : float
        Max and mean over i < j of ``|t_ij - t_ji|`` (seconds).
    max_relative_asymmetry, mean_relative_asymmetry : float
        The same divided by ``max(t_ij, t_ji)``.
    asymmetric_pair : tuple[int, int] or None
        A pair attaining the max relative asymmetry.
    worst_triangle : float
        ``max over distinct (i, j, k) of (t_ik - t_ij - t_jk) / t_ik``; Lemma 2.3
        says this is <= 0 (up to the solver's accuracy).
    worst_triple : tuple[int, int, int] or None
        The triple ``(i, j, k)`` attaining it.
    """

    n: int
    max_asymmetry: float
    mean_asymmetry: float
    max_relative_asymmetry: float
    mean_relative_asymmetry: float
    asymmetric_pair: tuple[int, int] | None
    worst_triangle: float
    worst_triple: tuple[int, int, int] | None

    def triangle_holds(self, rtol: float = 1e-6) -> bool:
        """Lemma 2.3's inequality within relative tolerance ``rtol``."""
        return self.worst_triangle <= rtol

    def summary(self) -> str:
        tri = (
            "n/a"
            if self.worst_triple is None
            else f"{self.worst_triangle:.3e} at (i, j, k) = {self.worst_triple}"
        )
        return (
            f"{self.n} points: asymmetry |t_ij - t_ji| max {self.max_asymmetry:.4g} s, mean "
            f"{self.mean_asymmetry:.4g} s (relative max {self.max_relative_asymmetry:.3%}, mean "
            f"{self.mean_relative_asymmetry:.3%}); worst triangle violation "
            f"(t_ik - t_ij - t_jk) / t_ik = {tri} (<= 0: Lemma 2.3 holds)"
        )

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def matrix_report(matrix: Any) -> MatrixReport:
    """Asymmetry and the worst relative violation of Lemma 2.3's triangle inequality.

    Parameters
    ----------
    matrix : (N, N) array_like
        Travel times with zero diagonal.

    Returns
    -------
    MatrixReport

    Raises
    ------
    InstanceError
        Not square, negative or non-finite off-diagonal entries, or a non-zero diagonal.

    Example
    -------
    >>> matrix_report([[0, 1, 3], [1, 0, 1], [1, 1, 0]]).worst_triple
    (0, 1, 2)

    Notes
    -----
    O(N^3) time in N vectorised (N, N) steps, O(N^2) memory: N = 140 takes a
    few milliseconds. Coincident points (``t_ik = 0``) are left out of the ratio.
    """
    T = np.asarray(matrix, dtype=float)
    if T.ndim != 2 or T.shape[0] != T.shape[1]:
        raise InstanceError(f"travel-time matrix must be square, got shape {T.shape}")
    n = T.shape[0]
    off = ~np.eye(n, dtype=bool)
    if not np.isfinite(T[off]).all() or (T[off] < 0).any():
        bad = np.argwhere(off & (~np.isfinite(T) | (T < 0)))[0]
        raise InstanceError(
            f"travel time t[{bad[0]}, {bad[1]}] = {T[bad[0], bad[1]]} is negative or not finite"
        )
    if np.any(np.diag(T) != 0):
        k = int(np.flatnonzero(np.diag(T) != 0)[0])
        raise InstanceError(f"travel-time matrix diagonal must be zero, t[{k}, {k}] = {T[k, k]}")

    upper = np.triu(off)
    diff = np.abs(T - T.T)[upper]
    larger = np.maximum(T, T.T)[upper]
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(larger > 0, diff / larger, 0.0)
    if diff.size:
        arg = int(np.argmax(rel))
        iu = np.argwhere(upper)[arg]
        pair: tuple[int, int] | None = (int(iu[0]), int(iu[1]))
    else:
        pair = None

    worst, triple = -np.inf, None
    positive = T > 0
    for j in range(n):
        # violation[i, k] = t_ik - t_ij - t_jk, relative to t_ik, for i, k != j and i != k
        slack = T - T[:, j : j + 1] - T[j : j + 1, :]
        mask = positive.copy()
        mask[j, :] = False
        mask[:, j] = False
        if not mask.any():
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(mask, slack / np.where(mask, T, 1.0), -np.inf)
        flat = int(np.argmax(ratio))
        if ratio.flat[flat] > worst:
            worst = float(ratio.flat[flat])
            i, k = divmod(flat, n)
            triple = (i, j, k)
    return MatrixReport(
        n=n,
        max_asymmetry=float(diff.max()) if diff.size else 0.0,
        mean_asymmetry=float(diff.mean()) if diff.size else 0.0,
        max_relative_asymmetry=float(rel.max()) if diff.size else 0.0,
        mean_relative_asymmetry=float(rel.mean()) if diff.size else 0.0,
        asymmetric_pair=pair,
        worst_triangle=float(worst) if triple is not None else float("nan"),
        worst_triple=triple,
    )


def heading_residual(field: Field | None, path: Path) -> dict[str, float]:
    """How well a path's heading follows the navigation law (2.6).

    Compares the path's own heading rate (the derivative of the collocation
    control polynomial, or (2.6) itself for shooting) with the right-hand side
    of (2.6) evaluated at the path's positions and headings.

    Returns
    -------
    dict
        ``max`` (rad/s), ``rms`` (rad/s) and ``relative`` (``max`` divided by the
        largest ``|psi_dot|`` of (2.6) along the path, or by 1 if that is 0).
    """
    field = as_field(field)
    if path.heading_rate is None:
        raise InstanceError(f"path from method {path.method!r} carries no heading rate")
    law = navigation_law(field, path.xy, path.heading)
    err = np.abs(path.heading_rate - law)
    scale = float(np.max(np.abs(law))) or 1.0
    return {
        "max": float(err.max()),
        "rms": float(np.sqrt(np.mean(err**2))),
        "relative": float(err.max()) / scale,
    }
