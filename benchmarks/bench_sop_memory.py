"""Peak memory of each stage of the SOP engine, measured, and the memory model fitted on it.

Run::

    python benchmarks/bench_sop_memory.py                     # estimate vs peak, every SOP file
    python benchmarks/bench_sop_memory.py --stages dp,beam,milp,cpsat --generated --out runs.jsonl
    python benchmarks/bench_sop_memory.py --fit runs.jsonl    # the constants, from saved runs

Each run is one stage on one instance in a fresh interpreter (``python -c``), so its peak
resident memory is its own: ``resource.getrusage(RUSAGE_SELF).ru_maxrss`` after the stage,
and before it (the *base*: the interpreter with taopt, numpy, scipy, cvxpy and highspy
imported and the instance loaded). A stage run in a worker process (CP-SAT) is measured by
polling that process's RSS with ``psutil`` every 50 ms. Stages:

``portfolio``
    ``taopt.solve(problem, "exact", time_limit=T)``: the registered engine, warm start
    included. Printed beside the memory guard's estimate made before the run
    (:func:`taopt.runtime.footprint`) and the estimate of the stages that ran, made by the
    engine before each one (``info["memory_estimate"]``).
``dp``
    :func:`taopt.models.sop_dp.solve_sop_dp` without a state cap (feature: the states kept,
    both directions, ``info["states"]``).
``beam``
    :func:`taopt.models.sop_dp.beam_order` of width :data:`BEAM_WIDTH` (feature: width x n).
``milp``
    :func:`taopt.models.sop.solve_sop`, the flow model built, compiled and solved (feature:
    its nonzeros, :func:`taopt.models.sop.nonzero_count`; a model the run left built but not
    compiled is fitted apart, ``milp-build``). Skipped when the model would have more than ``--max-columns`` columns
    (the machine is shared).
``cpsat``
    ``taopt.solve(problem, "cpsat", time_limit=T)``: the worker's peak (feature: node pairs,
    n^2; fitted as ``CPSAT_WORKER_BYTES`` + ``CPSAT_BYTES_PER_NODE_PAIR`` x n^2).

``--fit`` reads the saved runs and prints, per stage, the constant ``bytes per unit of
feature`` that keeps ``base + constant x feature`` within the smallest factor of every
measured peak (minimax of ``|log(estimate / peak)|``), the factor reached and the median
base. These are the constants of :mod:`taopt.models.sop` (``BASE_BYTES``,
``DP_BYTES_PER_STATE``, ``BEAM_BYTES_PER_SLOT``, ``SOP_MILP_BYTES`` and
``SOP_MILP_BYTES_PER_NONZERO``, ``SOP_BUILD_BYTES_PER_NONZERO``, ``CPSAT_WORKER_BYTES`` and
``CPSAT_BYTES_PER_NODE_PAIR``) and re-running
the fit after the flow model changes refits the last one.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SHARED = next(
    (
        up / "shared" / "benchmarks" / "tsplib"
        for up in HERE.parents[0:4]
        if (up / "shared" / "benchmarks" / "tsplib").is_dir()
    ),
    HERE.parents[1] / "shared" / "benchmarks" / "tsplib",
)

#: Width of the measured beam pass.
BEAM_WIDTH = 4096

#: Generated instances, 100-380 nodes: rbg-like (chains with cross precedences: dense,
#: thousands of pairs, few ideals) and sparse random precedence (many ideals, large flow
#: models). name -> (function of taopt.sop.generate, args, keywords).
GENERATED: dict[str, tuple[str, tuple, dict]] = {
    "chains-100-3-x0.02": ("chain_sop", (100, 3, 1), {"cross": 0.02}),
    "chains-200-6-x0.02": ("chain_sop", (200, 6, 1), {"cross": 0.02}),
    "chains-380-8-x0.01": ("chain_sop", (380, 8, 1), {"cross": 0.01}),
    "random-100-0.3": ("random_sop", (100, 0.3, 1), {}),
    "random-150-0.05": ("random_sop", (150, 0.05, 1), {}),
    "random-300-0.02": ("random_sop", (300, 0.02, 1), {}),
}

_CHILD = r"""
import json, resource, sys, threading, time
sys.path.insert(0, {here!r})
import taopt, taopt.models, taopt.heuristics
from taopt.orchestration import pipeline
from taopt.runtime import footprint
from taopt.models.sop import column_count, nonzero_count, usable_arcs
from bench_sop_memory import load_any
problem = load_any({name!r})
stage, limit = {stage!r}, {limit!r}
features = dict(n=problem.n, arcs=int(len(usable_arcs(problem.cost, problem.closure)[0])))
if stage in ("milp", "portfolio"):
    features["columns"] = column_count(problem.cost, problem.closure, problem.start)
    features["nonzeros"] = nonzero_count(problem.cost, problem.closure, problem.start)
    if stage == "milp" and features["columns"] > {max_columns!r}:
        print(json.dumps(dict(skipped="columns", **features)))
        sys.exit(0)
