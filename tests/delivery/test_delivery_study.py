"""The chapter 5 study runner on a tiny setup, including resume and the CLI."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest
from conftest import DELIVERY_TINY

from taopt.errors import InstanceError
from taopt.orchestration.cli import main
from taopt.orchestration.studies.delivery import SPEC, delivery_study, study_instance, summarize

COLUMNS = SPEC.columns


def test_study_instance_servable_at_the_smallest_ratio():
    """Every customer can be served at L = 0.15 L0; ratios share customers and precedences."""
    for setup in ("dag40", "pairs120"):
        inst = study_instance(setup, 0, seed=1, ratio=0.15)
        assert inst.s == 121 and inst.flight_range == 150.0
        assert 2 * inst.flight_distance.min(axis=1).max() <= 150.0  # <= 2 * 70.7 m
    a, b = study_instance("dag40", 3, seed=1, ratio=0.3), study_instance("dag40", 3, 1, 0.9)
    assert (a.customers == b.customers).all() and a.precedences == b.precedences


def test_small_study_resumes_and_checks(tmp_path):
    """Resumes with more methods; bound <= optimum <= every method; the subset DP attains it."""
    kwargs = dict(instances=2, ratios=(0.15, 0.6), seed=2, out_dir=tmp_path, progress=False)
    first = delivery_study("small", methods=("NIA", "subset-dp"), **kwargs)
    assert len(first) == 2 * 2 * 2
    csv = tmp_path / "delivery_small.csv"
    assert len(pd.read_csv(csv)) == 8
    # re-run with one more method: only the 4 new rows are computed, old rows kept as is
    second = delivery_study("small", methods=("NIA", "MMA", "subset-dp"), jobs=2, **kwargs)
    assert len(second) == 12 and len(pd.read_csv(csv)) == 12
    old = second[second.method != "MMA"].reset_index(drop=True)
    pd.testing.assert_frame_equal(old, first.reset_index(drop=True), check_dtype=False)
    # a complete re-run computes nothing
    third = delivery_study("small", methods=("NIA", "MMA", "subset-dp"), **kwargs)
    assert len(third) == 12 and len(pd.read_csv(csv)) == 12
    # properties: bound <= optimum <= every method; the subset DP attains the optimum
    assert (second.valid_bound <= second.optimum + 1e-9).all()
    assert (second.makespan >= second.optimum - 1e-9).all()
    dp = second[second.method == "subset-dp"]
    assert dp.gap_to_optimum.abs().max() < 1e-9
    assert (second.q >= 1 - 1e-12).all()
    table = summarize(second)
    assert set(table.index.get_level_values("method")) == {"NIA", "MMA", "subset-dp"}
    assert table.loc[("subset-dp", 0.15), "gap_mean"] == pytest.approx(0.0, abs=1e-9)


def test_cli_prints_tables(tmp_path, capsys):
    """`taopt study delivery` prints the thesis's tables and the gap to the optimum."""
    argv = ["study", "delivery", "--setup", "small", "--scenarios", "1", "--ratios", "0.3"]
    argv += ["--methods", "NIA,subset-dp", "--out", str(tmp_path), "--quiet"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "average q" in out and "gap to the optimum" in out
    assert len(pd.read_csv(tmp_path / "delivery_small.csv")) == 2


def test_taopt_study_delivery_command_writes_plot(tmp_path, capsys):
    """Through the real ``taopt`` entry point: the study prints its tables and draws q vs L/L0."""
    png = tmp_path / "q.png"
    argv = ["study", "delivery", "--setup", "small", "--scenarios", "1", "--ratios", "0.3,0.9"]
    argv += ["--methods", "MMA,subset-dp", "--out", str(tmp_path), "--quiet", "--plot", str(png)]
    assert main(argv) == 0
    assert png.stat().st_size > 0
    df = pd.read_csv(tmp_path / "delivery_small.csv")
    # the subset DP is exact, so no heuristic is below it on the same instance and ratio
    optimum = df[df.method == "subset-dp"].set_index("ratio")["objective"]
    mma = df[df.method == "MMA"].set_index("ratio")["objective"]
    assert (mma >= optimum * (1 - 1e-9)).all()


# -- the resumable CSV (taopt.orchestration.studyio): method sets, settings, torn lines, order --------------
STABLE = [c for c in COLUMNS if c != "runtime"]
TINY = DELIVERY_TINY  # the settings of conftest's delivery_tiny_study


@pytest.fixture(scope="module")
def one_instance_study(tmp_path_factory):
    """A one-instance TINY study of NIA (GA options recorded), run once: its folder."""
    folder = tmp_path_factory.mktemp("one") / "study"
    base = {**TINY, "instances": 1, "out_dir": folder, "methods": ("NIA",)}
    delivery_study("small", **{**base, "method_options": {"GA": {"generations": 2}}})
    return folder


def copy_of(folder, to):
    """A finished study folder copied to ``to`` (the rows and settings a run there finds)."""
    shutil.copytree(folder, to)
    return to


def test_other_method_set_keeps_earlier_rows(tmp_path, delivery_tiny_study):
    """Asking for other methods extends the file; nothing is recomputed."""
    tmp_path = copy_of(delivery_tiny_study[0], tmp_path / "study")
    first = delivery_tiny_study[1]
    only_mma = delivery_study("small", methods=("MMA",), out_dir=tmp_path, **TINY)
    assert set(only_mma.method) == {"MMA"} and len(only_mma) == 4
    on_disk = pd.read_csv(tmp_path / "delivery_small.csv")
    assert len(on_disk) == 12 and (on_disk["complete"] == 1).all()
    again = delivery_study("small", methods=("NIA", "subset-dp"), out_dir=tmp_path, **TINY)
    pd.testing.assert_frame_equal(again, first)  # same runtimes too: nothing recomputed


@pytest.mark.parametrize(
    "change, key",
    [
        ({"seed": 4}, "seed"),
        ({"vd_ratio": 1.4}, "vd_ratio"),
        ({"method_options": {"GA": {"generations": 3}}}, "method_options"),
        ({"exact_max_n": 0}, "exact_max_n"),
    ],
)
def test_other_settings_refused_naming_the_key(tmp_path, change, key, one_instance_study):
    """Other settings on a folder with rows are refused, naming the key."""
    tmp_path = copy_of(one_instance_study, tmp_path / "study")
    base = {**TINY, "instances": 1, "out_dir": tmp_path, "methods": ("NIA",)}
    with pytest.raises(InstanceError, match=rf"{key}=.* there, {key}=.* now"):
        delivery_study("small", **{**base, "method_options": {"GA": {"generations": 2}}, **change})
    # the setup's own v_d / v_t given explicitly is the same setting
    delivery_study("small", **{**base, "method_options": {"GA": {"generations": 2}}, "vd_ratio": 1})


def test_setups_share_a_folder(tmp_path):
    """Two setups keep separate files and settings in one folder."""
    kwargs = {**TINY, "instances": 1, "ratios": (0.9,), "out_dir": tmp_path, "methods": ("NIA",)}
    delivery_study("small", **kwargs)
    delivery_study("dag40", **kwargs)
    assert (tmp_path / "delivery_small.config.json").exists()
    assert (tmp_path / "delivery_dag40.config.json").exists()


@pytest.mark.parametrize("cut", ["mid-number", "after-field"])
def test_torn_row_dropped_and_recomputed(tmp_path, cut, delivery_tiny_study):
    """A row torn by a crash is dropped and recomputed; later appends stay intact."""
    reference = delivery_tiny_study[1]
    folder = copy_of(delivery_tiny_study[0], tmp_path / "torn")
    csv = folder / "delivery_small.csv"
    text = csv.read_text()
    last = text.splitlines()[-1]
    fields = last.split(",")
    at = COLUMNS.index("objective")
    if cut == "mid-number":  # a makespan cut short would be a wrong, smaller value
        torn = ",".join(fields[:at]) + "," + fields[at][:3]
    else:  # cut right after the makespan: q and the rest missing
        torn = ",".join(fields[: at + 1]) + ","
    csv.write_text(text[: len(text) - len(last) - 1] + torn)
    resumed = delivery_study("small", methods=("NIA", "subset-dp"), out_dir=folder, **TINY)
    pd.testing.assert_frame_equal(resumed[STABLE], reference[STABLE])
    more = delivery_study("small", methods=("NIA", "subset-dp", "MMA"), out_dir=folder, **TINY)
    lines = csv.read_text().splitlines()
    assert len(lines) == 1 + 12 and len(more) == 12
    assert all(len(line.split(",")) == len(COLUMNS) + 1 for line in lines[1:])
    assert all(line.endswith(",1") for line in lines[1:])


def test_interrupted_resume_and_parallel_give_the_same_table(tmp_path):
    """A study cut after one instance and resumed on two workers equals the whole run."""
    methods = ("NIA", "MMA", "subset-dp")
    whole = delivery_study("small", methods=methods, out_dir=tmp_path / "whole", **TINY)
    # "interrupted" after the first instance, then resumed with jobs=2
    part = delivery_study(
        "small", methods=methods, out_dir=tmp_path / "part", **TINY | {"instances": 1}
    )
    assert len(part) == 6
    resumed = delivery_study("small", methods=methods, out_dir=tmp_path / "part", jobs=2, **TINY)
    pd.testing.assert_frame_equal(resumed[STABLE], whole[STABLE])
