"""Exact SOP model on TSPLIB .sop instances, and the thesis's sequencing heuristics' gaps.

Run::

    python benchmarks/bench_sop.py                    # ESC07 ESC11 ESC12 br17.10 br17.12, flow model
    python benchmarks/bench_sop.py --esc25            # also ESC25 (about a minute)
    python benchmarks/bench_sop.py --mtz 60           # also the MTZ model with a 60 s limit
    python benchmarks/bench_sop.py --time-limit 300 ESC12 br17.10
    python benchmarks/bench_sop.py --compare 60       # portfolio, DP, MILP, CP-SAT side by side
    python benchmarks/bench_sop.py --compare 60 ESC25 p43.4

    python benchmarks/bench_sop.py --resources 10 --load   # wall time and peak RSS, per process
    python benchmarks/bench_sop.py --table 60 --load  # every SOP: exact beside CP-SAT
    python benchmarks/bench_sop.py --roots 120        # root bounds: flow LP vs precedence cuts
    python benchmarks/bench_sop.py --cuts 60 p43.1    # the cut engine alone (also DERIVED)
    python benchmarks/bench_sop.py --table 60 --unseen --load   # the stand-ins (UNSEEN)
    python benchmarks/bench_sop.py --resources 60 --unseen --load
    python benchmarks/bench_sop.py --resources 60 --cpsat both   # portfolio without/with CP-SAT
    python benchmarks/bench_sop.py --table 60 --methods exact ESC25   # one method only

``--resources T`` runs ``taopt.solve(problem, "exact", time_limit=T)`` on each instance (default:
every shipped SOP file, :data:`RESOURCES`) in its own fresh process and prints status,
objective, bound, wall time (``time.perf_counter`` around the call), the overrun over
``T + max(1 s, 5 %)``, the peak resident memory of the run: that process's
(``resource.getrusage``, ``ru_maxrss``) plus CP-SAT's worker's beside it (the reaped
children's ``ru_maxrss``), against the memory guard's upper estimate made before the run
(:func:`taopt.runtime.footprint`, CP-SAT's worker counted when it runs; a ratio above 2 is
marked) and the reported estimate (``info["memory_estimate"]``, predicted by
:func:`taopt.models.sop.predicted_peak` after the probe of the first DP stage's first layers,
:class:`taopt.models.sop.LayerWatch`, before the later stages; a ratio outside [0.5, 2] is
marked ``**out**``), listed at the end, with the states the estimate expected (the probe's
measured states → its expectation; "states kept" is the last DP stage's count). ``--load`` starts a second process spinning on one core for
the duration (the shared-machine condition of issue 33). ``--generated`` adds the generated
instances of :data:`GENERATED` (``taopt.sop.generate``). ``--record FILE`` appends each run's
row (the prediction's inputs, the states kept, the peaks) as JSON, the data
:func:`~taopt.models.sop.predicted_peak` is fitted on.

``--compare T`` runs, on each instance (default: :data:`COMPARE`, read from the shipped
files or from ``../shared/benchmarks/tsplib``), ``taopt.solve(problem, "exact")`` (the
portfolio of :func:`taopt.models.sop.solve_sop_problem`), the same with
``engine="dp"`` and ``engine="milp"`` (each with the NIA/MMA/SMMA warm start), and
OR-Tools CP-SAT (``"cpsat"``, 2 workers, in its worker process), each with a time limit of
T seconds, and prints a Markdown table: status, objective, bound, wall time, ideals, DP
states kept and pruned. Every objective is re-scored by ``evaluate_order``.

For every instance it prints the exact model's status, objective, proven bound, gap and
time, the TSPLIB optimum, and the path cost and gap to the optimum of NIA, MMA and SMMA
(``heuristics.sequencing``, the generic ``*_order(cost, precedences, start, end)``).
A time limit is reported as such, with its gap; nothing is called optimal unless proven.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from taopt.models import solve_sop
from taopt.sop.problem import KNOWN_OPTIMA, load_sop, path_cost

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


COMPARE = [
    "ESC07",
    "ESC11",
    "ESC12",
    "br17.10",
    "br17.12",
    "ESC25",
    "ESC47",
    "rbg048a",
    "rbg050c",
    "p43.4",
    "ry48p.4",
    "ft53.4",
]

#: Optima of the comparison set not shipped with taopt (shared/benchmarks/tsplib/README.md).
MORE_OPTIMA = {
    "rbg048a": 351,
    "rbg050c": 467,
    "ry48p.4": 31446,
    "ft53.4": 14425,
    "p43.1": 28140,
    "ry48p.1": 15805,
    "ft53.1": 7531,
    "prob.42": 243,
}

SHARED = next(
    (
        up / "shared" / "benchmarks" / "tsplib"
        for up in Path(__file__).resolve().parents[1:4]
        if (up / "shared" / "benchmarks" / "tsplib").is_dir()
    ),
    Path(__file__).resolve().parents[1].parent / "shared" / "benchmarks" / "tsplib",
)


def load_problem(name: str):
    from taopt.sop.problem import SopProblem, shipped_sop

    if name in shipped_sop():
        return SopProblem.load(name)
    return SopProblem.load(SHARED / f"{name}.sop")


def compare(names: list[str], limit: float) -> None:
    """The side-by-side table of ``--compare`` (see the module docstring)."""
    import taopt
    from taopt.sop.problem import evaluate_order

    runs = {
        "portfolio": lambda p: taopt.solve(p, "exact", time_limit=limit),
        "DP alone": lambda p: taopt.solve(p, "exact", time_limit=limit, engine="dp"),
        "MILP alone": lambda p: taopt.solve(p, "exact", time_limit=limit, engine="milp"),
        "CP-SAT": lambda p: taopt.solve(p, "cpsat", time_limit=limit, num_workers=2),
    }
    taopt.solve(load_problem("ESC07"), "cpsat", time_limit=10)  # start the worker: not timed
    print(f"time limit {limit:g} s per run")
    print(
        "| instance | optimum | method | status | objective | bound | time (s) | ideals | states kept / pruned |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in names:
        problem = load_problem(name)
        optimum = KNOWN_OPTIMA.get(name, MORE_OPTIMA.get(name))
        for label, run in runs.items():
            began = time.perf_counter()
            result = run(problem)
            elapsed = time.perf_counter() - began
            if result.solution is not None:
                assert evaluate_order(problem, result.order) == result.objective
            info = result.info
            ideals = info.get("ideals", "")
            if ideals != "" and info.get("ideals_capped"):
                ideals = f"> {ideals:,}"
            elif ideals != "":
                ideals = f"{ideals:,}"
            kept = info.get("states", info.get("dp_states"))
            pruned = info.get("pruned", info.get("dp_pruned"))
            states = "" if kept is None else f"{kept:,} / {pruned:,}"
            bound = "" if result.bound is None else f"{result.bound:g}"
            print(
                f"| {name} | {optimum} | {label} | {result.status} | {result.objective:g} | "
                f"{bound} | {elapsed:.2f} | {ideals} | {states} |",
                flush=True,
            )


#: Every SOP file shipped or kept in ../shared/benchmarks/tsplib (resources run).
RESOURCES = [
    "ESC07",
    "ESC11",
    "ESC12",
    "br17.10",
    "br17.12",
    "ESC25",
    "ESC47",
    "p43.1",
    "p43.4",
    "prob.42",
    "ry48p.1",
    "ry48p.4",
    "ft53.1",
    "ft53.4",
    "rbg048a",
    "rbg050c",
]

#: Generated instances (name -> constructor call in taopt.sop.generate).
GENERATED = {
    "random-40-0.1": ("random_sop", (40, 0.1, 1)),
    "random-60-0.3": ("random_sop", (60, 0.3, 1)),
    "random-100-0.3": ("random_sop", (100, 0.3, 1)),
    "random-150-0.6": ("random_sop", (150, 0.6, 1)),
    "chains-80-3": ("chain_sop", (80, 3, 1)),
    "chains-120-3": ("chain_sop", (120, 3, 1)),
    "chains-150-4": ("chain_sop", (150, 4, 2)),
    "chains-380-8-x0.01": ("chain_sop", (380, 8, 1, 0.01)),
    "random-300-0.02": ("random_sop", (300, 0.02, 1)),
}

#: The first stand-ins for the rbg family (issue 33, stop 31): chains with uniform random costs
#: 0-33. CP-SAT finds no order on them, while it closes the real rbg109a and rbg150a: not like
#: the real family (no crane moves, no time-window precedences); kept as generated instances.
GENERATED.update(
    {
        "rbg-like-110": ("rbg_like_sop", (110, 1, 0.85)),
        "rbg-like-150": ("rbg_like_sop", (150, 1, 0.8)),
        "rbg-like-175": ("rbg_like_sop", (175, 2, 0.75)),
        "rbg-like-255": ("rbg_like_sop", (255, 1, 0.85)),
        "rbg-like-340": ("rbg_like_sop", (340, 1, 0.85)),
        "rbg-like-380": ("rbg_like_sop", (380, 1, 0.89)),
    }
)

#: Stand-ins for the TSPLIB SOP families we do not have (issue 33's unseen set), built without
#: tuning to the shipped files:
#:
#: * rbg (rbg109a-rbg378a: 111-380 nodes, 5,000-64,000 precedence pairs): ``rbg_from_atsp``,
#:   the crane moves of a random subset of rbg403's or rbg443's jobs (the same stacker-crane
#:   application) and time-window precedences (an interval order, jobs released in batches),
#:   closure 0.82-0.89 of the job pairs;
#: * ESC (ESC63, ESC78): ``esc_like_sop`` at 65 and 80 nodes, closure 0.15 and 0.04 of the
#:   inner pairs (ESC25 and ESC47: 0.030-0.037 of the inner pairs, 0.11 with the start's and
#:   end's pairs);
#: * SOPs from the shipped ATSP matrices with the densities of TSPLIB's .2 and .3 files (ft70
#:   from ftv70, p43, ry48p; kro124p is not shipped).
#:
#: ``--unseen`` runs these.
UNSEEN = {
    "rbg-atsp-75-0.5": ("atsp_file_rbg", ("rbg403", 75, 1, 0.5)),
    "rbg-atsp-110": ("atsp_file_rbg", ("rbg403", 110, 1, 0.84)),
    "rbg-atsp-110-0.6": ("atsp_file_rbg", ("rbg403", 110, 2, 0.6)),
    "rbg-atsp-150": ("atsp_file_rbg", ("rbg403", 150, 1, 0.86)),
    "rbg-atsp-150-0.6": ("atsp_file_rbg", ("rbg443", 150, 2, 0.6)),
    "rbg-atsp-175": ("atsp_file_rbg", ("rbg443", 175, 1, 0.86)),
    "rbg-atsp-255": ("atsp_file_rbg", ("rbg443", 255, 1, 0.87)),
    "rbg-atsp-343": ("atsp_file_rbg", ("rbg403", 343, 1, 0.88)),
    "rbg-atsp-380": ("atsp_file_rbg", ("rbg443", 380, 1, 0.89)),
    "esc-like-65": ("esc_like_sop", (65, 1, 0.15)),
    "esc-like-80": ("esc_like_sop", (80, 1, 0.15)),
    "esc-like-65-0.04": ("esc_like_sop", (65, 2, 0.04)),
    "esc-like-80-0.04": ("esc_like_sop", (80, 2, 0.04)),
    "ftv70-0.15": ("atsp_file_sop", ("ftv70", 0.15, 1)),
    "ftv70-0.3": ("atsp_file_sop", ("ftv70", 0.3, 1)),
    "p43-0.15": ("atsp_file_sop", ("p43", 0.15, 1)),
    "p43-0.3": ("atsp_file_sop", ("p43", 0.3, 1)),
    "ry48p-0.15": ("atsp_file_sop", ("ry48p", 0.15, 1)),
    "ry48p-0.3": ("atsp_file_sop", ("ry48p", 0.3, 1)),
}
GENERATED.update(UNSEEN)

_CHILD = """
import json, resource, sys, time
began = time.perf_counter()
import taopt
import taopt.heuristics
import taopt.models
from taopt.runtime import footprint
from taopt.orchestration import pipeline  # imported before the clock: the call alone is timed
sys.path.insert(0, {bench!r})
from bench_sop import load_any
problem = load_any({name!r})
from taopt.models.sop import BASE_BYTES, dp_bytes, nonzero_count, sop_milp_bytes
import taopt.models.sop
if {nice!r} is not None:
    taopt.models.sop.CPSAT_NICE = {nice!r}
