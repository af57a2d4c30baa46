"""The chapter-6 study (taopt.orchestration.studies.budgeted): levels, a tiny run, its summary and plot."""

from __future__ import annotations

import argparse
import math

import pandas as pd
import pytest

from taopt.errors import InstanceError
from taopt.orchestration.studies import budgeted as study


def test_levels_parse_and_sort():
    """Level names give (s, tau); they sort none, Q loosest first, then T loosest first."""
    assert study.parse_level("none") == (math.inf, math.inf)
    assert study.parse_level("Q1.2T0.8") == (1.2, 0.8)
    levels = ["T0.6", "Q1", "none", "Q2", "T1"]
    assert sorted(levels, key=study.level_order) == ["none", "Q2", "Q1", "T1", "T0.6"]
    for bad in ("Q0.5", "T0", "X1", ""):
        with pytest.raises(InstanceError):
            study.parse_level(bad)
    with pytest.raises(InstanceError):
        study.parse_size("50x10")


def test_scenario_limits_follow_the_level(tmp_path):
    """Q = ceil(s n / m) and T = tau T*, T* the longest route of the unlimited optimum."""
    settings = {"seed": 1, "context": {"cache_dir": str(tmp_path)}}
    key = {"size": "n6m2", "scenario": 0}
    free = study.make_scenario({**key, "level": "none"}, settings)
    tight = study.make_scenario({**key, "level": "Q1T0.5"}, settings)
    assert math.isinf(free.columns["Q"]) and not free.problem.has_capacity
    assert tight.columns["Q"] == 3 and tight.problem.capacity.tolist() == [3.0, 3.0]
    assert tight.columns["T"] == pytest.approx(0.5 * tight.references["T_star"])
    assert free.references == tight.references  # one cached unlimited optimum per scenario


def test_tiny_study_writes_its_csv_and_summary(tmp_path):
    """A 2-scenario run writes budgeted.csv; exact rows are optimal or infeasible; heuristics
    never beat a certified optimum; at tau = 1 the optimum equals the unlimited one."""
    out = tmp_path / "study"
    df = study.budgeted_study(
        ["n6m2"],
        ["none", "Q1", "T1", "T0.7"],
        2,
        methods=["MC", "EVM", "GA", "exact"],
        out_dir=out,
        method_options={"GA": {"population": 20, "generations": 10}},
        progress=False,
    )
    assert (out / "budgeted.csv").exists()
    assert len(pd.read_csv(out / "budgeted.csv")) == 2 * 4 * 4
    exact = df[df["method"] == "exact"]
    assert set(exact["status"]) <= {"optimal", "infeasible"}
    answered = df[df["status"] == "feasible"]
    assert (answered["objective"] >= answered["optimum"] * (1 - 1e-9)).all()
    at_one = exact[exact["level"] == "T1"]
    assert at_one["objective"].to_numpy() == pytest.approx(at_one["f_unlimited"].to_numpy())
    table = study.summarize(df)
    assert list(dict.fromkeys(table["level"])) == ["none", "Q1", "T1", "T0.7"]
    assert (table.loc[table["method"] == "exact", "gap_pct"].fillna(0) == 0).all()
    assert table["no_answer_pct"].dropna().between(0, 100).all()
    figure = study.plot_study(table, path=str(tmp_path / "plot.png"), exclude=("exact",))
    assert (tmp_path / "plot.png").stat().st_size > 0
    assert figure.axes[0].get_ylabel().startswith("true gap")
    assert len(figure.axes) == 3


def test_run_from_arguments(tmp_path, capsys):
    """``run(args)`` (the CLI body) resumes the folder, prints and saves the summary."""
    parser = argparse.ArgumentParser()
    study.add_arguments(parser)
    args = parser.parse_args(
        ["--sizes", "n5m2", "--levels", "none,Q1", "--scenarios", "1", "--methods", "MC,exact"]
    )
    args.out, args.quiet, args.plot = str(tmp_path), True, None
    assert study.run(args) == 0
    assert (tmp_path / "summary.csv").exists()
    assert "MC" in capsys.readouterr().out
