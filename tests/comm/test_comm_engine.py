"""The chapter 4 engine: exact event times, links against geometry, messages, rules, seeds."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from taopt.comm import CommProblem, random_problem
from taopt.comm.bytes import NUMBER_BYTES
from taopt.comm.engine import Group, components, simulate
from taopt.errors import ConvergenceError, FeasibilityError
from taopt.heuristics.comm import CAA, DAA, HDA


def passing_problem() -> CommProblem:
    """Two vehicles of different abilities drive head-on along the x axis and pass.

    A starts at (0, 0) for its target at (60, 0), B at (100, 0) for its target at (40, 0);
    with r = 10 they link at t = 45 (gap 100 - 2t = 10) and unlink at t = 55.
    """
    return CommProblem([[60, 0], [40, 0]], [[0, 0], [100, 0]], ["a", "b"], ["a", "b"], 10.0)


def test_contact_and_parting_times_are_exact() -> None:
    """The link forms at exactly t = 45 and breaks at t = 55; (4.1) is 120."""
    run = simulate(passing_problem(), DAA())
    groups = run.info["groups"]
    assert len(groups) == 1
    assert groups[0]["time"] == pytest.approx(45.0, abs=1e-9)
    assert groups[0]["members"] == [0, 1] and groups[0]["links"] == [[0, 1]]
    assert run.info["link_changes"] == 2
    assert run.objective == pytest.approx(120.0)
    assert run.info["end_time"] == pytest.approx(60.0)


def test_components_match_networkx() -> None:
    """components() labels each vehicle by the smallest index it can reach."""
    rng = np.random.default_rng(0)
    for _ in range(30):
        m = int(rng.integers(1, 9))
        linked = rng.random((m, m)) < 0.25
        linked = linked | linked.T
        np.fill_diagonal(linked, False)
        labels = components(linked)
        g = nx.from_numpy_array(linked.astype(int))
        for part in nx.connected_components(g):
            assert {int(labels[v]) for v in part} == {min(part)}


def check_links_against_geometry(problem: CommProblem, run) -> None:
    """At every newly connected group, its links are the pairs within r, and it is a component."""
    r = problem.comm_range
    tr = run.trajectories
    for g in run.info["groups"]:
        t = g["time"]
        where = np.array([tr.position(j, t) for j in range(problem.m)])
        gap = where[:, None, :] - where[None, :, :]
        dist = np.hypot(gap[..., 0], gap[..., 1])
        members = set(g["members"])
        links = {tuple(sorted(pair)) for pair in g["links"]}
        for a in range(problem.m):
            for b in range(a + 1, problem.m):
                inside = a in members and b in members
                if dist[a, b] < r - 1e-6:
                    assert (a in members) == (b in members), (t, a, b)
                    if inside:
                        assert (a, b) in links
                if (a, b) in links:
                    assert dist[a, b] <= r + 1e-6


@settings(derandomize=True, max_examples=25, deadline=None)
@given(
    n=st.integers(1, 8),
    m=st.integers(1, 5),
    k=st.integers(1, 5),
    r=st.floats(0.0, 500.0),
    seed=st.integers(0, 10_000),
)
def test_links_follow_the_geometry(n: int, m: int, k: int, r: float, seed: int) -> None:
    """Every group's links are exactly the vehicle pairs within r at that time (4.3)."""
    k = min(k, n, m)
    problem = random_problem(n, m, k, r, seed=seed)
    for policy in (DAA(), HDA()):
        run = simulate(problem, policy, strict=True)
        check_links_against_geometry(problem, run)


def test_no_contact_is_missed() -> None:
    """A fine sampled replay finds no newly connected group that the engine missed."""
    for seed in range(3):
        problem = random_problem(8, 4, 2, 150.0, seed=seed)
        run = simulate(problem, DAA())
        tr = run.trajectories
        times = np.arange(0.0, run.info["end_time"], 0.05)
        engine_times = np.array([g["time"] for g in run.info["groups"]])
        previous = None
        for t in times:
            where = np.array([tr.position(j, t) for j in range(problem.m)])
            gap = where[:, None, :] - where[None, :, :]
            labels = components(np.hypot(gap[..., 0], gap[..., 1]) <= problem.comm_range)
            if previous is not None:
                for label in np.unique(labels):
                    members = labels == label
                    if members.sum() > 1 and np.unique(previous[members]).size > 1:
                        assert np.min(np.abs(engine_times - t)) <= 0.05 + 1e-9, t
            previous = labels


