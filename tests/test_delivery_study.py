"""The chapter 5 study runner on a tiny setup, including resume and the CLI."""

from __future__ import annotations

import argparse

import pandas as pd
import pytest

from taopt.delivery.study import delivery_study, register_cli, study_instance, summarize


def test_study_instance_servable_at_the_smallest_ratio():
    for setup in ("dag40", "pairs120"):
        inst = study_instance(setup, 0, seed=1, ratio=0.15)
        assert inst.s == 121 and inst.flight_range == 150.0
        assert 2 * inst.flight_distance.min(axis=1).max() <= 150.0  # <= 2 * 70.7 m
    a, b = study_instance("dag40", 3, seed=1, ratio=0.3), study_instance("dag40", 3, 1, 0.9)
    assert (a.customers == b.customers).all() and a.precedences == b.precedences


def test_small_study_resumes_and_checks(tmp_path):
    kwargs = dict(instances=2, ratios=(0.15, 0.6), seed=2, out_dir=tmp_path, progress=False)
    first = delivery_study("small", methods=("NIA", "DP"), **kwargs)
    assert len(first) == 2 * 2 * 2
    csv = tmp_path / "delivery_small.csv"
    assert len(pd.read_csv(csv)) == 8
    # re-run with one more method: only the 4 new rows are computed, old rows kept as is
    second = delivery_study("small", methods=("NIA", "MMA", "DP"), jobs=2, **kwargs)
    assert len(second) == 12 and len(pd.read_csv(csv)) == 12
    old = second[second.method != "MMA"].reset_index(drop=True)
    pd.testing.assert_frame_equal(old, first.reset_index(drop=True), check_dtype=False)
    # a complete re-run computes nothing
    third = delivery_study("small", methods=("NIA", "MMA", "DP"), **kwargs)
    assert len(third) == 12 and len(pd.read_csv(csv)) == 12
    # properties: bound <= optimum <= every method; the DP attains the optimum
    assert (second.bound <= second.optimum + 1e-9).all()
    assert (second.makespan >= second.optimum - 1e-9).all()
    dp = second[second.method == "DP"]
    assert dp.gap_to_optimum.abs().max() < 1e-9
    assert (second.q >= 1 - 1e-12).all()
    table = summarize(second)
    assert set(table.index.get_level_values("method")) == {"NIA", "MMA", "DP"}
    assert table.loc[("DP", 0.15), "gap_mean"] == pytest.approx(0.0, abs=1e-9)


def test_cli_registration(tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="taopt")
    sub = parser.add_subparsers(dest="command")
    register_cli(sub)
    args = parser.parse_args(
        ["study", "delivery", "--setup", "small", "--methods", "NIA,DP", "--vd-ratio", "1.4"]
    )
    assert args.setup == "small" and args.vd_ratio == 1.4 and callable(args.handler)
    args = parser.parse_args(
        [
            "study",
            "delivery",
            "--setup",
            "small",
            "--instances",
            "1",
            "--ratios",
            "0.3",
            "--methods",
            "NIA,DP",
            "--out",
            str(tmp_path),
            "--quiet",
        ]
    )
    assert args.handler(args) == 0
    out = capsys.readouterr().out
    assert "average q" in out and "gap to the optimum" in out
    assert len(pd.read_csv(tmp_path / "delivery_small.csv")) == 2


def test_taopt_study_delivery_command_writes_plot(tmp_path, capsys):
    """Through the real ``taopt`` entry point: the study prints its tables and draws q vs L/L0."""
    from taopt.cli import main

    png = tmp_path / "q.png"
    argv = ["study", "delivery", "--setup", "small", "--instances", "1", "--ratios", "0.3,0.9"]
    argv += ["--methods", "MMA,DP", "--out", str(tmp_path), "--quiet", "--plot", str(png)]
    assert main(argv) == 0
    assert png.stat().st_size > 0
    df = pd.read_csv(tmp_path / "delivery_small.csv")
    # the subset DP is exact, so no heuristic is below it on the same instance and ratio
    optimum = df[df.method == "DP"].set_index("ratio")["makespan"]
    mma = df[df.method == "MMA"].set_index("ratio")["makespan"]
    assert (mma >= optimum * (1 - 1e-9)).all()
