"""Exact SOP model on TSPLIB .sop instances, and the thesis's sequencing heuristics' gaps.

Run::

    python benchmarks/bench_sop.py                    # ESC07 ESC11 ESC12 br17.10 br17.12, flow model
    python benchmarks/bench_sop.py --esc25            # also ESC25 (about a minute)
    python benchmarks/bench_sop.py --mtz 60           # also the MTZ model with a 60 s limit
    python benchmarks/bench_sop.py --time-limit 300 ESC12 br17.10

For every instance it prints the exact model's status, objective, proven bound, gap and
time, the TSPLIB optimum, and the path cost and gap to the optimum of NIA, MMA and SMMA
(``heuristics.sequencing``, the generic ``*_order(cost, precedences, start, end)``).
A time limit is reported as such, with its gap; nothing is called optimal unless proven.
"""

from __future__ import annotations

import argparse
import time

from taopt.delivery.sop import KNOWN_OPTIMA, load_sop, path_cost
from taopt.models import solve_sop

DEFAULT = ["ESC07", "ESC11", "ESC12", "br17.10", "br17.12"]


def heuristic_rows(cost, precedences, start, end, optimum):
    try:
        from taopt.heuristics.sequencing import mma_order, nia_order, smma_order
    except ImportError as exc:  # pragma: no cover - until heuristics exist
        print(f"    heuristics unavailable: {exc}")
        return
    for name, func in (("NIA", nia_order), ("MMA", mma_order), ("SMMA", smma_order)):
        began = time.perf_counter()
        order = func(cost, precedences, start, end)
        elapsed = time.perf_counter() - began
        value = path_cost(cost, order)
        gap = 100 * (value / optimum - 1) if optimum else float("nan")
        print(f"    {name:<5} cost={value:<8g} gap to optimum={gap:6.2f}%  time={elapsed:.3f}s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("names", nargs="*", default=None)
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--esc25", action="store_true", help="add ESC25")
    parser.add_argument("--mtz", type=float, default=0.0, help="also run MTZ with this limit")
    args = parser.parse_args()
    names = args.names or DEFAULT + (["ESC25"] if args.esc25 else [])
    for name in names:
        cost, precedences, start, end, _ = load_sop(name)
        known = KNOWN_OPTIMA.get(name)
        print(f"{name}: n={len(cost)}, {len(precedences)} precedences, TSPLIB optimum {known}")
        forms = [("flow", args.time_limit)] + ([("mtz", args.mtz)] if args.mtz > 0 else [])
        for formulation, limit in forms:
            sol = solve_sop(
                cost, precedences, start, end, time_limit=limit, formulation=formulation
            )
            assert abs(path_cost(cost, sol.order) - sol.objective) < 1e-9
            agree = "" if known is None else ("  (= TSPLIB)" if sol.objective == known else "")
            print(f"    {formulation:<5} {sol.summary()}  limit={limit:g}s{agree}")
        heuristic_rows(cost, precedences, start, end, known or sol.objective)


if __name__ == "__main__":
    main()
