"""The one study runner: executors agree, bad arguments write nothing, Ctrl-C leaves nothing."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from taopt.errors import InstanceError
from taopt.fields import UniformField
from taopt.orchestration.studies.capability import capability_study
from taopt.orchestration.studies.delivery import delivery_study
from taopt.orchestration.studies.drift import drift_study
from taopt.orchestration.study import DASK_CONNECT_TIMEOUT
from taopt.orchestration.studyio import LOCK, StudyLocked, folder_lock

FIELD = UniformField(0.3, 0.1)  # closed-form travel times: scenarios are cheap
METHODS = "MC,EVM,GA,exact"
OPTIONS = {"GA": {"generations": 10, "population": 12}}


def small(out: Path, **kw) -> pd.DataFrame:
    args = dict(methods=METHODS, seed=2, out_dir=out, progress=False, field=FIELD)
    args.update(method_options=OPTIONS)
    args.update(kw)
    return drift_study(7, 2, 3, **args)


def stable(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=["runtime"]).reset_index(drop=True)


def test_jobs_and_dask_give_identical_rows(tmp_path):
    """--jobs 1, --jobs 2 and a local Dask cluster give the same rows, timing aside."""
    one = small(tmp_path / "one", jobs=1)
    two = small(tmp_path / "two", jobs=2)
    dask = small(tmp_path / "dask", jobs=2, dask="local")
    pd.testing.assert_frame_equal(stable(one), stable(two))
    pd.testing.assert_frame_equal(stable(one), stable(dask))
    assert (one.loc[one.method == "exact", "status"] == "optimal").all()


@pytest.mark.parametrize(
    "change, message",
    [
        ({"time_limit": -1.0}, "time_limit must be a positive"),
        ({"jobs": 0}, "jobs must be an integer >= 1"),
        ({"methods": "MC,NOPE"}, "no method 'NOPE'"),
        ({"method_options": {"GA": {"colour": "red"}}}, "does not take option"),
    ],
)
def test_invalid_arguments_write_nothing(tmp_path, change, message):
    """A refused call leaves no folder behind (issue: a config was written first)."""
    out = tmp_path / "study"
    with pytest.raises(InstanceError, match=message):
        small(out, **change)
    assert not out.exists()


def _closed_port() -> int:
    """A local TCP port nothing listens on."""
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _capability(out: Path, **kw):
    args = dict(instances=["n3m2"], capabilities=[1], scenarios=1, methods="MC", out_dir=out)
    return capability_study(**{**args, **kw})


@pytest.mark.parametrize(
    "run, message",
    [
        (lambda out: small(out, method_options={"GA": {"generations": -1}}),
         r"method 'GA' option 'generations' must be an integer >= 0, got -1"),
        (lambda out: delivery_study("small", 1, [0.3], ["NIA"], out_dir=out, vd_ratio=0),
         r"vd_ratio must be a positive finite number, got 0"),
        (lambda out: delivery_study("small", 1, [0.3], ["NIA"], out_dir=out, vd_ratio=-1),
         r"vd_ratio must be a positive finite number, got -1"),
        (lambda out: _capability(out, cell=0), r"cell must be a positive finite number, got 0"),
        (lambda out: _capability(out, cell=-10), r"cell must be a positive finite number, got -10"),
        (lambda out: _capability(out, capabilities="1,x"),
         r"capabilities: 'x' is not an integer"),
        (lambda out: small(out, dask=f"tcp://127.0.0.1:{_closed_port()}"),
         r"no Dask scheduler at tcp://127\.0\.0\.1:\d+ .*nothing written"),
    ],
    ids=["ga-generations", "vd-ratio-0", "vd-ratio-neg", "cell-0", "cell-neg", "capabilities",
         "dask-unreachable"],
)  # fmt: skip
def test_the_six_invalid_arguments_write_nothing(tmp_path, run, message):
    """--ga-generations -1, --vd-ratio 0/-1, --cell 0/-10, --capabilities x and an unreachable
    --dask address are refused by name, quickly, before any folder is created."""
    out = tmp_path / "study"
    with pytest.raises(InstanceError, match=message) as refused:
        run(out)
    if "Dask" in message:  # the probe waits DASK_CONNECT_TIMEOUT (5 s) at most, and says so
        assert DASK_CONNECT_TIMEOUT <= 5
        assert f"within {DASK_CONNECT_TIMEOUT:g} s" in str(refused.value)
    assert list(tmp_path.iterdir()) == []


def never_wait(seconds: float) -> None:
    """Stands in for time.sleep where a refusal must come at once: any wait fails the test."""
    raise AssertionError(f"waited {seconds} s instead of refusing at once")


def test_second_study_on_a_folder_in_use_is_refused(tmp_path, monkeypatch):
    """While another run holds the folder, a study needing to write is refused at once with
    the folder and the holder's pid, and writes no row."""
    out = tmp_path / "study"
    with folder_lock(out):
        with monkeypatch.context() as patch:
            patch.setattr(time, "sleep", never_wait)  # refused at once: it never waits
            with pytest.raises(StudyLocked, match=rf"{out} is in use by another study \(pid "):
                small(out, methods="MC")
        assert not (out / "drift.csv").exists()
    assert len(small(out, methods="MC")) == 3  # free again: the same call runs


