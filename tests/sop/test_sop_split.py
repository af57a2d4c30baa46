"""Our tree in two processes (issue 33, :mod:`taopt.models.sop_split`): the split tree proves
the same optimum as the tree alone, its nodes really travel both ways, its bound stays below
the optimum when it is stopped early, and a peer lost mid-search costs no proof (its nodes
come back). The protocol runs with the peer in a thread (``Peer(in_thread=True)``: no
process start-up) except in the one test that starts the real process; the trees are made
to branch (no strong branching, no node rounds, no stretch rows) so that nodes change hands.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from taopt.models import sop_bc, sop_cuts, sop_split
from taopt.models.sop_bc import solve_sop_bc
from taopt.models.sop_split import Peer
from taopt.sop.generate import random_sop
from taopt.sop.problem import SopProblem, evaluate_order


@pytest.fixture
def branching(monkeypatch: pytest.MonkeyPatch) -> None:
    """Trees of tens to hundreds of nodes on 26-node SOPs."""
    monkeypatch.setattr(sop_bc, "STRONG_CANDIDATES", 1)
    monkeypatch.setattr(sop_bc, "NODE_ROUNDS", 0)
    monkeypatch.setattr(sop_cuts, "STRETCH_CUTS", False)


def _ready(problem: SopProblem, in_thread: bool = True) -> Peer:
    peer = Peer(problem, None, in_thread=in_thread)
    until = time.perf_counter() + 120
    while not peer.poll_ready():
        assert time.perf_counter() < until, "the peer did not build its model"
        time.sleep(0.005)
    return peer


def _cost(problem: SopProblem, order: list[int]) -> float:
    """The order's cost by the problem's own scorer (which checks the order)."""
    return evaluate_order(problem, order)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_split_tree_proves_the_optimum_of_the_tree_alone(branching: None, seed: int) -> None:
    problem = random_sop(26, 0.05, seed)
    alone = solve_sop_bc(problem)
    split = solve_sop_bc(problem, peer=_ready(problem))
    assert alone.status == split.status == "optimal"
    assert split.objective == alone.objective == split.bound
    assert _cost(problem, list(split.order)) == split.objective
    peer = split.info["peer"]
    assert peer["loaded"] and not peer["lost"]
    assert peer["taken"] > 0 and peer["nodes"] > 0  # nodes went to the peer and were solved
    assert peer["lps"] > 0


def test_split_rows_and_orders_cross_over(branching: None) -> None:
    problem = random_sop(26, 0.05, 0)
    split = solve_sop_bc(problem, peer=_ready(problem))
    peer = split.info["peer"]
    assert peer["rows_sent"] > 0 and peer["rows_taken"] > 0  # the peer's rows, and ours there
    assert split.info["split"]["rows_taken"] > 0  # its rows added here


def test_split_stopped_early_keeps_a_valid_bound(branching: None) -> None:
    problem = random_sop(26, 0.05, 0)
    optimum = solve_sop_bc(problem).objective
    stopped = solve_sop_bc(problem, node_limit=40, peer=_ready(problem))
    assert stopped.status == "time_limit"
    assert stopped.bound <= optimum < math.inf
    assert stopped.objective >= optimum
    assert _cost(problem, list(stopped.order)) == stopped.objective


def test_a_lost_peer_gives_its_nodes_back(branching: None, monkeypatch: pytest.MonkeyPatch) -> None:
    """The peer solves two nodes and vanishes without its last answer: this side takes back
    every node it lent and still proves the optimum."""

    def vanish(tree: sop_bc.BranchCut, deadline: object) -> None:
        tree.run(deadline, node_limit=2, root=False)  # type: ignore[arg-type]
        tree.link.conn.close()  # gone: its ``left`` is never sent

    monkeypatch.setattr(sop_split, "search_given", vanish)
    problem = random_sop(26, 0.05, 0)
    optimum = solve_sop_bc(problem).objective
    split = solve_sop_bc(problem, peer=_ready(problem))
    assert split.info["peer"]["lost"]
    assert split.status == "optimal" and split.objective == optimum == split.bound


def test_the_peer_process_starts_searches_and_is_reaped(branching: None) -> None:
    problem = random_sop(26, 0.05, 0)
    peer = _ready(problem, in_thread=False)
    split = solve_sop_bc(problem, peer=peer)
    assert split.status == "optimal"
    assert split.objective == solve_sop_bc(problem).objective
    assert split.info["peer"]["startup"] is not None and split.info["peer"]["loaded"]
    assert not peer.process.is_alive() and peer.process.exitcode is not None


def test_an_unloaded_peer_is_killed_and_reaped() -> None:
    """A tree closed before its peer process was ready (a 12-node SOP, closed in well under
    the process's start-up) does not load it and leaves no process behind."""
    problem = random_sop(12, 0.1, 0)
    peer = Peer(problem, None)
    result = solve_sop_bc(problem, peer=peer)
    assert result.status == "optimal"
    assert result.info["peer"]["loaded"] is False and "split" not in result.info
    assert not peer.process.is_alive() and peer.process.exitcode is not None


def test_split_wanted_is_off_in_a_pool_worker(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TAOPT_SOLVER_THREADS", "1")
    assert not sop_split.split_wanted()
    monkeypatch.delenv("TAOPT_SOLVER_THREADS")
    monkeypatch.setattr(sop_split, "SPLIT", False)
    assert not sop_split.split_wanted()


def test_the_outside_bound_counts_batches_in_flight() -> None:
    """The main side's bound of the nodes outside: the peer's report, and every batch sent
    that the report does not yet include (by number)."""
    link = sop_split.Link(None, main=True)
    link.flight = {1: 10.0, 2: 7.0}
    link.peer_bound = 12.0
    assert link.outside() == 7.0
    link._report(11.0, 1)  # batch 1 taken in: 2 still on its way
    assert link.flight == {2: 7.0} and link.outside() == 7.0
    link._report(np.inf, 2)
    assert link.outside() == math.inf


def test_rows_installed_in_the_peer_are_known_there() -> None:
    """The rows and fixings the peer's model takes in (``SopCutModel.install``) are in its
    LP, in order, and known by their keys (``row_key``): sent again, none is added twice; the
    two LPs have the same optimum."""
    from taopt.models.sop_cuts import SopCutModel

    problem = random_sop(14, 0.1, 0)
    main = SopCutModel(problem)
    main.root(stretch=True)
    assert main.cut_rows
    main.fix_by_reduced_cost(main.dual_bound() + 3.0)
    fixed = np.flatnonzero(main.fixed)
    assert len(fixed)
    peer = SopCutModel(problem)
    peer.install(main.cut_rows, main.cut_sides, main.cut_weights, fixed, main.conditional)
    assert peer.highs.getNumRow() == main.highs.getNumRow()
    assert (peer.fixed == main.fixed).all() and peer.conditional == main.conditional
    plain = [k for k, weights in enumerate(main.cut_weights) if weights is None]
    assert plain
    assert peer.add_cuts([main.cut_rows[k] for k in plain], [main.cut_sides[k] for k in plain]) == 0
    weighted = [k for k, weights in enumerate(main.cut_weights) if weights is not None]
    assert weighted  # the stretch rows
    again = [(main.cut_rows[k], main.cut_weights[k], main.cut_sides[k]) for k in weighted]
    assert peer.add_weighted_rows(again) == 0
    main.highs.run()
    peer.highs.run()
    assert peer.highs.getInfo().objective_function_value == pytest.approx(
        main.highs.getInfo().objective_function_value
    )


def test_the_peer_runs_the_stretch_rows_and_they_reach_this_side() -> None:
    """With a peer the tree's root skips the stretch rows (``SPLIT_STRETCH`` off) and asks the
    peer for them: the peer runs them before it takes nodes and sends them at its first
    look, and they enter this side's LP (weighted rows, the LP's row count with them)."""
    from taopt.models.sop_cuts import root_stage
    from taopt.runtime import Deadline

    problem = random_sop(26, 0.05, 0)
    assert solve_sop_bc(problem).info["root_stretch_lps"] > 0  # the tree alone runs them
    model, known, _, info = root_stage(problem, Deadline(None), stretch=False)
    assert info["root_stretch_lps"] == 0
    tree = sop_bc.BranchCut(model, known)
    peer = _ready(problem)
    peer.stretch = True
    link = peer.load(tree)
    assert link is not None
    rows = model.highs.getNumRow()
    until = time.perf_counter() + 60
    while not any(weights is not None for weights in model.cut_weights):
        assert time.perf_counter() < until, "no stretch row came"
        link.poll(tree)
        time.sleep(0.005)
    added = sum(weights is not None for weights in model.cut_weights)
    assert model.highs.getNumRow() >= rows + added and link.rows_taken >= added
    peer.close(tree)
    assert tree.peer_counts is not None and not peer.process.is_alive()


def test_a_tree_with_a_peer_asks_it_for_the_stretch_rows() -> None:
    problem = random_sop(26, 0.05, 0)
    peer = _ready(problem)
    split = solve_sop_bc(problem, peer=peer)
    assert split.info["root_stretch_lps"] == 0 and peer.stretch
    assert split.status == "optimal" and split.objective == solve_sop_bc(problem).objective
