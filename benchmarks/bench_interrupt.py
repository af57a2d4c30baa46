"""How fast Ctrl-C stops `taopt solve`, `verify`, `simulate` and `claims` (issue 15, item 8).

Run from the repository root::

    python benchmarks/bench_interrupt.py              # SIGINT 3 s after the command starts
    python benchmarks/bench_interrupt.py --delay 1.5

Each command runs as a subprocess (as the ``taopt`` script, SIGINT at its default), on a
problem that would run for minutes: the delivery MILP on 10 customers (cvxpy's HiGHS
object), the DFJ loop on 250 targets (the persistent HighsModel), ``verify --exact`` on 18
customers (the MILP), ``claims`` over 100,000 samples and ``simulate`` of 1,500 targets
(pure Python). SIGINT is sent ``--delay`` seconds after the heavy imports are done; the
time until the process has exited is printed with its exit code and stderr. The bar:
within 2 s, exit code 130, the one line ``taopt COMMAND: interrupted``.
"""

from __future__ import annotations

import argparse
import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

LAUNCH = "import sys, taopt.orchestration.cli, taopt.orchestration.solving\nprint('ready', flush=True)\nsys.exit(taopt.orchestration.cli.main())\n"


def delivery_file(folder: Path, n: int) -> Path:
    from taopt.delivery.dags import layered_dag
    from taopt.delivery.instance import DeliveryInstance

    rng = np.random.default_rng(0)
    customers = rng.uniform(0, 1000, size=(n, 2))
    pairs = layered_dag(n, layers=3, density=0.2, seed=rng)
    instance = DeliveryInstance.grid(
        customers, 11, 1000.0, v_drone=1.0, v_truck=1.0, flight_range=300.0,
        precedences=pairs, name=f"delivery-{n}",
    )  # fmt: skip
    path = folder / f"delivery{n}.json"
    instance.save(path)
    return path


def cases(folder: Path) -> dict[str, list[str]]:
    import taopt
    from taopt.comm import CommProblem
    from taopt.delivery.instance import DeliveryInstance

    d10, d18 = delivery_file(folder, 10), delivery_file(folder, 18)
    plan = taopt.solve(DeliveryInstance.load(d18), "NIA")
    plan.replace(status="optimal", bound=plan.objective).save(folder / "nia.json")
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 100, size=(254, 2))
    cost = np.linalg.norm(points[:, None] - points[None], axis=2).round(1)
    data = {"schema_version": 1, "kind": "assignment_problem", "n_targets": 250,
            "cost": cost.tolist()}  # fmt: skip
    (folder / "assignment.json").write_text(json.dumps(data))
    rng = np.random.default_rng(1)
    CommProblem(
        rng.uniform(0, 3000, (1500, 2)).tolist(), rng.uniform(0, 3000, (12, 2)).tolist(),
        ["a"] * 1500, ["a"] * 12, 300.0,
    ).save(folder / "comm.json")  # fmt: skip
    return {
        "solve, delivery MILP (cvxpy's HiGHS)": ["solve", str(d10), "--methods", "exact"],
        "solve, DFJ loop (HighsModel)": [
            "solve",
            str(folder / "assignment.json"),
            "--methods",
            "exact",
        ],  # fmt: skip
        "verify --exact, 18 customers": ["verify", str(folder / "nia.json"), str(d18), "--exact"],
        "claims": ["claims", "--samples", "100000"],
        "simulate": ["simulate", str(folder / "comm.json")],
    }


def interrupt(folder: Path, args: list[str], delay: float) -> tuple[int, str, float]:
    process = subprocess.Popen(
        [sys.executable, "-c", LAUNCH, *args, "--quiet"] if args[0] == "solve" else
        [sys.executable, "-c", LAUNCH, *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=folder,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    assert process.stdout.readline().strip() == "ready"
    time.sleep(delay)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    return process.returncode, err.strip(), time.monotonic() - sent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--delay", type=float, default=3.0, help="seconds before SIGINT")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, argv in cases(folder).items():
            code, err, seconds = interrupt(folder, argv, args.delay)
            print(f"{name:40s} exit {code} after {seconds:.2f} s  stderr {err!r}", flush=True)


if __name__ == "__main__":
    main()