estimate = footprint(problem, "exact", {{"time_limit": {limit!r}, "cpsat": {cpsat!r}}})[0]
t0 = time.perf_counter()
result = taopt.solve(problem, "exact", time_limit={limit!r}, cpsat={cpsat!r})
wall = time.perf_counter() - t0
from taopt.heuristics import peers
peers.shutdown()  # CP-SAT's worker reaped: its peak is the children's
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
worker_peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
info = result.info
side = info.get("cpsat")
if isinstance(side, dict):
    side = "{{}} {{:g}} [{{}}] {{:.1f}} s".format(side.get("status"), side.get("objective", float("inf")),
        side.get("bound"), side.get("seconds") or 0.0)
states = max(info.get("states") or 0, info.get("dp_states") or 0)
staged = info.get("memory_estimate") or estimate
nonzeros = nonzero_count(problem.cost, problem.closure, problem.start) if info.get("variables") else 0
model = BASE_BYTES + dp_bytes(problem.n, states) + sop_milp_bytes(nonzeros)
print(json.dumps(dict(status=str(result.status), objective=result.objective, bound=result.bound,
    wall=wall, peak=peak, estimate=estimate, n=problem.n, engine=info.get("engine"),
    states=states, columns=info.get("variables") or 0, model=model, staged=staged,
    rest=info.get("rest"), cpsat=side, worker_peak=worker_peak,
    prediction=info.get("memory_prediction"), stages=info.get("memory_stages"),
    root=(info.get("root_stage") or {{}}).get("closed"), ideals=info.get("ideals"),
    capped=info.get("ideals_capped"), cut_rounds=info.get("mip_rounds"),
    pool=info.get("pool_rows"), cuts=info.get("cuts"), arcs=info.get("arcs"),
    began=began), default=str))
