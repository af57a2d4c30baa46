"""Study runner: how fast Ctrl-C stops a study in each mode, and the rows per second.

Run from the repository root::

    python benchmarks/bench_study.py            # 3 tries per mode

For each mode (``--jobs 1``, ``--jobs 2``, ``--jobs 2 --dask local``) a long chapter 2 study
(GA on n30m4, uniform current) is started as a subprocess; SIGINT is sent once rows are
being written, and the time until the process has exited (and every worker with it) is
measured. The issue's bar: within 2 s, no process left behind.
"""

from __future__ import annotations

import argparse
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MODES = {
    "jobs1": ["--jobs", "1"],
    "jobs2": ["--jobs", "2"],
    "dask": ["--jobs", "2", "--dask", "local"],
}


def children(pid: int) -> set[int]:
    found, todo = set(), [pid]
    while todo:
        parent = todo.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            path = task / "children"
            for child in map(int, path.read_text().split() if path.exists() else []):
                if child not in found:
                    found.add(child)
                    todo.append(child)
    return found


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def one(mode: list[str]) -> tuple[float, int, int]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "study"
        argv = [
            sys.executable,
            "-m",
            "taopt.orchestration.cli",
            "study",
            "drift",
            "--sizes",
            "n30m4",
        ]
        argv += ["--scenarios", "400", "--methods", "GA", "--out", str(out), "--quiet", *mode]
        process = subprocess.Popen(
            argv,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            cwd=tmp,
            # as from a terminal: a benchmark started in the background (nohup, `&` in a
            # script) inherits an ignored SIGINT, and a study keeps what it inherits
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        csv = out / "drift.csv"
        while not (csv.exists() and len(csv.read_text().splitlines()) > 2):
            time.sleep(0.05)
        kids = children(process.pid)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        process.wait()
        while any(alive(p) for p in kids) and time.monotonic() - sent < 30:
            time.sleep(0.01)
        stopped = time.monotonic() - sent
        left = sum(alive(p) for p in kids)
        return stopped, left, process.returncode


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tries", type=int, default=3)
    args = parser.parse_args()
    for name, mode in MODES.items():
        results = [one(mode) for _ in range(args.tries)]
        times = [r[0] for r in results]
        print(
            f"{name:6s} SIGINT -> exited with every worker gone: median {statistics.median(times):.2f} s, "
            f"max {max(times):.2f} s; processes left: {sum(r[1] for r in results)}; "
            f"exit codes {[r[2] for r in results]}"
        )


if __name__ == "__main__":
    main()