def test_byte_model_on_a_hand_counted_meeting() -> None:
    """Two same-ability vehicles linked from t = 0, 3 targets: DAA and CAA counts by hand.

    DAA: consensus 3 rounds x 2 messages x (n(n+2) + 2n = 21) + positions 2 x 2 x 6 +
    cooperative 2 x 2 x 3 + bids 3 targets x 2 rounds x 2 x 6 + check 2 x 2 x 3 = 246
    numbers in 15 rounds. CAA: collect 3 x 2 x (n(3n+3) + n = 39) + distribute 2 x 2 x 36
    = 378 numbers.
    """
    problem = CommProblem([[10, 0], [20, 0], [30, 5]], [[0, 0], [5, 0]], [0, 0, 0], [0, 0], 50.0)
    daa = simulate(problem, DAA())
    assert daa.info["numbers"] == 246 and daa.info["rounds"] == 15
    assert daa.info["messages"] == 30 and daa.info["bytes"] == 246 * NUMBER_BYTES
    caa = simulate(problem, CAA())
    assert caa.info["numbers"] == 378
    assert caa.info["group_events"] == daa.info["group_events"] == 1


@pytest.mark.parametrize("policy", [CAA, DAA, HDA])
def test_same_seed_same_run(policy) -> None:
    """Same seed, same run: trajectories, events, bytes and the group log, bit for bit."""
    problem = random_problem(20, 6, 2, 250.0, seed=11)
    a = simulate(problem, policy(), seed=5)
    b = simulate(problem, policy(), seed=5)
    assert a.trajectories == b.trajectories
    assert a.info == b.info


def test_caa_leader_is_random_but_routes_are_not() -> None:
    """CAA's leader is drawn with the seed; the assignment does not depend on it."""
    problem = random_problem(12, 5, 1, 2000.0, seed=1)  # a complete graph: all tie
    leaders = {simulate(problem, CAA(), seed=s).info["groups"][0]["leader"] for s in range(12)}
    assert len(leaders) > 1
    runs = [simulate(problem, CAA(), seed=s).trajectories for s in range(3)]
    assert runs[0] == runs[1] == runs[2]


class Forgetful(DAA):
    """A broken policy: it makes the group forget what it knows."""

    name = "forgetful"

    def on_connect(self, group: Group) -> None:
        known = group.knowledge
        known[:] = False
        group.set_knowledge(known)


class Greedy(DAA):
    """A broken policy: it hands a vehicle a target of another attribute."""

    name = "greedy"

    def on_connect(self, group: Group) -> None:
        group.set_route(0, list(range(group.problem.n)))


class Dropper(DAA):
    """A broken policy: every group drops all its routes."""

    name = "dropper"

    def on_connect(self, group: Group) -> None:
        for i in range(group.size):
            group.set_route(i, [])


def test_engine_enforces_the_rules() -> None:
    """Forgetting (Lemma 4.3(ii)) and wrong-ability targets are refused, naming the vehicle."""
    p = CommProblem([[50, 50], [60, 60]], [[0, 0], [1, 0]], ["a", "b"], ["a", "b"], 5.0)
    # vehicle 0 visits target 0 at t = 0 on its way; it meets vehicle 1 at t = 7.5
    p_visited = CommProblem([[0, 0], [10, 0]], [[0, 0], [20, 0]], ["a", "a"], ["a", "a"], 5.0)
    with pytest.raises(FeasibilityError, match="forget"):
        simulate(p_visited, Forgetful())
    with pytest.raises(FeasibilityError, match="cannot take target 1"):
        simulate(p, Greedy())


def test_lost_targets_are_reported() -> None:
    """Dropping routes breaks Lemma 4.3 (counted, or raised with strict) and Proposition 4.4."""
    p = CommProblem([[50, 50], [60, 60]], [[0, 0], [1, 0]], ["a", "a"], ["a", "a"], 5.0)
    with pytest.raises(FeasibilityError, match="Lemma 4.3"):
        simulate(p, Dropper(), strict=True)
    with pytest.raises(ConvergenceError, match="no vehicle moves"):
        simulate(p, Dropper())