estimate = footprint(problem, "exact", {{"time_limit": limit}})[0]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
worker = [0]
def watch():
    import psutil
    me = psutil.Process()
    while True:
        try:
            worker[0] = max([worker[0]] + [c.memory_info().rss for c in me.children(True)])
        except Exception:
            pass
        time.sleep(0.05)
threading.Thread(target=watch, daemon=True).start()
t0 = time.perf_counter()
if stage == "portfolio":
    result = taopt.solve(problem, "exact", time_limit=limit)
elif stage == "dp":
    from taopt.models.sop_dp import solve_sop_dp
    result = solve_sop_dp(problem, limit)
elif stage == "beam":
    from taopt.models.sop_dp import beam_order
    result = beam_order(problem, {beam!r}, limit)
    features["slots"] = {beam!r} * problem.n
elif stage == "milp":
    from taopt.models.sop import solve_sop
    result = solve_sop(problem.cost, problem.precedences, problem.start, problem.end,
                       time_limit=limit, problem=problem)
elif stage == "cpsat":
    result = taopt.solve(problem, "cpsat", time_limit=limit)
wall = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
out = dict(wall=wall, base=base, peak=peak, worker=worker[0], estimate=estimate, **features)
if hasattr(result, "info"):
    info = result.info
    out.update(status=str(result.status), objective=result.objective, bound=result.bound,
               states=max(info.get("states") or 0, info.get("dp_states") or 0),
               engine=info.get("engine"), model=info.get("model"),
               staged=info.get("memory_estimate"), variables=info.get("variables"),
               peak_layer=info.get("peak_layer"), rest=info.get("rest"))
print(json.dumps(out))
"""


def load_any(name: str):
    """A shipped or shared SOP file (by name), or a generated instance of :data:`GENERATED`."""
    from taopt.sop import generate
    from taopt.sop.problem import SopProblem, shipped_sop

    if name in GENERATED:
        func, args, kwargs = GENERATED[name]
        return getattr(generate, func)(*args, **kwargs)
    if name in shipped_sop():
        return SopProblem.load(name)
    return SopProblem.load(SHARED / f"{name}.sop")


def sop_files() -> list[str]:
    """Every SOP file shipped or kept in ``../shared/benchmarks/tsplib``, by size."""
    from taopt.sop.problem import shipped_sop

    names = set(shipped_sop()) | {p.stem for p in SHARED.glob("*.sop")}
    return sorted(names, key=lambda s: (load_any(s).n, s))


def run(name: str, stage: str, limit: float, max_columns: int) -> dict:
    """One stage on one instance in a fresh interpreter; its measurements."""
    code = _CHILD.format(
        here=str(HERE), name=name, stage=stage, limit=limit, beam=BEAM_WIDTH,
        max_columns=max_columns,
    )  # fmt: skip
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE.parent), env.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    if done.returncode != 0:
        tail = done.stderr.strip().splitlines()[-1:] or [f"exit {done.returncode}"]
        return {"name": name, "stage": stage, "failed": tail[0]}
    return {
        "name": name,
        "stage": stage,
        "limit": limit,
        **json.loads(done.stdout.splitlines()[-1]),
    }


def nonzeros(r: dict) -> float:
    """The flow model's nonzeros of a run (counted again for runs saved without them)."""
    if "nonzeros" not in r:
        from taopt.models.sop import nonzero_count

        problem = load_any(r["name"])
        r["nonzeros"] = nonzero_count(problem.cost, problem.closure, problem.start)
    return float(r["nonzeros"])


def feature(r: dict) -> float | None:
    """The unit a stage's memory is fitted on."""
    stage = r["stage"]
    if stage == "dp":
        return float(r.get("states") or 0)
    if stage == "beam":
        return float(r.get("slots") or 0)
    if stage == "milp":  # only runs where HiGHS ran (not a model left uncompiled)
        ran = r.get("model") in (None, "solved", "compiled, not solved")
        return nonzeros(r) if ran else 0.0
    if stage == "milp-build":  # a model built but not compiled
        return nonzeros(r) if r.get("model") == "built, not compiled" else 0.0
    if stage == "cpsat":
        return float(r["n"] * r["n"])
    return None


