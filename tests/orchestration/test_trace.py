"""Traces drawn and animated: taopt.plot.trace, the GIF's frames, ``taopt solve --trace``,
and the ideal DP's trace layer by layer."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import taopt
import taopt.plot
from taopt.errors import InstanceError, OutputError
from taopt.examples import path as example_path
from taopt.orchestration.cli import main
from taopt.orchestration.solving import load_problem_file
from taopt.trace import animate_trace, rounds

#: A 3-target, 1-vehicle matrix whose root LP has the 2-cycle {t0, t1}.
COST = np.array([[0, 1, 9, 9], [1, 0, 9, 9], [9, 9, 0, 9], [5, 6, 4, 0.0]])


@pytest.fixture(scope="module")
def small() -> tuple[taopt.AssignmentProblem, taopt.Solution]:
    """The matrix problem above solved with trace=True: two root LPs and one MIP round."""
    problem = taopt.AssignmentProblem(COST, 3)
    return problem, taopt.solve(problem, "exact", time_limit=None, trace=True)


@pytest.fixture(scope="module")
def delivery() -> tuple[object, taopt.Solution]:
    """Chapter 5's 20-customer example solved by the ideal DP with trace=True."""
    instance, _ = load_problem_file("example:delivery_example_20", progress=False)
    return instance, taopt.solve(instance, "exact", time_limit=None, trace=True)


def test_gif_has_one_frame_per_round(small, tmp_path):
    """The animation of a DFJ trace has exactly one frame per round (PIL n_frames)."""
    problem, solution = small
    gif = tmp_path / "rounds.gif"
    frames = animate_trace(solution, problem, gif)
    assert frames == len(solution.info["trace"]["rounds"]) >= 2
    with Image.open(gif) as image:
        assert image.n_frames == frames


def test_plot_has_a_panel_per_round_and_the_progress(small, tmp_path):
    """taopt.plot.trace draws one labelled map per round and the value/bound chart."""
    problem, solution = small
    png = tmp_path / "rounds.png"
    fig = taopt.plot.trace(solution, problem, png)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert len(shown) == len(rounds(solution)) + 1
    assert shown[0].get_xlabel().startswith("x (") and "violated set" in shown[0].get_title()
    assert shown[-1].get_xlabel() == "round" and "(s)" in shown[-1].get_ylabel()
    assert png.stat().st_size > 1000


def test_plot_refuses_a_solution_without_trace(small):
    """A solution solved without trace=True is refused with what to do."""
    problem, _ = small
    plain = taopt.solve(problem, "exact", time_limit=None)
    with pytest.raises(InstanceError, match="trace=True"):
        taopt.plot.trace(plain, problem)


def test_ideal_dp_trace_layers(delivery):
    """Every layer's states are dominated + pruned + kept; every bound is at most the optimum."""
    instance, solution = delivery
    layers = solution.info["trace"]["layers"]
    assert [layer["served"] for layer in layers] == list(range(len(layers)))
    assert len(layers) == instance.n  # the last customer is added by the final sortie
    for layer in layers:
        assert layer["states"] == layer["dominated"] + layer["pruned"] + layer["kept"]
        assert layer["bound"] <= solution.objective * (1 + 1e-9)
    assert layers[-1]["bound"] == pytest.approx(solution.objective, rel=1e-9)


def test_ideal_dp_trace_drawn_and_animated(tmp_path):
    """The DP's trace is drawn as two labelled charts and animated one frame per layer."""
    instance, _ = load_problem_file("example:delivery_instance", progress=False)
    solution = taopt.solve(instance, "exact", time_limit=None, trace=True)
    fig = taopt.plot.trace(solution)
    assert [ax.get_xlabel() for ax in fig.axes] == ["layer: customers served |I|"] * 2
    gif = tmp_path / "layers.gif"
    assert animate_trace(solution, instance, gif) == len(solution.info["trace"]["layers"])
    with Image.open(gif) as image:
        assert image.n_frames == len(solution.info["trace"]["layers"])


def test_cli_writes_the_trace_of_the_chapter_2_example(tmp_path, capsys):
    """`taopt solve example:demo --trace X.gif` writes one frame per round of the saved trace."""
    gif, out = tmp_path / "trace.gif", tmp_path / "solutions"
    argv = ["solve", "example:demo", "--methods", "exact", "--quiet"]
    code = main([*argv, "--trace", str(gif), "--out", str(out)])
    assert code == 0
    assert example_path("demo").exists()
    saved = json.loads((out / "exact.json").read_text())
    frames = len(saved["info"]["trace"]["rounds"])
    with Image.open(gif) as image:
        assert image.n_frames == frames
    assert f"({frames} frames, one per round)" in capsys.readouterr().out


def test_cli_refuses_a_trace_nobody_keeps(tmp_path):
    """--trace with only heuristics, or a file that is not a GIF, is refused before solving."""
    with pytest.raises(InstanceError, match="none of the methods MC keeps a trace"):
        taopt.orchestration.solving.solve_file(
            "example:demo", methods=("MC",), trace=tmp_path / "t.gif", progress=False
        )
    with pytest.raises(OutputError, match=r"\.gif"):
        taopt.orchestration.solving.solve_file(
            "example:demo", trace=tmp_path / "t.png", progress=False
        )
    assert not list(tmp_path.iterdir())
