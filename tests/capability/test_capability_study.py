"""The chapter 3 study on the one runner: rows, references, resumption, tables, CLI."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from taopt.errors import InstanceError
from taopt.orchestration.cli import main
from taopt.orchestration.studies.capability import (
    SPEC,
    capability_study,
    make_scenario,
    parse_instance,
    plot_figures,
    summarize,
    thesis_comparison,
    thesis_table,
)

OPTIONS = {"GA": {"generations": 20}}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """n7m3 with |A| in {1, 3}, 2 scenarios, DTAA, GA (20 generations) and exact."""
    out = tmp_path_factory.mktemp("capability")
    df = capability_study(
        instances=("n7m3",),
        capabilities=(1, 3),
        scenarios=2,
        methods=("DTAA", "GA", "exact"),
        out_dir=out,
        method_options=OPTIONS,
        progress=False,
    )
    return out, df


def test_rows_and_references(study):
    """One row per (scenario, method); heuristics never below the certified optimum."""
    _, df = study
    assert len(df) == 2 * 2 * 3
    assert (df.loc[df["method"] == "exact", "status"] == "optimal").all()
    assert np.allclose(df.loc[df["method"] == "exact", "q_exact"], 1.0)
    assert (df["q_exact"] >= 1 - 1e-9).all()
    assert (df["valid_bound"] <= df["optimum"] * (1 + 1e-9)).all()
    assert (df["optimum"] <= df["f_da"] * (1 + 1e-9)).all()  # Lemma 3.6 (grid: metric)
    dtaa = df[df["method"] == "DTAA"]
    assert (dtaa["rounds"] > 0).all() and (dtaa["bytes"] > 0).all()
    assert df.loc[df["method"] == "exact", "rounds"].isna().all()


def test_scenarios_are_deterministic():
    """make_scenario depends only on the key and the settings."""
    key = {"n": 6, "m": 3, "A": 2, "scenario": 4}
    settings = {"seed": 1, "cell": 10.0, "neighbours": 16}
    a, b = make_scenario(key, settings), make_scenario(dict(key), dict(settings))
    np.testing.assert_array_equal(a.problem.cost, b.problem.cost)
    assert a.references == b.references and a.columns == b.columns
    other = make_scenario({**key, "scenario": 5}, settings)
    assert other.columns["scenario_seed"] != a.columns["scenario_seed"]
    assert SPEC.key_columns == ("n", "m", "A", "scenario")
    assert len(set(SPEC.columns)) == len(SPEC.columns)  # no scenario column shadows "seed"


def test_resume_adds_nothing_and_refuses_other_settings(study):
    """A second identical call computes no new rows; other settings are refused."""
    out, df = study
    again = capability_study(
        instances=("n7m3",),
        capabilities=(1, 3),
        scenarios=2,
        methods=("DTAA", "GA", "exact"),
        out_dir=out,
        method_options=OPTIONS,
        progress=False,
    )
    pd.testing.assert_frame_equal(
        again[["objective", "runtime"]], df[["objective", "runtime"]], check_exact=True
    )
    with pytest.raises(InstanceError):
        capability_study(
            instances=("n7m3",),
            capabilities=(1,),
            scenarios=1,
            methods=("DTAA",),
            out_dir=out,
            cell=5.0,
            progress=False,
        )


def test_tables_and_figures(study, tmp_path):
    """summarize / thesis_table / thesis_comparison shapes; the figure is written."""
    _, df = study
    table = summarize(df)
    assert set(table.index.get_level_values("method")) == {"DTAA", "GA", "exact"}
    assert (table["scenarios"] == 2).all()
    q = thesis_table(df, "q_thesis")
    assert list(q.columns) == [1, 3] and len(q) == 3
    comparison = thesis_comparison(df, "3.2")
    assert "thesis" in comparison.index.get_level_values("source")
    path = tmp_path / "fig.png"
    plot_figures(df, path=str(path))
    assert path.stat().st_size > 1000


def test_bad_arguments():
    """Bad instance names and |A| > m are refused before anything runs."""
    assert parse_instance("n50m10") == (50, 10)
    with pytest.raises(InstanceError, match="nNmM"):
        parse_instance("50x10")
    with pytest.raises(InstanceError, match=r"\|A\| must be an integer in 1..m = 3"):
        capability_study(instances=("n5m3",), capabilities=(4,), scenarios=1, out_dir="unused")


def test_cli_runs_the_study(tmp_path, capsys):
    """`taopt study capability` prints the summary and Tables 3.1-3.2 beside the thesis."""
    code = main(
        [
            "study",
            "capability",
            "--sizes",
            "n5m2",
            "--capabilities",
            "1,2",
            "--scenarios",
            "1",
            "--methods",
            "DTAA,exact",
            "--out",
            str(tmp_path),
            "--quiet",
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "Table 3.1, thesis beside taopt" in out and "DTAA" in out
    assert (tmp_path / "capability.csv").exists() and (tmp_path / "summary.csv").exists()


def test_markdown_report(study):
    """The doc's tables render from the rows: every section, thesis rows beside ours."""
    from taopt.orchestration.studies.capability import markdown_report

    _, df = study
    text = markdown_report(df)
    for title in ("Mean q = f / f^a", "true ratio f / f^o", "Table 3.1", "Table 3.2", "DTAA"):
        assert title in text
    assert "| n7m3 | DTAA |" in text and "| n50m10 | GA | thesis |" in text
