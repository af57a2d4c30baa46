"""Every plot reads on its own: units on the axes, ids on the points, legends outside the data.

And ``--plot`` works for every file kind of ``taopt solve``, or is refused before any work.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import taopt
from taopt.errors import OutputError
from taopt.orchestration.cli import main
from taopt.plot import check_output, method_style, schematic_layout

EXAMPLES = Path(taopt.__file__).parent / "data" / "examples"
UNIT = re.compile(r"\([^()]*\)")  # "x (m)", "time (s)", "ratio (1)"


def readable(ax, ids=(), legend=True, categorical=""):
    """Assert ``ax`` has unit-bearing axis labels, the ``ids`` as text and a legend outside.

    A ``categorical`` axis ("x" or "y": methods, vehicles) needs a label but no unit.
    """
    for axis, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
        assert label, f"no {axis} label"
        assert axis == categorical or UNIT.search(label), f"axis label without a unit: {label!r}"
    texts = {t.get_text() for t in ax.texts}
    missing = set(ids) - texts
    assert not missing, f"ids not written on the plot: {sorted(missing)}"
    if legend:
        box = ax.get_legend()
        assert box is not None, "no legend"
        ax.figure.draw_without_rendering()
        inner, outer = ax.get_window_extent(), box.get_window_extent()
        assert not inner.overlaps(outer), "the legend covers the data"


def no_work(monkeypatch):
    """Make any load or solve fail loudly: a refusal must come before them."""
    import taopt.orchestration.pipeline
    import taopt.orchestration.solving

    def boom(*args, **kwargs):
        raise AssertionError("work started before the refusal")

    monkeypatch.setattr(taopt.orchestration.solving, "load_problem_file", boom)
    monkeypatch.setattr(taopt.orchestration.solving, "method_table", boom)
    monkeypatch.setattr(taopt.orchestration.pipeline, "solve", boom)


# -- shared helpers -----------------------------------------------------------------------------
def test_check_output_refuses_wrong_suffix_and_missing_folder(tmp_path):
    """A .jpg for a PNG, an .mp4 for a GIF and a missing folder are refused; good names pass."""
    check_output(tmp_path / "a.png", ".png", "--plot")
    check_output(tmp_path / "a.GIF", ".gif", "--animate")
    with pytest.raises(OutputError, match=r"--plot .*a\.jpg.*\.png"):
        check_output(tmp_path / "a.jpg", ".png", "--plot")
    with pytest.raises(OutputError, match=r"\.gif"):
        check_output(tmp_path / "a.mp4", ".gif", "--animate")
    with pytest.raises(OutputError, match="does not exist"):
        check_output(tmp_path / "nowhere" / "a.png", ".png", "--plot")


def test_schematic_layout_recovers_planar_distances():
    """Classical MDS of a Euclidean distance matrix reproduces the distances."""
    points = np.random.default_rng(0).uniform(0, 100, size=(7, 2))
    distance = np.linalg.norm(points[:, None] - points[None], axis=2)
    xy = schematic_layout(distance)
    again = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    np.testing.assert_allclose(again, distance, atol=1e-6)


def test_method_styles_differ_without_colour():
    """The methods each chapter compares get distinct line style / marker pairs (declared by
    their registrations)."""
    import taopt.orchestration.pipeline  # noqa: F401  (registers every method)

    chapters = (
        ("VN", "VM", "EVN", "EVM", "MC", "GA", "exact"),
        ("DTAA", "GA", "GA-memetic", "MC", "exact"),
        ("DAA", "HDA", "CAA", "exact"),
        ("NIA", "MMA", "SMMA", "GA", "ILS", "subset-dp", "milp", "exact"),
    )
    for group in chapters:
        pairs = {tuple(method_style(m).values()) for m in group}
        assert len(pairs) == len(group)


# -- each family's picture ------------------------------------------------------------------------
def test_route_plot_has_ids_units_and_route_legend():
    """plot_routes writes t*/v* ids, metres on both axes and each route in the outside legend."""
    from taopt.routing.plot import plot_routes

    points = np.array([[0.0, 0.0], [10.0, 5.0], [3.0, 8.0], [12.0, 12.0], [-2.0, 3.0]])
    ax = plot_routes(points, [[0, 2], [1]], title="exact routes")
    readable(ax, ids=("t0", "t1", "t2", "v0", "v1"))
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "v0: v0 -> t0 -> t2" in legend and "v1: v1 -> t1" in legend
    styles = {line.get_linestyle() for line in ax.lines if line.get_label().startswith("v")}
    assert len(styles) == 2  # one line style per vehicle, not only a colour


def test_instance_routes_follow_the_drift_paths():
    """With a field, every leg is drawn along its minimum-time path (a curve, not a segment)."""
    from taopt import Instance, Target, Vehicle, thesis_field
    from taopt.routing.plot import plot_instance_routes

    instance = Instance(
        vehicles=(Vehicle("boat", (0.0, 0.0)),),
        targets=(Target("north", (20.0, 80.0)), Target("east", (80.0, 60.0))),
        region=(0.0, 100.0, 0.0, 100.0),
        field=thesis_field(1e-2),
    )
    ax = plot_instance_routes(instance, [[0, 1]], title="two legs")
    readable(ax, ids=("boat", "north", "east"))
    legs = [line for line in ax.lines if len(line.get_xdata()) > 2]
    assert len(legs) == 2
    for leg in legs:  # curved: the middle of the path leaves the straight chord
        xy = np.column_stack([leg.get_xdata(), leg.get_ydata()])
        chord = xy[-1] - xy[0]
        rel = xy - xy[0]
        offsets = np.abs(chord[0] * rel[:, 1] - chord[1] * rel[:, 0]) / np.linalg.norm(chord)
        assert offsets.max() > 0.5


def test_capability_routes_name_vehicles_and_targets():
    """The chapter 3 route plot names every target and vehicle of the instance file."""
    from taopt.capability.instances import capability_problem_from_instance
    from taopt.capability.plot import plot_routes

    instance = taopt.Instance.load(EXAMPLES / "instance.json")
    problem = capability_problem_from_instance(instance)
    routes = taopt.solve(problem, "MC").routes
    ax = plot_routes(instance, problem, routes, title="MC")
    readable(ax, ids=("t0", "t1", "t2", "v0", "v1"))


def test_delivery_plan_and_gantt_read_on_their_own():
    """Plan map: metres, customer ids; Gantt: seconds, customers, and the makespan line at f."""
    from taopt.delivery import DeliveryInstance
    from taopt.delivery.evaluate import timeline
    from taopt.delivery.plot import plot_gantt, plot_plan

    instance = DeliveryInstance.load(EXAMPLES / "delivery_instance.json")
    solution = taopt.solve(instance, "NIA")
    ax = plot_plan(instance, solution, method="NIA")
    readable(ax, ids=[f"{j} (#{p + 1})" for p, j in enumerate(solution.plan.order)])
    gantt = plot_gantt(instance, solution, method="NIA")
    readable(gantt, ids=[str(j) for j in solution.plan.order], categorical="y")
    line = timeline(instance, solution.plan)
    assert line.makespan == pytest.approx(solution.objective)
    makespan_lines = [x for x in gantt.lines if x.get_linestyle() == ":"]
    assert makespan_lines and makespan_lines[0].get_xdata()[0] == pytest.approx(line.makespan)
    # what is drawn after f is the last return and landing, marked as not counted in (5.1)
    assert max(line.recovery_time) > line.makespan
    labels = [t.get_text() for t in gantt.get_legend().get_texts()]
    assert any("not part of (5.1)" in text for text in labels)


def test_sop_order_chart_draws_precedences(ref_sop):
    """The SOP chart labels every node, shows cumulative cost and one arc per precedence."""
    from taopt.delivery.plot import plot_order

    problem = ref_sop.problem
    solution = taopt.solve(problem, "NIA")
    ax = plot_order(problem, solution, method="NIA")
    readable(ax, ids=[str(v) for v in range(problem.n)])
    arcs = [t for t in ax.texts if t.arrow_patch is not None]
    assert len(arcs) == len(problem.precedences)
    _, top = ax.lines[0].get_data()
    assert top[-1] == pytest.approx(solution.objective)


def test_comm_run_names_vehicles_and_targets():
    """A run: v0.. at the starts, target indices, metres, one legend entry per vehicle."""
    from taopt.comm.plot import plot_run

    problem = taopt.CommProblem.load(EXAMPLES / "comm_problem.json")
    result = taopt.solve(problem, "DAA")
    ax = plot_run(problem, result)
    readable(ax, ids=[f"v{j}" for j in range(problem.m)] + [str(q) for q in range(problem.n)])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert sum(bool(re.match(r"v\d+ \(", text)) for text in labels) == problem.m


# -- study plots (small hand-made tables with the studies' columns) -----------------------------
def test_comm_range_curves_tell_daa_from_hda():
    """In the comm study figure DAA and HDA differ by line style and marker, legend outside."""
    from taopt.comm.plot import plot_range_curves

    table = pd.DataFrame(
        [
            {"A": a, "r": r, "method": m, "q": 1 + r / 1000 + k / 10}
            for a in (1, 2)
            for r in (1.0, 150.0, 300.0)
            for k, m in enumerate(("DAA", "HDA"))
        ]
    )
    ax = plot_range_curves(table, "q", ("DAA", "HDA"), ylabel="mean q (1)")
    readable(ax)
    look = {line.get_label(): (line.get_linestyle(), line.get_marker()) for line in ax.lines}
    assert look["DAA, |A| = 1"] != look["HDA, |A| = 1"]


def test_study_plots_are_labelled():
    """Drift boxplot, delivery curves, capability quality and comm figures carry units."""
    from taopt.capability.plot import plot_quality
    from taopt.orchestration.studies.comm import plot_homogeneous, plot_scalability
    from taopt.orchestration.studies.delivery import plot_study
    from taopt.orchestration.studies.drift import plot_gaps

    rng = np.random.default_rng(1)
    drift = pd.DataFrame(
        [
            {
                "scenario": s,
                "method": m,
                "objective": 10 + rng.random(),
                "f_a": 9.0,
                "valid_bound": 9.5,
                "optimum": 10.0,
                "n": 5,
                "m": 2,
            }
            for s in range(3)
            for m in ("VN", "MC", "exact")
        ]
    )
    readable(
        plot_gaps(drift), legend=False, categorical="x"
    )  # a boxplot: the methods are the x ticks
    delivery = pd.DataFrame(
        [
            {"scenario": s, "method": m, "ratio": r, "q": 1 + r * k / 10}
            for s in range(2)
            for k, m in enumerate(("NIA", "MMA", "DP"))
            for r in (0.3, 0.9)
        ]
    )
    readable(plot_study(delivery, "q"))
    quality = pd.DataFrame(
        [
            {"instance": "n7m3", "A": a, "method": m, "q_thesis": 1 + a * k / 50}
            for a in (1, 3)
            for k, m in enumerate(("DTAA", "GA", "exact"))
        ]
    )
    readable(plot_quality(quality, instance="n7m3"))
    comm = pd.DataFrame(
        [
            {
                "n": n,
                "m": 10,
                "A": 1,
                "r": r,
                "method": "DAA",
                "q": 1.2,
                "gap": 1.1,
                "certified": 1,
                "runtime": 0.1 * n,
            }
            for n in (10, 20)
            for r in (1.0, 300.0)
        ]
    )
    for figure in (plot_homogeneous([comm[comm.n == 10]]), plot_scalability(comm)):
        for ax in figure.axes:
            readable(ax)


# -- issue 30, item 13: plots a user would look at --------------------------------------------
def marker_x(ax, label):
    """The x data of the line labelled ``label``."""
    (line,) = [x for x in ax.lines if x.get_label() == label]
    return np.asarray(line.get_xdata(), dtype=float)


def test_gantt_draws_one_drone_bar_per_sortie_and_landings_as_ticks():
    """The drone row is one bar per sortie (S_p to R_p) and two ticks per sortie at t_j, R_p."""
    from taopt.delivery import DeliveryInstance
    from taopt.delivery.evaluate import timeline
    from taopt.delivery.plot import plot_gantt

    instance = DeliveryInstance.load(taopt.__path__[0] + "/data/delivery_example_20.json")
    solution = taopt.solve(instance, "NIA")
    line = timeline(instance, solution.plan)
    ax = plot_gantt(instance, solution, method="NIA")
    by_gid = {c.get_gid(): c for c in ax.collections if c.get_gid()}
    bars = by_gid["drone sorties"].get_paths()
    assert len(bars) == len(solution.plan.order) == 20
    starts = sorted(float(b.vertices[:, 0].min()) for b in bars)
    ends = sorted(float(b.vertices[:, 0].max()) for b in bars)
    np.testing.assert_allclose(starts, np.sort(line.launch_time))
    np.testing.assert_allclose(ends, np.sort(line.recovery_time))
    for gid, times in (
        ("customer landings", line.service_time),
        ("truck landings", line.recovery_time),
    ):
        ticks = [float(seg[0, 0]) for seg in by_gid[gid].get_segments()]
        np.testing.assert_allclose(sorted(ticks), np.sort(times))
    # nothing else is drawn in the drone row (no stripe per flight, landing and wait)
    drone_row = [c for c in ax.collections if c.get_gid() is None and len(c.get_paths())]
    assert all(float(p.vertices[:, 1].min()) > 0.3 for c in drone_row for p in c.get_paths())
    readable(ax, ids=[str(j) for j in solution.plan.order], categorical="y")


def test_plan_map_labels_of_20_customers_do_not_collide():
    """On the 20-customer map no two customer or stop labels overlap (their drawn boxes)."""
    from taopt.delivery import DeliveryInstance
    from taopt.delivery.plot import plot_plan

    instance = DeliveryInstance.load(taopt.__path__[0] + "/data/delivery_example_20.json")
    ax = plot_plan(instance, taopt.solve(instance, "NIA"), method="NIA")
    ax.figure.draw_without_rendering()
    labels = [t for t in ax.texts if re.fullmatch(r"\d+ \(#\d+\)|\d+|s\d+", t.get_text())]
    assert len(labels) >= 20
    boxes = [t.get_window_extent() for t in labels]
    clashes = [
        (labels[a].get_text(), labels[b].get_text())
        for a in range(len(boxes))
        for b in range(a + 1, len(boxes))
        if boxes[a].overlaps(boxes[b])
    ]
    assert not clashes, f"labels drawn over each other: {clashes}"


def delivery_rows(instances=1, ratios=(0.3, 0.6, 0.9)):
    """A delivery study frame: NIA, MMA and GA equal (all optimal) at every ratio."""
    return pd.DataFrame(
        [
            {"instance": i, "ratio": r, "method": m, "q": 1.4, "makespan": 100.0}
            for i in range(instances)
            for r in ratios
            for m in ("GA", "MMA", "NIA")
        ]
    )


@pytest.mark.parametrize(("instances", "words"), [(1, "1 instance x 3"), (4, "4 instances x 3")])
def test_delivery_study_title_counts_the_plotted_instances(instances, words):
    """The title names the instances plotted (one instance at 3 L/L0 values: "1 instance")."""
    from taopt.orchestration.studies.delivery import plot_study

    ax = plot_study(delivery_rows(instances), "q")
    assert f"({words} L/L0 values)" in ax.get_title()
    readable(ax)


def test_delivery_study_markers_of_equal_methods_do_not_overlap():
    """GA, MMA and NIA at the same mean are drawn at distinct x (dodged), each near its L/L0."""
    from taopt.orchestration.studies.delivery import plot_study

    ax = plot_study(delivery_rows(), "q")
    xs = [marker_x(ax, m) for m in ("GA", "MMA", "NIA")]
    for a in range(3):
        np.testing.assert_allclose(xs[a], [0.3, 0.6, 0.9], atol=0.05)
        for b in range(a + 1, 3):
            assert np.all(np.abs(xs[a] - xs[b]) > 1e-3)
    assert "shifted" in ax.get_xlabel()


def test_comm_run_draws_the_range_r_around_each_start():
    """plot_run draws a circle of radius r around every vehicle start, labelled with r."""
    from matplotlib.patches import Circle

    from taopt.comm.plot import plot_run

    problem = taopt.CommProblem.load(EXAMPLES / "comm_problem.json")
    ax = plot_run(problem, taopt.solve(problem, "DAA"))
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    assert len(circles) == problem.m
    for circle, start in zip(circles, problem.vehicles, strict=True):
        assert circle.get_radius() == pytest.approx(problem.comm_range)
        np.testing.assert_allclose(circle.center, start)
    texts = [t.get_text() for t in ax.texts] + [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(f"r = {problem.comm_range:g} m" in t for t in texts)


def test_comm_study_bytes_axis_is_in_the_tables_unit():
    """The bytes panel plots 10^5 bytes (as Table 4.2 and bytes_table), with no 1e7 offset."""
    from taopt.orchestration.studies.comm import bytes_table, plot_study

    table = pd.DataFrame(
        [
            {"n": 30, "m": 6, "A": 2, "r": r, "method": m, "q": 1.2, "bytes": 3.0e7 + r * 1e5}
            for r in (1.0, 100.0)
            for m in ("DAA", "HDA", "CAA")
        ]
    )
    figure = plot_study(table)
    bytes_ax = figure.axes[1]
    assert "(10^5 bytes)" in bytes_ax.get_ylabel()
    plotted = np.concatenate([line.get_ydata() for line in bytes_ax.lines])
    printed = bytes_table(table).to_numpy().ravel()
    np.testing.assert_allclose(np.sort(plotted), np.sort(printed))
    figure.draw_without_rendering()
    assert bytes_ax.yaxis.get_offset_text().get_text() == ""
    for ax in figure.axes:
        readable(ax)


def test_budgeted_panels_are_titled_by_measure_and_methods_distinguishable():
    """Each panel's title says its measure; MC and EVM, equal here, differ in style and x."""
    from taopt.orchestration.studies.budgeted import plot_study

    table = pd.DataFrame(
        [
            {
                "size": "n6m2",
                "level": level,
                "method": method,
                "scenarios": 3,
                "gap_pct": 1.5,
                "vs_best_pct": 1.5,
                "no_answer_pct": 0.0,
            }
            for level in ("none", "Q1", "T1.2")
            for method in ("MC", "EVM", "GA", "exact")
        ]
    )
    figure = plot_study(table, exclude=("exact",))
    titles = [ax.get_title() for ax in figure.axes]
    assert len(set(titles)) == 3 and not any(t == "n6m2" for t in titles)
    assert "true gap" in titles[0] and "no feasible answer" in titles[2]
    assert "3 scenarios" in figure.get_suptitle()
    for ax in figure.axes:
        looks = {
            m: (ax.lines[k].get_linestyle(), ax.lines[k].get_marker())
            for k, m in enumerate(("MC", "EVM", "GA"))
        }
        assert len(set(looks.values())) == 3
        assert np.all(np.abs(marker_x(ax, "MC") - marker_x(ax, "EVM")) > 1e-3)
        readable(ax, legend=ax is figure.axes[-1], categorical="x")


