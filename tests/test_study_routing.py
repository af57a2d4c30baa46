"""Chapter 2 gap study: rows are right, the study resumes after an interrupt, CLI and plots."""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.routing.scenarios import drift_scenario, scenario_seed
from taopt.routing.study import drift_study, register_cli, summarize, wilcoxon_pairs

METHODS = "VN,VM,EVN,EVM,MC,GA,exact"
OPTIONS = {"GA": {"generations": 15, "population": 16}}
STABLE = ["scenario", "seed", "method", "objective", "status", "f_a", "valid_bound", "optimum"]


def run(tmp, scenarios=3, jobs=1, **kw):
    return drift_study(
        6,
        2,
        scenarios,
        methods=METHODS,
        seed=1,
        out_dir=tmp,
        jobs=jobs,
        progress=False,
        method_options=OPTIONS,
        **kw,
    )


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    folder = tmp_path_factory.mktemp("full")
    return folder, run(folder)


def test_rows_are_consistent(full):
    _, df = full
    assert len(df) == 3 * 7
    assert set(df["method"]) == set(METHODS.split(","))
    for k, group in df.groupby("scenario"):
        scenario = drift_scenario(6, 2, scenario_seed(1, int(k)), cache_dir=None)
        assert group["seed"].iloc[0] == scenario_seed(1, int(k))
        optimum = group["optimum"].iloc[0]
        exact = group[group["method"] == "exact"].iloc[0]
        assert exact["status"] == "optimal" and exact["objective"] == pytest.approx(optimum)
        # no heuristic beats the proven optimum; the valid bound is below it
        assert (group["objective"] >= optimum * (1 - 1e-9)).all()
        assert group["valid_bound"].iloc[0] <= optimum * (1 + 1e-9)
        # the row's f_a is the thesis's MCGA on this scenario's matrix
        from taopt.routing.bounds import thesis_mcga

        assert group["f_a"].iloc[0] == pytest.approx(thesis_mcga(scenario.problem))
        mc = taopt.heuristics.run("MC", scenario.problem, seed=int(group["seed"].iloc[0]))
        assert group[group["method"] == "MC"]["objective"].iloc[0] == pytest.approx(mc.objective)