def test_finished_folder_is_read_without_writing(tmp_path, monkeypatch):
    """Re-running a finished study only reads: no lock is taken, no file changes, and the
    rows come back (so a read-only folder can be reported on)."""
    out = tmp_path / "study"
    first = small(out, methods="MC,EVM")
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert LOCK in before  # the writing run held the lock

    def no_lock(folder):
        raise AssertionError("a finished folder must not be locked")

    monkeypatch.setattr("taopt.orchestration.study.folder_lock", no_lock)
    again = small(out, methods="MC,EVM")
    pd.testing.assert_frame_equal(stable(first), stable(again))
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes through read-only permissions")
def test_read_only_finished_folder_can_be_reported_on(tmp_path):
    """chmod a-w on a finished folder: the same call still returns its rows."""
    out = tmp_path / "study"
    first = small(out, methods="MC")
    for path in [*out.rglob("*"), out]:
        path.chmod(path.stat().st_mode & ~0o222)
    try:
        pd.testing.assert_frame_equal(stable(first), stable(small(out, methods="MC")))
    finally:
        for path in [out, *out.rglob("*")]:
            path.chmod(path.stat().st_mode | 0o200)


def test_zero_scenarios_is_a_clear_error(tmp_path):
    """--scenarios 0 is refused by name, before anything is written."""
    out = tmp_path / "study"
    with pytest.raises(InstanceError, match="scenarios must be an integer >= 1"):
        drift_study(7, 2, 0, methods="MC", out_dir=out, progress=False, field=FIELD)
    assert not out.exists()


def test_settings_of_an_empty_folder_are_replaced(tmp_path):
    """A folder holding a config but no rows takes the new settings."""
    out = tmp_path / "study"
    out.mkdir()
    (out / "drift.config.json").write_text('{"n": 99}')
    df = small(out, methods="MC")
    assert len(df) == 3


def _descendants(pid: int) -> set[int]:
    found, todo = set(), [pid]
    while todo:
        parent = todo.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            children = (
                (task / "children").read_text().split() if (task / "children").exists() else []
            )
            for child in map(int, children):
                if child not in found:
                    found.add(child)
                    todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize(
    "mode",
    [
        pytest.param(["--jobs", "1"], id="jobs1"),  # the fast equivalent in the default run
        pytest.param(["--jobs", "2"], marks=pytest.mark.slow, id="jobs2"),
        pytest.param(["--jobs", "2", "--dask", "local"], marks=pytest.mark.slow, id="dask"),
    ],
)
def test_sigint_stops_cleanly_and_the_folder_resumes(tmp_path, mode):
    """Ctrl-C stops the study (one line, exit 130), leaves no process, and a re-run resumes.

    The stop latency is measured in benchmarks/bench_study.py; here the rows written (fewer
    than the 400 scenarios) separate "stopped" from "ran on to the end", without a clock. The scenarios are small (8 targets in a
    uniform drift, 30 GA generations: ~0.1 s each) and the signal comes after the first row,
    so the cost is mostly two interpreter starts; the resume runs in this process.
    """
    out = tmp_path / "study"
    argv = [
        sys.executable,
        "-m",
        "taopt.orchestration.cli",
        "study",
        "drift",
        "--sizes",
        "n8m2",
    ]
    argv += ["--scenarios", "400", "--methods", "GA", "--ga-generations", "30"]
    argv += ["--field", "uniform:0.3,0.1", "--out", str(out), "--quiet", *mode]
    # outside the checkout: `python -m` puts the working folder first on sys.path
    process = subprocess.Popen(
        argv,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        # as from a terminal, even when pytest itself runs in the background with SIGINT
        # ignored (a study keeps an inherited SIG_IGN, as `nohup ... &` users expect)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    csv = out / "drift.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:  # wait for the first finished row
        if csv.exists() and len(csv.read_text().splitlines()) > 1:
            break
        assert process.poll() is None, process.communicate()
        time.sleep(0.2)
    children = _descendants(process.pid)
    assert children, "the study runs its tasks in worker processes"
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)  # a hang guard, not a measurement
    assert process.returncode == 130, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "interrupted" in lines[0] and "resume" in lines[0], err
    gone_by = time.monotonic() + 1.0  # the workers are killed, then reaped: within 1 s
    while any(_alive(pid) for pid in children) and time.monotonic() < gone_by:
        time.sleep(0.05)
    left = [pid for pid in children if _alive(pid)]
    for pid in left:  # do not leak them into the rest of the test run
        os.kill(pid, signal.SIGKILL)
    assert not left, f"processes left behind: {left}"
    done = pd.read_csv(csv)
    assert 0 < len(done) < 400 and (done["complete"] == 1).all()  # stopped, not run to the end
    # the same command resumes: here with a smaller count, so that it finishes quickly, and
    # in this process (the command line is the same; only the interpreter start is saved)
    from taopt.orchestration.cli import main

    total = len(done) + 1
    rerun = argv[: argv.index("--scenarios") + 1] + [str(total)] + argv[argv.index("400") + 1 :]
    assert main(rerun[3:]) == 0
    again = pd.read_csv(csv)
    assert sorted(again["scenario"]) == list(range(total))  # finished rows kept, one added