"""


#: SOPs derived from the shipped ATSP matrices (``taopt.sop.generate.atsp_sop``: random
#: precedences of the density named, seed last) and small random/chain SOPs, for ``--cuts``.
DERIVED = [
    "ftv33-0.02-1",
    "ftv38-0.05-1",
    "ftv44-0.02-1",
    "ftv47-0.05-2",
    "p43-0.02-1",
    "p43-0.05-1",
    "ry48p-0.02-1",
    "ry48p-0.05-1",
    "ft53-0.02-1",
    "ft53-0.05-1",
]


def load_derived(name: str):
    """``BASE-DENSITY-SEED``: the ATSP file BASE of ``../shared/benchmarks/tsplib`` made an
    SOP by :func:`taopt.sop.generate.atsp_sop`."""
    import numpy as np

    from taopt.sop.generate import atsp_sop
    from taopt.tsplib import read_tsplib

    base, density, seed = name.rsplit("-", 2)
    header, words = read_tsplib(SHARED / f"{base}.atsp")
    n = int(header["DIMENSION"])
    cost = np.array([float(w) for w in (words or [])[: n * n]]).reshape(n, n)
    np.fill_diagonal(cost, 0.0)
    return atsp_sop(cost, float(density), int(seed))


def cuts(names: list[str], limit: float) -> None:
    """``--cuts T``: the cut engine alone (:func:`taopt.models.sop_cuts.solve_sop_cuts`, no
    warm start) at T s on each instance: root bound, status, objective, bound, wall time,
    MIP rounds, arcs fixed by reduced cost and HiGHS cuts kept."""
    import os

    from taopt.models.sop_cuts import solve_sop_cuts

    print(f"cut engine at {limit:g} s, load {os.getloadavg()[0]:.1f}")
    print(
        "| instance | n | root | status | objective | bound | time (s) | MIP rounds | fixed | pool |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        problem = load_derived(name) if name in DERIVED else load_any(name)
        began = time.perf_counter()
        result = solve_sop_cuts(problem, limit)
        wall = time.perf_counter() - began
        info = result.info or {}
        print(
            f"| {name} | {problem.n} | {info.get('root_bound')} | {result.status} | "
            f"{result.objective} | {result.bound} | {wall:.1f} | {info.get('mip_rounds')} | "
            f"{info.get('fixed')} | {info.get('pool_rows')} |",
            flush=True,
        )


def tree(names: list[str], limit: float) -> None:
    """``--tree T``: the cut engine alone (:func:`taopt.models.sop_cuts.solve_sop_cuts`, its MIP
    rounds) and our branch-and-cut (:func:`taopt.models.sop_bc.solve_sop_bc`) at T s on each
    instance, alternated, no warm start: the proven bound at the end (the tree's also at 10 and
    30 s, from its trace), the best order, nodes or MIP rounds, LPs per second."""
    import os

    from taopt.models.sop_bc import solve_sop_bc
    from taopt.models.sop_cuts import solve_sop_cuts

    print(f"cut engine vs tree at {limit:g} s, load {os.getloadavg()[0]:.1f}")
    print(
        "| instance | engine | bound 10 s | bound 30 s | bound | objective | time (s) | "
        "nodes / rounds | LPs/s | load |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        for engine in ("mip-rounds", "tree"):
            problem = load_derived(name) if name in DERIVED else load_any(name)
            began = time.perf_counter()
            if engine == "tree":
                result = solve_sop_bc(problem, limit)
            else:
                result = solve_sop_cuts(problem, limit)
            wall = time.perf_counter() - began
            info = result.info or {}
            trace = info.get("trace") or []

            def at(seconds: float, trace=trace) -> str:
                seen = [b for t, b in trace if t <= seconds]
                return f"{seen[-1]:g}" if seen else "-"

            count = info.get("nodes") if engine == "tree" else info.get("mip_rounds")
            rate = f"{info['lps'] / wall:.1f}" if engine == "tree" else "-"
            print(
                f"| {name} | {engine} | {at(10) if trace else '-'} | {at(30) if trace else '-'} "
                f"| {result.bound:g} | {result.objective:g} | {wall:.1f} | {count} | {rate} | "
                f"{os.getloadavg()[0]:.1f} |",
                flush=True,
            )


def load_any(name: str):
    """A shipped or shared SOP file, or a generated instance of :data:`GENERATED`."""
    if name in GENERATED:
        from taopt.sop import generate

        func, args = GENERATED[name]
        if func == "atsp_file_sop":  # a shipped ATSP matrix with random precedences
            from taopt.routing.tsplib import load_atsp

            stem, density, seed = args
            cost = load_atsp(SHARED / f"{stem}.atsp").distance.astype(float)
            return generate.atsp_sop(cost, 0.0, seed, closure=density).replace(name=name)
        if func == "atsp_file_rbg":  # a stacker-crane ATSP matrix, time-window precedences
            from taopt.routing.tsplib import load_atsp

            stem, n, seed, closure = args
            cost = load_atsp(SHARED / f"{stem}.atsp").distance.astype(float)
            return generate.rbg_from_atsp(cost, n, seed, closure).replace(name=name)
        return getattr(generate, func)(*args)
    return load_problem(name)


def resources(
    names: list[str],
    limit: float,
    load: bool,
    cpsat: tuple[bool | None, ...] = (None,),
    nice: int | None = None,
    record: str | None = None,
) -> None:
    """The wall-time and peak-memory table of ``--resources`` (module docstring); one row per
    instance and ``cpsat`` setting of the portfolio (``--cpsat both``: off, then on)."""
    import json
    import os
    import subprocess
    import sys

    spinner = None
    if load:
        spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    here = str(Path(__file__).resolve().parent)
    env = dict(os.environ)
    print(
        f"time limit {limit:g} s per run, each in its own process; load: {load}; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    print(
        "| instance | n | cpsat | status | objective | bound | wall (s) | over | parent peak (MB) |"
        " worker peak (MB) | peak (MB) | guard (MB) | peak / guard | estimate (MB) |"
        " peak / estimate | states kept | probe → expected states | engine | after the stages |"
        " CP-SAT beside |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    runs = [(name, side) for name in names for side in cpsat]
    outside = []
    try:
        for name, side in runs:
            code = _CHILD.format(bench=here, name=name, limit=limit, cpsat=side, nice=nice)
            run = subprocess.run(
                [sys.executable, "-c", code], capture_output=True, text=True, env=env
            )
            if run.returncode != 0:
                print(
                    f"| {name} | | process failed ({run.returncode}): "
                    f"{run.stderr.strip().splitlines()[-1:]} |",
                    flush=True,
                )
                continue
            r = json.loads(run.stdout.strip().splitlines()[-1])
            if record:  # every run's row, for fitting the estimate (predicted_peak)
                with open(record, "a") as out:
                    row = dict(r, name=name, limit=limit, side=side, load=load)
                    row["loadavg"] = os.getloadavg()[0]
                    out.write(json.dumps(row, default=str) + "\n")
            allowed = limit + max(1.0, 0.05 * limit)
            over = "yes" if r["wall"] > allowed else "no"
            # the run's cost to the machine: this process and CP-SAT's worker beside it
            peak = r["peak"] + r["worker_peak"]
            flag = {None: "auto", True: "on", False: "off"}[side]
            ratios = []
            for what, estimate in (("guard", r["estimate"]), ("estimate", r["staged"])):
                ratio = peak / estimate if estimate else float("nan")
                # the guard is an upper estimate (only above the peak is a miss); the
                # reported estimate is a prediction, its target [0.5, 2]
                low = 0.0 if what == "guard" else 0.5
                mark = "" if low <= ratio <= 2.0 else " **out**"
                if mark:
                    outside.append(f"{name} ({flag}, {what}: {ratio:.2f})")
                ratios.append(f"{ratio:.2f}{mark}")
            prediction = r.get("prediction") or {}
            probe = prediction.get("probe")
            expected = f"{prediction['states']:,.0f}" if "states" in prediction else ""
            if isinstance(probe, dict):
                expected = f"{probe['states']:,} → {expected}"
            print(
                f"| {name} | {r['n']} | {flag} | {r['status']} | {r['objective']:g} | "
                f"{r['bound']:g} | {r['wall']:.2f} | {over} | {r['peak'] / 1e6:.0f} | "
                f"{r['worker_peak'] / 1e6:.0f} | {peak / 1e6:.0f} | {r['estimate'] / 1e6:.0f} | "
                f"{ratios[0]} | {r['staged'] / 1e6:.0f} | {ratios[1]} | {r['states']:,} | "
                f"{expected} | {r['engine']} | {', '.join(r['rest'] or [])} | {r['cpsat']} |",
                flush=True,
            )
        print(
            f"peak / estimate outside [0.5, 2]: {', '.join(outside) or 'none'}; "
            f"load average {os.getloadavg()[0]:.1f}"
        )
    finally:
        if spinner is not None:
            spinner.kill()


_SIDE = """
import json, resource, sys, time
import taopt
import taopt.heuristics
import taopt.models
from taopt.orchestration import pipeline
sys.path.insert(0, {bench!r})
from bench_sop import load_any
from taopt.sop.problem import evaluate_order
problem = load_any({name!r})
options = {{"num_workers": 2}} if {method!r} == "cpsat" else {{}}
t0 = time.perf_counter()
result = taopt.solve(problem, {method!r}, time_limit={limit!r}, **options)
wall = time.perf_counter() - t0
if result.solution is not None:  # every order re-scored from the data
    assert abs(evaluate_order(problem, result.order) - result.objective) < 1e-6