def test_resume_after_interrupt(full, tmp_path):
    _, reference = full
    # 1. stop early: only 2 scenarios, then ask for 3
    partial = run(tmp_path, scenarios=2)
    assert partial["scenario"].nunique() == 2
    resumed = run(tmp_path, scenarios=3)
    pd.testing.assert_frame_equal(resumed[STABLE], reference[STABLE])
    # 2. a crash mid-scenario: drop some rows of scenario 1 and leave a torn last line
    csv = tmp_path / "results.csv"
    lines = csv.read_text().splitlines(keepends=True)
    kept = [line for line in lines if not line.startswith("1,")][:-2]  # scenario 2 incomplete too
    torn = lines[-1][: len(lines[-1]) // 2]
    csv.write_text("".join(kept) + torn)
    again = run(tmp_path, scenarios=3)
    pd.testing.assert_frame_equal(again[STABLE], reference[STABLE])
    # nothing duplicated on disk
    on_disk = pd.read_csv(csv)
    assert len(on_disk) == 3 * 7
    assert not on_disk.duplicated(["scenario", "method"]).any()


def test_parallel_same_table(full, tmp_path):
    _, reference = full
    parallel = run(tmp_path, jobs=2)
    pd.testing.assert_frame_equal(parallel[STABLE], reference[STABLE])


def test_summary_and_wilcoxon(full):
    _, df = full
    table = summarize(df)
    assert list(table.index) == METHODS.split(",")
    assert table.loc["exact", "q_exact"] == pytest.approx(1.0)
    assert (table["q_exact"] >= 1 - 1e-9).all()
    assert (table["q_valid"] >= table["q_exact"] - 1e-9).all()
    assert table.loc["exact", "optimal"] == 3
    manual = (df[df.method == "MC"]["objective"] / df[df.method == "MC"]["f_a"]).mean()
    assert table.loc["MC", "q_thesis"] == pytest.approx(manual)
    tests = wilcoxon_pairs(df)
    assert len(tests) == 21
    assert tests["p_value"].between(0, 1).all()


def test_other_settings_in_same_folder_refused(full):
    folder, _ = full
    with pytest.raises(InstanceError, match="n="):
        drift_study(7, 2, 1, methods="MC", seed=1, out_dir=folder, progress=False)
    with pytest.raises(InstanceError, match="unknown method"):
        drift_study(6, 2, 1, methods="MC,XYZ", seed=1, out_dir=folder, progress=False)


def test_cli_and_plots(tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="taopt study")
    register_cli(parser.add_subparsers(dest="command"))
    png = tmp_path / "gaps.png"
    args = parser.parse_args(
        [
            "drift",
            "--n",
            "5",
            "--m",
            "2",
            "--scenarios",
            "2",
            "--methods",
            "MC,EVM,exact",
            "--seed",
            "3",
            "--out",
            str(tmp_path / "cli"),
            "--plot",
            str(png),
            "--no-progress",
        ]
    )
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "q_thesis" in out and "p_value" in out
    assert png.stat().st_size > 1000
    from taopt.routing.plot import plot_routes

    scenario = drift_scenario(5, 2, scenario_seed(3, 0))
    solution = taopt.models.solve_routing(scenario.problem)
    ax = plot_routes(
        scenario.points,
        solution.routes,
        field=scenario.instance.field,
        path=str(tmp_path / "routes.png"),
    )
    assert len(ax.collections) >= 2
    assert np.isfinite(solution.objective)


# -- the resumable CSV (taopt.studyio): method sets, settings, torn lines -----------------------
def small(tmp, methods, scenarios=2, **kw):
    return drift_study(5, 2, scenarios, methods=methods, seed=4, out_dir=tmp, progress=False, **kw)


def test_other_method_set_keeps_earlier_rows(tmp_path):
    first = small(tmp_path, "MC,EVN")
    assert len(first) == 4
    second = small(tmp_path, "MC,VN", scenarios=1)  # MC reused, VN computed, EVN kept on disk
    assert list(second["method"]) == ["VN", "MC"]
    on_disk = pd.read_csv(tmp_path / "results.csv")
    assert len(on_disk) == 5 and (on_disk["complete"] == 1).all()
    assert sorted(on_disk["method"]) == ["EVN", "EVN", "MC", "MC", "VN"]
    pd.testing.assert_frame_equal(small(tmp_path, "MC,EVN"), first)  # nothing recomputed
    mc = first[first.method == "MC"].iloc[[0]].reset_index(drop=True)
    pd.testing.assert_frame_equal(second[second.method == "MC"].reset_index(drop=True), mc)


def test_exact_added_later_fills_the_optimum(tmp_path):
    """Scenario references are the same whether exact ran with the heuristics or later."""
    small(tmp_path / "later", "MC")
    later = small(tmp_path / "later", "MC,exact")
    together = small(tmp_path / "together", "MC,exact")
    pd.testing.assert_frame_equal(later[STABLE], together[STABLE])
    assert later["optimum"].notna().all()


@pytest.mark.parametrize(
    "change, key",
    [
        ({"seed": 5}, "seed"),
        ({"time_limit": 30.0}, "time_limit"),
        ({"method_options": {"GA": {"generations": 3}}}, "method_options"),
        ({"field": None}, "field"),
    ],
)
def test_other_settings_refused_naming_the_key(tmp_path, change, key):
    drift_study(5, 2, 0, methods="MC", seed=4, out_dir=tmp_path, progress=False)
    kwargs = {"methods": "MC", "seed": 4, "out_dir": tmp_path, "progress": False, **change}
    with pytest.raises(InstanceError, match=rf"{key}=.* there, {key}=.* now"):
        drift_study(5, 2, 1, **kwargs)
    assert not (tmp_path / "matrices").exists()  # refused before any work


@pytest.mark.parametrize("cut", ["mid-number", "after-field"])
def test_torn_last_line_recomputed(tmp_path, cut):
    reference = small(tmp_path / "ref", "MC,EVN")
    folder = tmp_path / "torn"
    small(folder, "MC,EVN")
    csv = folder / "results.csv"
    text = csv.read_text()
    last = text.splitlines()[-1]
    fields = last.split(",")
    if cut == "mid-number":  # inside the objective value
        torn = ",".join(fields[:5]) + "," + fields[5][:4]
    else:  # just after the status field and its comma
        torn = ",".join(fields[:8]) + ","
    csv.write_text(text[: len(text) - len(last) - 1] + torn)
    resumed = small(folder, "MC,EVN")
    pd.testing.assert_frame_equal(resumed[STABLE], reference[STABLE])
    resumed = small(folder, "MC,EVN", scenarios=3)  # the next appended rows are intact
    lines = csv.read_text().splitlines()
    assert len(lines) == 1 + 6
    assert all(len(line.split(",")) == 13 and line.endswith(",1") for line in lines[1:])
    assert resumed["scenario"].nunique() == 3
