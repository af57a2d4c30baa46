"""The SOP portfolio's resources: the stage that fits the memory limit, and the time left used.

The portfolio (:func:`taopt.models.sop.solve_sop_problem`) never refuses an instance for its
size and never stops early while its limit lasts (issue 33, item 3):

**Memory ladder.** Each stage's peak is estimated with the measured model of
:mod:`taopt.models.sop` (``BASE_BYTES`` plus ``DP_BYTES_PER_STATE`` per DP state kept,
``BEAM_BYTES_PER_SLOT`` per beam slot (width x nodes), ``SOP_MILP_BYTES_PER_NONZERO`` per flow
nonzero; ``benchmarks/bench_sop_memory.py`` measures and fits them) and compared with the limit
(:func:`taopt.runtime.max_memory_gb`: ``max_memory_gb=`` or ``TAOPT_MAX_MEMORY_GB``), less
CP-SAT's worker when it runs beside the stages (``cpsat_worker_bytes``: a process of its own,
its memory spent first). From the strongest stage down (:func:`memory_plan`):

1. ``"dp"``: the DP over order ideals with a state cap that fits (at least
   :data:`MIN_DP_STATES` states), and the flow MILP when its columns fit too;
2. ``"beam"``: the DP's beam search (``taopt.models.sop_dp.beam_order``), its width fitted
   to the memory (at least :data:`MIN_BEAM_WIDTH`), widened while time is left, with the
   assignment and arborescence bounds (``taopt.models.sop._cheap_bound``);
3. ``"bound"``: the warm start's order and the same bounds (memory O(n^2), which the problem
   itself takes).

A degraded run ends through :func:`taopt.result.finish` with the stop ``"max_states"``: status
``time_limit`` with its best order and a proven bound (``optimal`` only when the two meet).

**The time left.** A portfolio run whose stages ended before its limit without proving the
optimum (a DP stopped by its state cap, a MILP that could not be built in its share) goes on
(:func:`use_the_rest`): a DP stage with twice the state cap while that fits the memory, then
beam passes of doubling width from the best order (the anytime beam search of Libralesso et
al., 2020) until the limit. Each pass re-proves nothing it does not keep: the best order and
the larger proven bound are kept (``taopt.models.sop._combine``).

References
----------
Libralesso, Bouhassoun, Cambazard and Jost, "Tree search for the sequential ordering
problem", ECAI 2020 (anytime beam search with growing widths).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from taopt.result import TIME_LIMIT, Order, Solution, finish
from taopt.runtime import MARGIN, Deadline
from taopt.sop.problem import SopProblem

__all__ = [
    "MIN_DP_STATES",
    "MIN_BEAM_WIDTH",
    "FIRST_FILL_WIDTH",
    "MAX_FILL_WIDTH",
    "memory_plan",
    "beam_width_cap",
    "degraded",
    "use_the_rest",
]

#: Fewest states a DP stage is run with; below, the memory gives the beam instead (a DP that
#: can keep only a few layers proves nothing the assignment bound does not).
MIN_DP_STATES = 20_000

#: Narrowest beam run; below, only the warm start's order and the cheap bounds fit.
MIN_BEAM_WIDTH = 8

#: Width of the first beam pass that uses the time left; the widths double from it, skipping
#: those the DP's own beam passes ran (``NARROW_BEAM`` of :mod:`taopt.models.sop_dp` and 1,024), so a
#: pass that cannot end in the time left costs at most as long as all the passes before it.
FIRST_FILL_WIDTH = 128

#: Widest beam pass (memory permitting): past it a pass takes minutes on 100+ nodes.
MAX_FILL_WIDTH = 1 << 20


def beam_width_cap(n: int, max_memory_gb: float | None) -> int:
    """The widest beam (at most :data:`MAX_FILL_WIDTH`) whose estimated peak fits the limit;
    0 when not even :data:`MIN_BEAM_WIDTH` does."""
    from taopt.models.sop import BASE_BYTES, beam_bytes
    from taopt.runtime import max_memory_gb as limit_gb

    room = limit_gb(max_memory_gb) * 1e9 - BASE_BYTES
    width = int(min(MAX_FILL_WIDTH, room / beam_bytes(n, 1))) if room > 0 else 0
    return width if width >= MIN_BEAM_WIDTH else 0


def memory_plan(n: int, max_memory_gb: float | None) -> str:
    """The strongest stage that fits the memory limit: "dp", "beam" or "bound" (module
    docstring)."""
    from taopt.models.sop import BASE_BYTES, dp_bytes
    from taopt.runtime import max_memory_gb as limit_gb

    room = limit_gb(max_memory_gb) * 1e9 - BASE_BYTES
    if room >= dp_bytes(n, MIN_DP_STATES):
        return "dp"
    return "beam" if beam_width_cap(n, max_memory_gb) else "bound"


def _widen(
    problem: SopProblem,
    known: tuple[float, list[int]] | None,
    deadline: Deadline,
    first: int,
    widest: int,
    info: dict[str, Any],
    stage: Callable[[float], None] | None = None,
    skip: tuple[int, ...] | None = None,
    setup: float = 0.0,
) -> tuple[tuple[float, list[int]] | None, bool]:
    """Beam passes of width ``first``, doubling up to ``widest``, until the deadline; the
    best order and whether the widest pass ended (False: the deadline came first).
    ``stage(bytes)`` is told each pass's estimated peak before it runs. A pass sets up its
    completion bound before it looks at the clock: it starts only when the time left covers
    the shortest pass seen so far (``setup`` before the first), so none overruns the limit."""
    from taopt.models.sop import BASE_BYTES, beam_bytes
    from taopt.models.sop_dp import beam_order

    widths: list[int] = info.setdefault("beam_widths", [])
    done = set() if skip is None else set(skip)
    width = max(MIN_BEAM_WIDTH, min(first, widest))
    shortest = setup  # a pass's setup is at most the shortest whole pass
    while not deadline.expired(MARGIN):
        if width in done and width < widest:
            width = min(2 * width, widest)
            continue
        left = deadline.remaining()
        if left is not None and left < shortest + MARGIN:
            info["beam_stopped"] = f"{left:.2f} s left for a pass of at least {shortest:.2f} s"
            break
        if stage is not None:
            stage(BASE_BYTES + beam_bytes(problem.n, width))
        began = time.perf_counter()
        beam = beam_order(problem, width, None if left is None else left - MARGIN)
        took = time.perf_counter() - began
        shortest = took if not widths else min(shortest, took)
        if beam is None:  # stopped by the deadline, or refused a layer it could not end in
            info["beam_stopped"] = f"width {width:,}: no order in the time left"
            break  # time (a wider pass would not either)
        widths.append(width)
        if beam is not None and (known is None or beam[0] < known[0]):
            known = beam
        if width >= widest:
            return known, True
        width = min(2 * width, widest)
    return known, False


def degraded(
    problem: SopProblem,
    plan: str,
    deadline: Deadline,
    incumbent: Any,
    max_memory_gb: float | None,
    began: float,
    stage: Callable[[float], None] | None = None,
) -> Solution:
    """The ``"beam"`` or ``"bound"`` stage of the memory ladder: the best order found and the
    assignment/arborescence bound, stop ``"max_states"`` (status ``time_limit`` unless they
    meet)."""
    from taopt.models.sop import _cheap_bound, _known_order

    known = _known_order(problem.cost, problem.closure, problem.start, problem.end, incumbent)
    info: dict[str, Any] = {"memory_plan": plan}
    if plan == "beam":
        widest = beam_width_cap(problem.n, max_memory_gb)
        info["beam_width_cap"] = widest
        known, _ = _widen(problem, known, deadline, FIRST_FILL_WIDTH, widest, info, stage)
    return finish(
        problem,
        None if known is None else Order(known[1]),
        method="exact-sop",
        stop="max_states",
        bound=_cheap_bound(problem),
        runtime=time.perf_counter() - began,
        info=info,
    )


def use_the_rest(
    problem: SopProblem,
    result: Solution,
    deadline: Deadline,
    state_cap: int,
    max_memory_gb: float | None,
    setup: float,
    stage: Callable[[float], None] | None = None,
) -> Solution:
    """Go on while the limit lasts (module docstring): DP stages with doubling state caps
    within the memory, then beam passes of doubling width; the best order and the larger
    proven bound are kept. ``state_cap`` is the last DP stage's cap, ``setup`` the longest
    setup measured on a DP stage (a DP stage starts only when the time left covers twice
    it). ``info["rest"]`` lists what ran; ``stage(bytes)`` is told each stage's estimated
    peak before it runs."""
    from taopt.models.sop import (
        BASE_BYTES,
        _combine,
        dp_bytes,
        dp_state_cap,
        dp_states_in,
    )
    from taopt.models.sop_dp import NARROW_BEAM, solve_sop_dp

    ran: list[str] = []
    memory_cap = dp_state_cap(problem.n, max_memory_gb, 1 << 40)
    cap = state_cap
    while result.status == TIME_LIMIT and cap < memory_cap and not deadline.expired(MARGIN):
        left = deadline.remaining()
        if left is not None and left < 2 * setup + MARGIN:
            break
        cap = min(2 * cap, memory_cap)
        if stage is not None:  # the states it can keep in its time, at most its cap
            made = cap if left is None else min(cap, dp_states_in(problem.n, left))
            stage(BASE_BYTES + dp_bytes(problem.n, made))
        again = solve_sop_dp(
            problem,
            None if left is None else max(left - MARGIN, MARGIN),
            incumbent=result.solution,
            max_states=cap,
            both_prices=True,
            beam_width=0,
        )
        setup = max(setup, again.info.get("setup_seconds", 0.0))
        ran.append(f"dp {cap:,} states")
        result = _combine(result, again)
        if again.info.get("stopped_by") != "max_states":
            break  # proved, or stopped by the deadline
    if result.status == TIME_LIMIT and deadline.limited and not deadline.expired(MARGIN):
        widest = beam_width_cap(problem.n, max_memory_gb)
        if widest:
            known = None
            if result.order is not None:
                known = (result.objective, list(result.order))
            info: dict[str, Any] = {}
            ran_before = (NARROW_BEAM, 1024)  # the DP's own beam passes
            found, _ = _widen(
                problem, known, deadline, FIRST_FILL_WIDTH, widest, info, stage, ran_before,
                setup / 2,  # one direction's bound of the two a DP stage sets up
            )  # fmt: skip
            ran += [f"beam {w:,}" for w in info.get("beam_widths", [])]
            if found is not None and (known is None or found[0] < known[0]):
                better = finish(
                    problem,
                    Order(found[1]),
                    method="exact-sop",
                    stop="time_limit",
                    bound=result.bound,
                    runtime=result.runtime,
                    info=dict(result.info),
                )
                result = _combine(result, better)
    if ran:
        result = result.replace(info={**result.info, "rest": ran})
    return result