def test_drift_plot_shows_the_true_gap_to_the_certified_optimum():
    """plot_gaps draws 100 (f / f_o - 1) per heuristic (not f / f_a), and says so."""
    from taopt.orchestration.studies.drift import plot_gaps

    rows = [
        {
            "scenario": s,
            "n": 5,
            "m": 2,
            "method": m,
            "objective": f,
            "status": st,
            "bound": np.nan,
            "f_a": 80.0,
            "valid_bound": 70.0,
        }
        for s in range(3)
        for m, f, st in (("MC", 110.0 + s, "feasible"), ("exact", 100.0, "optimal"))
    ]
    ax = plot_gaps(pd.DataFrame(rows))
    assert "f_o" in ax.get_ylabel() and "(%)" in ax.get_ylabel()
    assert [t.get_text() for t in ax.get_xticklabels()] == ["MC"]
    medians = [
        line
        for line in ax.lines
        if len(line.get_ydata()) == 2 and line.get_ydata()[0] == line.get_ydata()[1]
    ]
    assert any(line.get_ydata()[0] == pytest.approx(11.0) for line in medians)
    assert "certified in 3 of 3 scenarios" in ax.get_title()


def test_navigate_start_is_drawn_over_the_goal():
    """In a round trip each start (a dot) lies over the other path's goal (an open square)."""
    from taopt.fields import UniformField
    from taopt.navigation import min_time_path
    from taopt.plot import plot_paths

    field = UniformField(0.2, 0.0)
    there = min_time_path(field, (10.0, 20.0), (80.0, 70.0), method="closed_form")
    back = min_time_path(field, (80.0, 70.0), (10.0, 20.0), method="closed_form")
    ax = plot_paths(field, [there, back], labels=["i -> j", "j -> i"])
    starts = [x for x in ax.lines if x.get_gid() == "start"]
    goals = [x for x in ax.lines if x.get_gid() == "goal"]
    assert len(starts) == len(goals) == 2
    for start in starts:
        under = [g for g in goals if np.allclose(g.get_xydata(), start.get_xydata())]
        assert under, "each start of a round trip sits on the other path's goal"
        assert start.get_zorder() > under[0].get_zorder()
        assert start.get_marker() != under[0].get_marker()
        assert start.get_markersize() < under[0].get_markersize()
        assert under[0].get_markerfacecolor() == "none" or under[0].get_markerfacecolor()[3] == 0
    readable(ax)


