"""What a newcomer sees on a fresh machine: only taopt's own lines, and the checkout imports whole."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT

# Lines that no taopt command writes: solver banners and licence notices.
FOREIGN = re.compile(r"Running HiGHS|Copyright|THIRD_PARTY|licen[cs]e terms", re.I)


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``taopt ARGS`` in a fresh interpreter (a new process builds its first HiGHS object)."""
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from taopt.orchestration.cli import main; sys.exit(main())",
            *args,
        ],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def foreign_lines(stdout: str) -> list[str]:
    """The lines of ``stdout`` that a solver or a library wrote, not taopt."""
    return [line for line in stdout.splitlines() if FOREIGN.search(line)]


@pytest.mark.parametrize("quiet", [False, True])
def test_demo_prints_only_taopt_lines(tmp_path: Path, quiet: bool):
    """`taopt demo` (quiet or not) prints its tables and no solver banner."""
    done = run_cli("demo", *(["--quiet"] if quiet else []), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "exact" in done.stdout and "optimal" in done.stdout
    assert foreign_lines(done.stdout) == []


def test_solve_verify_and_study_print_only_taopt_lines(tmp_path: Path, assignment_example_file):
    """`taopt solve`, `verify` and a small study write no line of HiGHS's on stdout."""
    problem = assignment_example_file
    solved = run_cli("solve", str(problem), "--out", str(tmp_path / "sols"), cwd=tmp_path)
    assert solved.returncode == 0, solved.stderr
    assert foreign_lines(solved.stdout) == []
    verified = run_cli(
        "verify", str(tmp_path / "sols" / "exact.json"), str(problem), "--exact", cwd=tmp_path
    )
    assert verified.returncode == 0, verified.stderr
    assert foreign_lines(verified.stdout) == []
    study = run_cli(
        "study", "delivery", "--setup", "small", "--scenarios", "1", "--methods", "NIA,exact",
        "--ratios", "0.5", "--out", str(tmp_path / "study"), "--quiet", cwd=tmp_path,
    )  # fmt: skip
    assert study.returncode == 0, study.stderr
    assert foreign_lines(study.stdout) == []


def test_first_highs_object_prints_nothing(capfd):
    """A HiGHS object made by taopt prints nothing, whatever the highspy version."""
    code = (
        "import taopt.models.highs as h; h.new_highs(); "
        "import cvxpy as cp; x = cp.Variable(integer=True); "
        "cp.Problem(cp.Minimize(x), [x >= 1.5]).solve(solver=cp.HIGHS); print(x.value)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["2.0"]


def test_checkout_root_imports_the_whole_package():
    """Python started in the checkout root imports taopt.models and taopt.heuristics from the tree."""
    code = (
        "import taopt, taopt.models, taopt.heuristics; "
        "print(taopt.__file__); print(taopt.models.__file__); print(taopt.heuristics.__file__)"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120, env=env
    )
    assert done.returncode == 0, done.stderr
    files = [Path(line).resolve() for line in done.stdout.split()]
    assert files == [
        (ROOT / "taopt" / "__init__.py").resolve(),
        (ROOT / "models" / "__init__.py").resolve(),
        (ROOT / "heuristics" / "__init__.py").resolve(),
    ]


def test_models_and_heuristics_are_links_to_the_top_level_folders():
    """taopt/models and taopt/heuristics are symbolic links to the design card's top-level folders."""
    for name in ("models", "heuristics"):
        link = ROOT / "taopt" / name
        assert link.is_symlink(), f"taopt/{name} must be a symbolic link to ../{name}"
        assert link.resolve() == (ROOT / name).resolve()