def fit(runs: list[dict]) -> None:
    """Print the fitted constants (see the module docstring)."""
    bases = sorted(r["base"] for r in runs if "base" in r)
    base = bases[len(bases) // 2]
    print(
        f"base (median of {len(bases)}): {base / 1e6:.0f} MB ({bases[0] / 1e6:.0f}-{bases[-1] / 1e6:.0f})"
    )
    runs = runs + [
        {**r, "stage": "milp-build"}
        for r in runs
        if r.get("stage") == "milp" and r.get("model") == "built, not compiled"
    ]
    for stage in ("dp", "beam", "milp", "milp-build", "cpsat"):
        rows = [r for r in runs if r.get("stage") == stage and "peak" in r]
        if stage == "cpsat":  # the worker's own peak: a fixed part and a part per node pair
            pairs = [(feature(r), r["worker"], 0.0) for r in rows if r["worker"]]
        else:
            pairs = [(feature(r), r["peak"], base) for r in rows]
        pairs = [p for p in pairs if p[0]]
        if not pairs:
            continue
        best = (math.inf, 0.0, 0.0)
        fixed = [0.0] if stage in ("dp", "beam") else [m * 5e6 for m in range(0, 41)]
        for start in fixed:  # the MILP has a fixed part (HiGHS and cvxpy's work space)
            for step in range(0, 2001):
                k = 10 ** (-2 + step * 8 / 2000)  # 0.01 to 1e6 bytes per unit
                worst = max(abs(math.log((b + start + k * f) / peak)) for f, peak, b in pairs)
                best = min(best, (worst, k, start))
        print(
            f"{stage}: {best[1]:,.1f} bytes per unit + {best[2] / 1e6:.0f} MB over {len(pairs)} "
            f"runs; estimate within {math.exp(best[0]):.2f}x of every peak"
        )


def table(runs: list[dict], header: bool = True) -> None:
    """Markdown table of the runs: peak, the stage's model, their ratio."""
    from taopt.models import sop

    per_unit = {
        "dp": sop.DP_BYTES_PER_STATE,
        "beam": getattr(sop, "BEAM_BYTES_PER_SLOT", float("nan")),
    }
    if header:
        print(
            "| instance | n | stage | status | wall (s) | base (MB) | peak (MB) | feature |"
            " estimate (MB) | peak / estimate |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|")
    for r in runs:
        if "failed" in r or "skipped" in r:
            why = r.get("failed") or f"skipped ({r.get('columns', 0):,} columns)"
            print(f"| {r['name']} | {r.get('n', '')} | {r['stage']} | {why} | | | | | | |")
            continue
        unit = feature(r)
        if r["stage"] == "portfolio":
            estimate = r.get("staged") or r["estimate"]
            what = f"a priori {r['estimate'] / 1e6:.0f}"
            peak = r["peak"]
        elif r["stage"] == "cpsat":
            estimate = sop.cpsat_worker_bytes(r["n"])
            what = f"{unit:,.0f} node pairs"
            peak = r["worker"]
        elif r["stage"] == "milp":
            compiled = r.get("model") != "built, not compiled"
            built = r.get("model") != "not built"
            unit = nonzeros(r)
            estimate = sop.BASE_BYTES + (sop.sop_milp_bytes(unit, compiled) if built else 0.0)
            what = f"{unit:,.0f} nonzeros" + ("" if compiled else " (built only)")
            peak = r["peak"]
        else:
            assert unit is not None
            estimate = sop.BASE_BYTES + per_unit[r["stage"]] * unit
            what = f"{unit:,.0f}"
            peak = r["peak"]
        print(
            f"| {r['name']} | {r['n']} | {r['stage']} | {r.get('status', '')} | {r['wall']:.2f} | "
            f"{r['base'] / 1e6:.0f} | {peak / 1e6:.0f} | {what} | {estimate / 1e6:.0f} | "
            f"{peak / estimate:.2f} |",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="instances (default: every SOP file)")
    parser.add_argument("--stages", default="portfolio", help="comma-separated stages")
    parser.add_argument("--time-limit", type=float, default=10.0)
    parser.add_argument("--generated", action="store_true", help="add the generated instances")
    parser.add_argument("--max-columns", type=int, default=300_000)
    parser.add_argument("--out", help="append each run as a JSON line to this file")
    parser.add_argument("--fit", help="fit the constants on the runs saved in this file")
    args = parser.parse_args()
    if args.fit:
        runs = [json.loads(line) for line in Path(args.fit).read_text().splitlines() if line]
        table(runs)
        fit(runs)
        return
    names = args.names or sop_files() + (list(GENERATED) if args.generated else [])
    runs = []
    for name in names:
        for stage in args.stages.split(","):
            r = run(name, stage, args.time_limit, args.max_columns)
            runs.append(r)
            if args.out:
                with open(args.out, "a") as handle:
                    handle.write(json.dumps(r) + "\n")
            table([r], header=len(runs) == 1)
    fit(runs)


if __name__ == "__main__":
    main()