peak = max(resource.getrusage(who).ru_maxrss for who in
           (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)) * 1024
print(json.dumps(dict(status=str(result.status), objective=result.objective,
    bound=result.bound, wall=wall, peak=peak, engine=result.info.get("engine", ""))))
"""


def side_by_side(
    names: list[str], limit: float, load: bool, methods: tuple[str, ...] = ("exact", "cpsat")
) -> None:
    """``--table T``: "exact" (the portfolio) and CP-SAT on each instance, each call in its
    own process: status (the portfolio's engines in brackets), objective, bound, wall time,
    peak memory (the larger of the process and its workers, ``ru_maxrss``), and the TSPLIB
    optimum; the load average before and after."""
    import json
    import os
    import subprocess
    import sys

    spinner = None
    if load:
        spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    here = str(Path(__file__).resolve().parent)
    print(
        f"time limit {limit:g} s per run, each in its own process; load: {load}; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    head = " | ".join(f"{m}: status | objective | bound | wall (s) | peak (MB)" for m in methods)
    print(f"| instance | n | optimum | {head} |")
    print("|---|---|---|" + "---|---|---|---|---|" * len(methods))
    try:
        for name in names:
            cells = []
            for method in methods:
                code = _SIDE.format(bench=here, name=name, limit=limit, method=method)
                run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
                if run.returncode != 0:
                    cells.append(f"failed ({run.returncode}) | | | |")
                    continue
                r = json.loads(run.stdout.strip().splitlines()[-1])
                bound = "" if r["bound"] is None else f"{r['bound']:g}"
                engine = f" ({r['engine']})" if r.get("engine") else ""
                cells.append(
                    f"{r['status']}{engine} | {r['objective']:g} | {bound} | {r['wall']:.1f} | "
                    f"{r['peak'] / 1e6:.0f}"
                )
            optimum = KNOWN_OPTIMA.get(name, MORE_OPTIMA.get(name, ""))
            n = load_any(name).n
            print(f"| {name} | {n} | {optimum} | {' | '.join(cells)} |", flush=True)
    finally:
        if spinner is not None:
            spinner.kill()
        print(f"load average at the end {os.getloadavg()[0]:.1f}")


def roots(names: list[str], limit: float) -> None:
    """``--roots T``: root bounds before and after the precedence path cuts: the flow
    model's LP relaxation (:func:`taopt.models.sop.build` with ``relax=True``, HiGHS, at
    most T s), the cut loop's root (:func:`taopt.models.sop_cuts.cut_bound`) with the pair
    rows alone and with the set path cuts and alternation rows
    (:data:`taopt.models.sop_cuts.SET_CUTS`), each at most T s, the assignment and
    arborescence bounds, and the optimum."""
    from taopt.models import sop_cuts
    from taopt.models.highs import solve_highs
    from taopt.models.sop import _cheap_bound, build
    from taopt.models.sop_cuts import cut_bound

    print(f"flow LP and each cut loop at most {limit:g} s")
    print(
        "| instance | n | optimum | assignment/arborescence | flow LP root (s) |"
        " pair path cuts root (s) | with set rows root (s) | cuts root / optimum |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        problem = load_any(name)
        optimum = KNOWN_OPTIMA.get(name, MORE_OPTIMA.get(name))
        began = time.perf_counter()
        model = build(problem.cost, problem.precedences, problem.start, problem.end, relax=True)
        run = solve_highs(model.problem, time_limit=limit)
        flow = f"{run.bound:.1f}" if run.bound is not None else "not solved"
        flow_s = time.perf_counter() - began
        cells = []
        for sets in (False, True):
            began = time.perf_counter()
            saved, sop_cuts.SET_CUTS = sop_cuts.SET_CUTS, sets
            try:
                root = cut_bound(problem, limit)
            finally:
                sop_cuts.SET_CUTS = saved
            cells.append(f"{root.bound:g} ({time.perf_counter() - began:.1f})")
        share = f"{root.bound / optimum:.4f}" if optimum else ""
        print(
            f"| {name} | {problem.n} | {optimum or ''} | {_cheap_bound(problem):g} | "
            f"{flow} ({flow_s:.1f}) | {cells[0]} | {cells[1]} | {share} |",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("names", nargs="*", default=None)
    parser.add_argument(
        "--compare", type=float, default=0.0, help="portfolio, DP, MILP, CP-SAT with this limit"
    )
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--esc25", action="store_true", help="add ESC25")
    parser.add_argument("--mtz", type=float, default=0.0, help="also run MTZ with this limit")
    parser.add_argument(
        "--resources", type=float, default=0.0, help="wall time and peak RSS at this limit"
    )
    parser.add_argument("--load", action="store_true", help="a second process loads a core")
    parser.add_argument("--generated", action="store_true", help="add the generated instances")
    parser.add_argument(
        "--table", type=float, default=0.0, help="exact beside CP-SAT, every SOP, this limit"
    )
    parser.add_argument(
        "--roots", type=float, default=0.0, help="root bounds: flow LP (this limit) vs cuts"
    )
    parser.add_argument(
        "--cuts", type=float, default=0.0, help="the cut engine alone at this limit"
    )
    parser.add_argument(
        "--tree", type=float, default=0.0, help="cut engine vs branch-and-cut at this limit"
    )
    parser.add_argument("--unseen", action="store_true", help="only the unseen stand-ins")
    parser.add_argument(
        "--methods", default="exact,cpsat", help="--table: the methods, comma-separated"
    )
    parser.add_argument(
        "--cpsat",
        choices=("auto", "on", "off", "both"),
        default="auto",
        help="--resources: the portfolio's cpsat= (both: off, then on, in the same run)",
    )
    parser.add_argument(
        "--nice", type=int, default=None, help="--resources: niceness of CP-SAT's worker"
    )
    parser.add_argument(
        "--record", default=None, help="--resources: append each run's JSON row to this file"
    )
    args = parser.parse_args()
    if args.unseen and not args.names:
        args.names = list(UNSEEN)
    if args.tree > 0:
        tree(args.names or ["ft53.1", "ry48p.1", "p43.1", "prob.42"], args.tree)
        return
    if args.cuts > 0:
        cuts(args.names or RESOURCES + DERIVED, args.cuts)
        return
    if args.table > 0:
        names = args.names or RESOURCES + (list(UNSEEN) if args.generated else [])
        side_by_side(names, args.table, args.load, tuple(args.methods.split(",")))
        return
    if args.roots > 0:
        roots(args.names or RESOURCES, args.roots)
        return
    if args.resources > 0:
        names = args.names or RESOURCES + (list(GENERATED) if args.generated else [])
        sides = {"auto": (None,), "on": (True,), "off": (False,), "both": (False, True)}
        resources(names, args.resources, args.load, sides[args.cpsat], args.nice, args.record)
        return
    if args.compare > 0:
        compare(args.names or COMPARE, args.compare)
        return
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