# -- taopt solve --plot on every file kind ------------------------------------------------------
FAST = {
    "assignment_problem": "exact",
    "capability_problem": "MC",
    "comm_problem": "DAA",
    "delivery_instance": "NIA",
    "sop_problem": "exact",
    "instance": "MC",
}


@pytest.mark.parametrize("kind", sorted(FAST))
def test_solve_plot_writes_a_png_for_every_kind(kind, tmp_path, capsys):
    """`taopt solve <example> --plot x.png` draws the family's picture (never a late failure)."""
    png = tmp_path / f"{kind}.png"
    argv = ["solve", str(EXAMPLES / f"{kind}.json"), "--methods", FAST[kind], "--quiet"]
    assert main(argv + ["--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert f"plot of {FAST[kind]} written to {png}" in out
    # under it, the drawn solution in the ids of the picture (trajectories excepted)
    after = out.split(f"written to {png}\n")[1].splitlines()
    spelt = {"delivery_instance": "#1: customer ", "sop_problem": "order: "}.get(kind, "v0: v0")
    assert kind == "comm_problem" or after[0].startswith(f"  {spelt}")


def test_solve_prints_the_plotted_routes_with_the_plotted_ids(tmp_path, capsys):
    """The routes printed under the plot use the instance file's ids, as the picture does."""
    png = tmp_path / "routes.png"
    argv = ["solve", str(EXAMPLES / "instance.json"), "--methods", "MC", "--quiet"]
    assert main(argv + ["--plot", str(png)]) == 0
    data = json.loads((EXAMPLES / "instance.json").read_text())
    out = capsys.readouterr().out
    for vehicle in data["vehicles"]:
        assert f"  {vehicle['id']}: {vehicle['id']}" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["solve", "sop_problem.json", "--plot", "x.jpg"], "must end in .png"),
        (["solve", "delivery_instance.json", "--gantt", "x.svg"], "must end in .png"),
        (
            ["solve", "sop_problem.json", "--gantt", "x.png"],
            "--gantt draws a Gantt chart of a delivery_instance, fleet_problem only",
        ),
        (
            ["solve", "instance.json", "--gantt", "x.png"],
            "--gantt draws a Gantt chart of a delivery_instance, fleet_problem only",
        ),
        (["simulate", "comm_problem.json", "--animate", "x.mp4"], "must end in .gif"),
        (
            ["simulate", "comm_problem.json", "--animate", "x.gif", "--frames", "0"],
            "an animation needs frames >= 2",
        ),
        (["simulate", "comm_problem.json", "--plot", "x.pdf"], "must end in .png"),
        (["demo", "--plot", "x.jpeg"], "must end in .png"),
    ],
)
def test_bad_outputs_are_refused_before_any_work(args, message, tmp_path, monkeypatch, capsys):
    """A wrong extension or an impossible plot fails with rc 2 before loading or solving."""
    no_work(monkeypatch)
    import taopt.orchestration.demo

    monkeypatch.setattr(
        taopt.orchestration.demo, "load_demo_instance", lambda: pytest.fail("demo started")
    )
    argv = [str(EXAMPLES / a) if a.endswith(".json") else a for a in args]
    argv = [str(tmp_path / a) if a.startswith("x.") else a for a in argv]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
