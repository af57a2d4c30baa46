"""Travel-time matrices ``t(i, j)`` for all ordered pairs of points (thesis §2.2.1).

The matrix is the only thing the assignment layer sees (docs/architecture.md, invariant 2).
Methods:

* ``"pmp"``: all pairs at once by vectorised Pontryagin shooting on (2.6)/(2.10)
  (:mod:`taopt.navigation.pmp`); the default for analytic (linear) fields, and
  available for any smooth one (a B-spline gridded field). A pair it does
  not accept (no convergence, not accurate, a conjugate point, slower than the
  straight line, or a violated triangle inequality) is re-solved by
  collocation and reported by index in ``info["fallback"]``.
* ``"collocation"``: the parametric collocation solver of
  :mod:`taopt.navigation.collocation` (built once, reused for every pair,
  shared over worker processes); the reference, and the default for the
  other fields (:class:`~taopt.fields.GriddedField`).
* ``"shooting"``: per-pair CVODES shooting (:mod:`taopt.navigation.shooting`).

A uniform drift or still water always uses the closed form (3.4). A
collocation pair that does not converge is retried on a finer grid and then
by shooting; if all fail the error names the pair's indices. Nothing is
returned silently wrong.
"""

from __future__ import annotations

import multiprocessing
import os
import warnings
from collections.abc import Mapping
from concurrent.futures import as_completed
from typing import Any, Literal, overload

import numpy as np

from taopt.errors import ConvergenceError, InstanceError
from taopt.fields import Field
from taopt.navigation.collocation import (
    DEFAULT_DEGREE,
    DEFAULT_INTERVALS,
    collocation_path,
    get_solver,
    solver_from_dict,
)
from taopt.navigation.path import as_field, as_speed, check_drift
from taopt.navigation.pmp import is_analytic, pmp_travel_times, triangle_violations
from taopt.navigation.uniform import uniform_travel_times
from taopt.runtime.workers import WorkerPool

METHODS = ("auto", "pmp", "collocation", "shooting")
BATCH_SIZE = 32  # pairs per IPOPT call (measured: ~2x faster per pair than single solves)
_PARALLEL_MIN_PAIRS = 400  # below this, forking workers costs more than it saves
TRIANGLE_RTOL = 1e-9  # relative slack of the triangle guard on PMP entries (Lemma 2.3)

# worker-process state (set by the pool initialiser)
_WORKER: dict[str, Any] = {}


