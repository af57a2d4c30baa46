"""Chapter 2 gap study: rows are right, the study resumes after an interrupt, CLI and plots."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.orchestration.cli import main
from taopt.orchestration.studies.drift import SPEC, drift_study, summarize, wilcoxon_pairs
from taopt.routing.scenarios import drift_scenario, scenario_seed

METHODS = "VN,VM,EVN,EVM,MC,GA,exact"
OPTIONS = {"GA": {"generations": 15, "population": 16}}
COLUMNS = SPEC.columns
STABLE = ["scenario", "seed", "method", "objective", "status", "f_a", "valid_bound", "optimum"]
CSV = "drift.csv"


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
    """Each row's references are its scenario's; no heuristic beats the proven optimum."""
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
    """A study stopped early, or cut mid-write, resumes to the same table."""
    _, reference = full
    # 1. stop early: only 2 scenarios, then ask for 3
    partial = run(tmp_path, scenarios=2)
    assert partial["scenario"].nunique() == 2
    resumed = run(tmp_path, scenarios=3)
    pd.testing.assert_frame_equal(resumed[STABLE], reference[STABLE])
    # 2. a crash mid-scenario: drop some rows of scenario 1 and leave a torn last line
    csv = tmp_path / CSV
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
    """Two workers give the same rows as one."""
    _, reference = full
    parallel = run(tmp_path, jobs=2)
    pd.testing.assert_frame_equal(parallel[STABLE], reference[STABLE])


def test_summary_and_wilcoxon(full):
    """Table 2.1's means and the pairwise Wilcoxon tests are computed from the rows."""
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
    """A folder of other settings is refused; an unknown method is named."""
    folder, _ = full
    with pytest.raises(InstanceError, match="n="):
        drift_study(7, 2, 1, methods="MC", seed=1, out_dir=folder, progress=False)
    with pytest.raises(InstanceError, match="no method 'XYZ'"):
        drift_study(6, 2, 1, methods="MC,XYZ", seed=1, out_dir=folder, progress=False)


def test_cli_and_plots(tmp_path, capsys):
    """`taopt study drift` prints the summary and the tests and writes the plot."""
    png = tmp_path / "gaps.png"
    argv = ["study", "drift", "--sizes", "n5m2", "--scenarios", "2"]
    argv += ["--methods", "MC,EVM,exact", "--seed", "3", "--out", str(tmp_path / "cli")]
    argv += ["--plot", str(png), "--quiet"]
    assert main(argv) == 0
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


# -- the resumable CSV (taopt.orchestration.studyio): method sets, settings, torn lines -----------------------
def small(tmp, methods, scenarios=2, **kw):
    return drift_study(5, 2, scenarios, methods=methods, seed=4, out_dir=tmp, progress=False, **kw)


def test_other_method_set_keeps_earlier_rows(tmp_path):
    """Asking for other methods extends the file; earlier rows are never lost."""
    first = small(tmp_path, "MC,EVN")
    assert len(first) == 4
    second = small(tmp_path, "MC,VN", scenarios=1)  # MC reused, VN computed, EVN kept on disk
    assert list(second["method"]) == ["MC", "VN"]  # in the order asked for
    on_disk = pd.read_csv(tmp_path / CSV)
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
    """Other settings on a folder with rows are refused, naming the key, before any work."""
    drift_study(5, 2, 1, methods="MC", seed=4, out_dir=tmp_path, progress=False)
    (tmp_path / "matrices").rename(tmp_path / "matrices-first")
    kwargs = {"methods": "MC", "seed": 4, "out_dir": tmp_path, "progress": False, **change}
    with pytest.raises(InstanceError, match=rf"{key}=.* there, {key}=.* now"):
        drift_study(5, 2, 1, **kwargs)
    assert not (tmp_path / "matrices").exists()  # refused before any work


@pytest.mark.parametrize("cut", ["mid-number", "after-field"])
def test_torn_last_line_recomputed(tmp_path, cut):
    """A line torn by a crash is dropped and recomputed; later appends stay intact."""
    reference = small(tmp_path / "ref", "MC,EVN")
    folder = tmp_path / "torn"
    small(folder, "MC,EVN")
    csv = folder / CSV
    text = csv.read_text()
    last = text.splitlines()[-1]
    fields = last.split(",")
    at = COLUMNS.index("objective")
    if cut == "mid-number":  # inside the objective value
        torn = ",".join(fields[:at]) + "," + fields[at][:4]
    else:  # just after the status field and its comma
        torn = ",".join(fields[: at + 2]) + ","
    csv.write_text(text[: len(text) - len(last) - 1] + torn)
    resumed = small(folder, "MC,EVN")
    pd.testing.assert_frame_equal(resumed[STABLE], reference[STABLE])
    resumed = small(folder, "MC,EVN", scenarios=3)  # the next appended rows are intact
    lines = csv.read_text().splitlines()
    assert len(lines) == 1 + 6
    assert all(len(line.split(",")) == len(COLUMNS) + 1 for line in lines[1:])
    assert all(line.endswith(",1") for line in lines[1:])
    assert resumed["scenario"].nunique() == 3