def as_points(points: Any) -> np.ndarray:
    """(N, 2) finite float array, else :class:`InstanceError` naming the bad row."""
    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError("points must be an (N, 2) array of numbers") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InstanceError(f"points must have shape (N, 2), got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise InstanceError(f"point {int(bad[0])} is not finite: {arr[bad[0]].tolist()}")
    return arr


def _solve_pairs(solver: Any, points: np.ndarray, pairs: np.ndarray, speed: float) -> np.ndarray:
    """Rows (time, success, iterations) for each pair: batched solves, straight-line warm starts."""
    return solver.solve_batch(points[pairs[:, 0]], points[pairs[:, 1]], speed, BATCH_SIZE)


def _worker_init(
    field_dict: dict[str, Any], grid: dict[str, Any], points: np.ndarray, speed: float
) -> None:
    _WORKER["solver"] = solver_from_dict(field_dict, **grid)
    _WORKER["points"] = points
    _WORKER["speed"] = speed


def _worker_solve(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return pairs, _solve_pairs(_WORKER["solver"], _WORKER["points"], pairs, _WORKER["speed"])


def default_jobs() -> int:
    """Worker processes to use: the machine's CPU count (at least 1)."""
    return max(1, os.cpu_count() or 1)


@overload
def travel_time_matrix(
    field: Field | None,
    points: Any,
    speed: float = 1.0,
    *,
    method: str = "auto",
    jobs: int | None = None,
    progress: bool = False,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
    return_info: Literal[False] = False,
    pmp_options: Mapping[str, Any] | None = None,
) -> np.ndarray: ...


@overload
def travel_time_matrix(
    field: Field | None,
    points: Any,
    speed: float = 1.0,
    *,
    method: str = "auto",
    jobs: int | None = None,
    progress: bool = False,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
    return_info: Literal[True],
    pmp_options: Mapping[str, Any] | None = None,
) -> tuple[np.ndarray, dict[str, Any]]: ...


def travel_time_matrix(
    field: Field | None,
    points: Any,
    speed: float = 1.0,
    *,
    method: str = "auto",
    jobs: int | None = None,
    progress: bool = False,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
    return_info: bool = False,
    pmp_options: Mapping[str, Any] | None = None,
) -> np.ndarray | tuple[np.ndarray, dict[str, Any]]:
    """Minimum travel times between all ordered pairs of ``points``.

    Parameters
    ----------
    field : Field or None
        The drift (None: still water).
    points : (N, 2) array_like
        Locations; in the thesis's order targets first, then vehicle starts.
    speed : float
        Vehicle speed ``v`` relative to the field.
    method : {"auto", "pmp", "collocation", "shooting"}
        Solver for non-uniform fields (uniform fields and None always use the
        exact closed form (3.4)). "auto" (default) is "pmp" for analytic fields
        (:func:`taopt.navigation.pmp.is_analytic`: linear drifts) and
        "collocation" otherwise (a B-spline :class:`~taopt.fields.GriddedField`
        is only twice differentiable, where "pmp" works but needs many steps).
    jobs : int, optional
        Parallel workers (default: the CPU count): threads for "pmp", processes
        for "collocation" (each rebuilds the solver from ``field.to_dict()``;
        CasADi objects do not pickle). The result does not depend on ``jobs``.
    progress : bool
        Show a tqdm progress bar.
    intervals, degree : int
        Collocation grid (for "collocation" and for the pairs "pmp" falls back on).
    return_info : bool
        Also return a dict: ``method``; ``iterations`` (median and max per pair:
        IPOPT iterations, or Newton iterations for "pmp"); ``retried`` (pairs
        collocation re-solved on a finer grid or by shooting); and for "pmp"
        ``fallback`` (the ``(i, j)`` re-solved by collocation), ``fallback_reason``
        (why, aligned with ``fallback``), ``restarted`` (pairs accepted only after
        PMP's restarts from other headings) and ``suspect`` (entries that may
        still not be minimal: collocation did no better than a rejected extremal,
        or the triangle inequality still fails; also warned about).
    pmp_options : mapping, optional
        Keyword arguments for :func:`taopt.navigation.pmp.pmp_travel_times`
        (``tol``, ``max_iter``, ``max_steps``, ``restarts``).

    Returns
    -------
    (N, N) ndarray
        ``T[i, j] = t(i, j)``, zero diagonal; asymmetric in general (Lemma 2.3).

    Raises
    ------
    InstanceError
        Bad points, speed or method, or Assumption 2.1 fails on the points' bounding box.
    ConvergenceError
        Some pairs failed on every method; the message lists their indices.

    Example
    -------
    >>> from taopt.fields import UniformField
    >>> travel_time_matrix(UniformField(0.5, 0.0), [[0, 0], [3, 0]])
    array([[0., 2.],
           [6., 0.]])

    Notes
    -----
    "pmp" costs about 15 microseconds of CPU per pair on the thesis's field (a
    140-point matrix in well under a second); "collocation" solves ``N (N - 1)``
    small NLPs (about 2-3 ms each with the default grid), spread over ``jobs``
    processes. Coincident points get time 0.

    References
    ----------
    Thesis §2.2.1 (the matrix ``t(i, j)``), §2.3 (the path planning), Lemma 2.3.
    """
    field = as_field(field)
    pts = as_points(points)
    speed = as_speed(speed)
    if method not in METHODS:
        raise InstanceError(f"unknown method {method!r} (expected one of {', '.join(METHODS)})")
    n = len(pts)
    info: dict[str, Any] = {"method": "closed_form", "retried": [], "iterations": None}
    if n == 0:
        return (np.zeros((0, 0)), info) if return_info else np.zeros((0, 0))
    check_drift(field, pts, speed)
    if field.is_uniform:
        drift = field.velocity(pts[:1])[0]
        matrix = uniform_travel_times(drift, pts[:, None, :], pts[None, :, :], speed)
        np.fill_diagonal(matrix, 0.0)
        return (matrix, info) if return_info else matrix
    if method == "auto":
        method = "pmp" if is_analytic(field) else "collocation"

    ii, jj = np.nonzero(~np.eye(n, dtype=bool))
    coincident = np.all(pts[ii] == pts[jj], axis=1)
    pairs = np.column_stack([ii, jj])[~coincident]
    results = np.empty((len(pairs), 3))
    info["method"] = method
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    grid = {"intervals": intervals, "degree": degree}
    fallback = np.zeros(0, dtype=int)
    if method == "pmp":
        info.update(fallback=[], fallback_reason=[], suspect=[], restarted=[])
        bar = _bar(len(pairs), progress)
        out = pmp_travel_times(
            field,
            pts[pairs[:, 0]],
            pts[pairs[:, 1]],
            speed,
            callback=bar.update,
            jobs=jobs,
            **dict(pmp_options or {}),
        )
        bar.close()
        results[:, 0], results[:, 1], results[:, 2] = out.time, out.accepted, out.iterations
        info["restarted"] = [(int(i), int(j)) for i, j in pairs[out.restarted]]
        fallback = out.failed
        info["fallback_reason"] = [str(out.reason[row]) for row in fallback]
        if fallback.size:
            results[fallback] = _collocation_rows(field, pts, pairs[fallback], speed, jobs, grid)
    elif method == "shooting":
        from taopt.navigation.shooting import shooting_path

        for row, (i, j) in enumerate(_progress(pairs, progress)):
            try:
                path = shooting_path(field, pts[i], pts[j], speed)
            except ConvergenceError:
                results[row] = (np.nan, 0.0, 0.0)  # retried below by collocation
                continue
            results[row] = (path.time, 1.0, path.iterations)
    else:
        results = _collocation_rows(field, pts, pairs, speed, jobs, grid, progress)

    _retry_failed(field, pts, pairs, speed, results, grid, info)
    if method == "pmp" and fallback.size:
        _check_fallback(pairs, fallback, results, out, info)
    matrix = np.zeros((n, n))
    matrix[pairs[:, 0], pairs[:, 1]] = results[:, 0]
    if method == "pmp":
        fallback = _triangle_guard(field, pts, pairs, speed, matrix, fallback, jobs, grid, info)
        info["fallback"] = [(int(i), int(j)) for i, j in pairs[fallback]]
    info["iterations"] = {
        "median": float(np.median(results[:, 2])) if len(results) else 0.0,
        "max": int(results[:, 2].max()) if len(results) else 0,
    }
    return (matrix, info) if return_info else matrix


def _collocation_rows(
    field: Field,
    pts: np.ndarray,
    pairs: np.ndarray,
    speed: float,
    jobs: int,
    grid: dict[str, Any],
    progress: bool = False,
) -> np.ndarray:
    """Rows (time, success, iterations) of ``pairs`` by batched collocation."""
    if jobs == 1 or len(pairs) < _PARALLEL_MIN_PAIRS:
        results = np.empty((len(pairs), 3))
        solver = get_solver(field, **grid)
        bar = _bar(len(pairs), progress)
        step = 64
        for lo in range(0, len(pairs), step):
            results[lo : lo + step] = _solve_pairs(solver, pts, pairs[lo : lo + step], speed)
            bar.update(len(pairs[lo : lo + step]))
        bar.close()
        return results
    return _parallel(field, grid, pts, pairs, speed, jobs, progress)


def _retry_failed(
    field: Field,
    pts: np.ndarray,
    pairs: np.ndarray,
    speed: float,
    results: np.ndarray,
    grid: dict[str, Any],
    info: dict[str, Any],
) -> None:
    """Retry failed rows in place: a finer collocation grid, then shooting; else name the pairs."""
    failed = np.flatnonzero(
        (results[:, 1] < 0.5) | ~np.isfinite(results[:, 0]) | (results[:, 0] <= 0)
    )
    unresolved = []
    for row in failed:
        i, j = pairs[row]
        try:
            path = collocation_path(
                field, pts[i], pts[j], speed, 4 * grid["intervals"], grid["degree"]
            )
        except ConvergenceError:
            try:
                from taopt.navigation.shooting import shooting_path

                path = shooting_path(field, pts[i], pts[j], speed)
            except ConvergenceError:
                unresolved.append((int(i), int(j)))
                continue
        results[row] = (path.time, 1.0, results[row, 2] + path.iterations)
        info["retried"].append((int(i), int(j)))
    if unresolved:
        shown = ", ".join(str(p) for p in unresolved[:10])
        more = f" and {len(unresolved) - 10} more" if len(unresolved) > 10 else ""
        raise ConvergenceError(f"travel time did not converge for pairs (i, j) = {shown}{more}")


def _check_fallback(
    pairs: np.ndarray, fallback: np.ndarray, results: np.ndarray, out: Any, info: dict[str, Any]
) -> None:
    """Flag collocation fallbacks that did no better than the extremal PMP rejected.

    Collocation is a local method too: on a pair whose extremal was rejected as
    not locally optimal (or slower than the straight line) it may converge to the
    same stationary path. Such entries are kept but listed in ``info["suspect"]``
    and warned about; an entry above the straight-line time (a feasible time,
    check 3 of :mod:`taopt.navigation.pmp`) is replaced by it.
    """
    rejected = out.extremal_time[fallback]
    line = out.line_time[fallback]
    times = results[fallback, 0]
    no_better = np.isfinite(rejected) & (times >= rejected * (1.0 - 1e-9))
    above_line = times > line * (1.0 + 1e-9)
    results[fallback[above_line], 0] = line[above_line]
    flagged = [(int(i), int(j)) for i, j in pairs[fallback[no_better | above_line]]]
    if flagged:
        info["suspect"] = sorted(set(info["suspect"]) | set(flagged))
        shown = ", ".join(str(p) for p in flagged[:10])
        warnings.warn(
            "collocation did not improve on the rejected extremal (its time may not be the "
            f"minimum) at (i, j) = {shown}{' ...' if len(flagged) > 10 else ''}",
            RuntimeWarning,
            stacklevel=3,
        )


def _triangle_guard(
    field: Field,
    pts: np.ndarray,
    pairs: np.ndarray,
    speed: float,
    matrix: np.ndarray,
    fallback: np.ndarray,
    jobs: int,
    grid: dict[str, Any],
    info: dict[str, Any],
) -> np.ndarray:
    """Re-solve by collocation the PMP entries that break Lemma 2.3's triangle inequality.

    A PMP time belongs to a real trajectory, so it is never below the optimum:
    ``t(i, k) > t(i, j) + t(j, k)`` marks ``(i, k)`` as a slower extremal (check 4
    of :mod:`taopt.navigation.pmp`). The smaller of the two times is kept.
    Entries still violating afterwards are listed in ``info["suspect"]`` and
    warned about. Updates ``matrix`` in place; returns the new fallback rows.
    """
    n = len(pts)
    row_of = np.full((n, n), -1)
    row_of[pairs[:, 0], pairs[:, 1]] = np.arange(len(pairs))
    done = set(fallback.tolist())
    suspects = [
        row_of[i, k] for i, k in triangle_violations(matrix, TRIANGLE_RTOL) if row_of[i, k] >= 0
    ]
    fresh = np.array(sorted(set(suspects) - done), dtype=int)
    if fresh.size:
        rows = _collocation_rows(field, pts, pairs[fresh], speed, jobs, grid)
        good = (rows[:, 1] > 0.5) & np.isfinite(rows[:, 0]) & (rows[:, 0] > 0)
        i, k = pairs[fresh[good], 0], pairs[fresh[good], 1]
        matrix[i, k] = np.minimum(matrix[i, k], rows[good, 0])
        fallback = np.concatenate([fallback, fresh])
        info["fallback_reason"] += ["triangle inequality (Lemma 2.3) violated"] * fresh.size
    remaining = triangle_violations(matrix, TRIANGLE_RTOL) if suspects else []
    if remaining:
        info["suspect"] = sorted(set(info["suspect"]) | set(remaining))
        shown = ", ".join(str(p) for p in remaining[:10])
        warnings.warn(
            f"travel times still break the triangle inequality (Lemma 2.3) after re-solving by "
            f"collocation at (i, k) = {shown}{' ...' if len(remaining) > 10 else ''}",
            RuntimeWarning,
            stacklevel=3,
        )
    return fallback


def _bar(total: int, progress: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, disable=not progress, desc="travel times", unit="pair")


def _progress(items: np.ndarray, progress: bool) -> Any:
    from tqdm import tqdm

    return tqdm(items, disable=not progress, desc="travel times", unit="pair")


def _parallel(
    field: Field,
    grid: dict[str, Any],
    pts: np.ndarray,
    pairs: np.ndarray,
    speed: float,
    jobs: int,
    progress: bool,
) -> np.ndarray:
    """Solve ``pairs`` in ``jobs`` processes; returns rows in the order of ``pairs``."""
    methods = multiprocessing.get_all_start_methods()
    n_chunks = max(jobs * 8, 1)
    chunk = BATCH_SIZE * max(1, -(-len(pairs) // (n_chunks * BATCH_SIZE)))
    order = np.arange(len(pairs))
    results = np.empty((len(pairs), 3))
    bar = _bar(len(pairs), progress)
    # the workers keep the environment (env={}), ignore Ctrl-C and die with this process;
    # on Ctrl-C or an error they are killed at once (docs/architecture.md, the runtime contract)
    pool = WorkerPool(
        jobs,
        env={},
        context="fork" if "fork" in methods else "spawn",
        initializer=_worker_init,
        initargs=(field.to_dict(), grid, pts, speed),
    )
    try:
        futures = {}
        for lo in range(0, len(pairs), chunk):
            futures[pool.submit(_worker_solve, pairs[lo : lo + chunk])] = order[lo : lo + chunk]
        for future in as_completed(futures):
            rows = futures[future]
            _, out = future.result()
            results[rows] = out
            bar.update(len(rows))
    except BaseException:
        pool.terminate()
        raise
    pool.shutdown()
    bar.close()
    return results
