"""Proving a known optimum (issue 33): the DP at a trial cutoff (a finished run proves the cutoff
or finds an order below it), its give-up rule, and the portfolio's proof stage, on random tiny
SOPs checked against the brute force, forward, backward and meeting."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from taopt.models.sop_cuts import SopCutModel
from taopt.models.sop_dp import solve_sop_dp
from taopt.models.sop_statelp import StateLp
from taopt.models.sop_window import window_prices
from taopt.result import OPTIMAL, TIME_LIMIT
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders
from tests.sop.test_sop_credit import _clustered


def _instance(seed: int) -> SopProblem:
    """Even seeds: the shared tiny SOPs; odd seeds: clustered ones with precedences."""
    return sop_instance(seed) if seed % 2 == 0 else _clustered(seed)


def _worst(problem: SopProblem) -> list[int]:
    """The dearest feasible order (an incumbent far from the optimum)."""
    return max(sop_orders(problem), key=lambda o: evaluate_order(problem, o))


@pytest.mark.parametrize("seed", range(24))
@pytest.mark.parametrize("both", [True, False])
def test_cutoff_below_the_optimum_proves_at_most_the_optimum(seed, both):
    """A cutoff at or below the optimum: the run ends without a cheaper order and proves a
    bound at least the cutoff (within 1e-9) and at most the brute-force optimum."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    worst = _worst(problem)
    for cutoff in (optimum, optimum - 1.0, optimum - 7.5, 0.5 * optimum):
        result = solve_sop_dp(problem, incumbent=worst, beam_width=0, both=both, cutoff=cutoff)
        assert result.bound is not None and result.bound <= optimum + 1e-6
        if result.objective > optimum + 1e-6:  # the worst order was kept: nothing below
            assert result.status == TIME_LIMIT
            assert result.info["cutoff_proven"]
            assert result.bound >= cutoff - 1e-9 * abs(cutoff) - 1e-9


@pytest.mark.parametrize("seed", range(24))
@pytest.mark.parametrize("both", [True, False])
def test_cutoff_above_the_optimum_finds_and_proves_it(seed, both):
    """A cutoff above the optimum (and below the incumbent) finds an optimal order and proves
    it: status optimal, the brute-force value, a feasible order."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    worst = _worst(problem)
    for cutoff in (optimum + 0.5, 0.5 * (optimum + evaluate_order(problem, worst))):
        if not cutoff < evaluate_order(problem, worst):
            continue
        result = solve_sop_dp(problem, incumbent=worst, beam_width=0, both=both, cutoff=cutoff)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(12))
def test_cutoff_with_root_prices_and_state_lp_stays_valid(seed):
    """With the root's Lagrangian prices, row credit and the per-state LP, a cutoff at the
    optimum proves a bound never above it, and one just above finds it."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    model = SopCutModel(problem)
    model.root()
    kwargs = {"lagrange": model.lagrangian_prices(), "credit": model.row_credit()}
    for cutoff in (optimum, optimum + 0.5):
        result = solve_sop_dp(
            problem, beam_width=0, cutoff=cutoff, state_lp=StateLp(model), **kwargs
        )
        assert result.bound is not None and result.bound <= optimum + 1e-6
        if cutoff > optimum:
            assert result.status == OPTIMAL and result.objective == pytest.approx(optimum)
        else:
            assert result.status == TIME_LIMIT and result.info["cutoff_proven"]


def test_cutoff_without_an_incumbent_returns_no_order_but_the_bound():
    """A finished run at a cutoff below the optimum, without an incumbent, has no order and
    proves at least the cutoff."""
    problem = _instance(2)
    optimum = sop_brute_force(problem)
    result = solve_sop_dp(problem, beam_width=0, cutoff=optimum - 1.0)
    assert result.status == TIME_LIMIT and result.solution is None
    assert optimum - 1.0 - 1e-6 <= result.bound <= optimum


@pytest.mark.parametrize("seed", range(12))
def test_give_up_keeps_a_valid_bound_and_an_ended_run_is_optimal(seed, monkeypatch):
    """With the give-up rule (made to fire on any growth), the DP with the per-state LP either
    proves the brute-force optimum or stops "time_limit" with a bound at most the optimum and
    says why."""
    from taopt.models import sop_dp

    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    model = SopCutModel(problem)
    model.root()
    kwargs = {"lagrange": model.lagrangian_prices(), "credit": model.row_credit()}
    for growth in (sop_dp.GIVE_UP_GROWTH, 0.5):
        monkeypatch.setattr(sop_dp, "GIVE_UP_GROWTH", growth)
        result = solve_sop_dp(
            problem,
            incumbent=_worst(problem),
            beam_width=0,
            state_lp=StateLp(model),
            give_up=True,
            **kwargs,
        )
        assert result.bound is not None and result.bound <= optimum + 1e-6
        if result.status == OPTIMAL:
            assert result.objective == pytest.approx(optimum)
        else:
            assert result.status == TIME_LIMIT and result.info["gave_up"]


def test_give_up_fires_on_a_growing_layer(monkeypatch):
    """A layer past the first that grows more than GIVE_UP_GROWTH times stops the search, and
    the reason names the layer."""
    from taopt.models import sop_dp

    monkeypatch.setattr(sop_dp, "GIVE_UP_GROWTH", 0.5)
    problem = _clustered(3, n=9)
    model = SopCutModel(problem)
    model.root()
    result = solve_sop_dp(
        problem,
        incumbent=_worst(problem),
        beam_width=0,
        lagrange=model.lagrangian_prices(),
        credit=model.row_credit(),
        state_lp=StateLp(model),
        give_up=True,
    )
    if result.status == TIME_LIMIT:
        assert "layer" in result.info["gave_up"]
        assert result.bound <= sop_brute_force(problem) + 1e-6


@pytest.mark.parametrize("seed", range(8))
def test_portfolio_proof_stage_proves_the_brute_force_optimum(seed, monkeypatch):
    """The portfolio with the root stage forced (ideals taken as too many) and the proof stage
    run at any gap proves the brute-force optimum, and says the proof stage ran."""
    from taopt.models import sop

    monkeypatch.setattr(sop, "PROOF_GAP", 1.0)
    monkeypatch.setattr(sop, "CUTS_FIRST_SHARE", 2.0)  # the DP path, never the cut engine first
    result = _checked_run(seed)
    if result is None:
        return
    assert isinstance(result.info["proof"], dict)


def test_portfolio_skips_the_proof_stage_on_a_wide_gap(monkeypatch):
    """With PROOF_GAP below 0 and no trial cutoffs the proof stage never runs (its reason is
    recorded) and the portfolio still proves the optimum."""
    from taopt.models import sop

    monkeypatch.setattr(sop, "PROOF_GAP", -1.0)
    monkeypatch.setattr(sop, "TRIAL_CUTOFFS", False)
    problem = _instance(5)
    result = sop.solve_sop_problem(problem, ideal_cap=1, cpsat=False, incumbent=_worst(problem))
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(sop_brute_force(problem))
    assert "proof" not in result.info or isinstance(result.info["proof"], str)


@pytest.mark.parametrize("seed", range(16))
def test_saved_root_prices_bound_every_order(seed):
    """A root loop stopped after adding rows (a round limit) has no LP solution; the prices of
    its last optimal LP (``saved=True``) give ``L + Σ max(d_a, 0)`` at most every order's cost,
    and the DP with them and their row credit proves the brute-force optimum."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    model = SopCutModel(problem)
    model.root(rounds=1)
    prices = model.lagrangian_prices(saved=True)
    credit = model.row_credit(saved=True)
    assert prices is not None and credit is not None
    constant, reduced = prices
    positive = np.maximum(np.nan_to_num(reduced, posinf=0.0), 0.0)
    for order in sop_orders(problem):
        arcs = positive[order[:-1], order[1:]]
        assert constant + arcs.sum() <= evaluate_order(problem, order) + 1e-6
    result = solve_sop_dp(
        problem, incumbent=_worst(problem), beam_width=0, lagrange=prices, credit=credit
    )
    assert result.status == OPTIMAL and result.objective == pytest.approx(optimum)


def test_constraint_matrix_reads_either_format():
    """The row matrix of a HiGHS LP is the same whether HiGHS holds it column-wise or row-wise
    (as it may after an LP it stopped)."""
    import highspy
    import scipy.sparse as sp

    from taopt.models.sop_statelp import constraint_matrix

    dense = np.array([[1.0, 0.0, 2.0], [0.0, 3.0, 4.0]])
    for form, made in ((highspy.MatrixFormat.kColwise, sp.csc_matrix(dense)),
                       (highspy.MatrixFormat.kRowwise, sp.csr_matrix(dense))):  # fmt: skip
        lp = highspy.HighsLp()
        lp.num_col_, lp.num_row_ = 3, 2
        lp.a_matrix_.format_ = form
        lp.a_matrix_.start_ = made.indptr.astype(np.int32)
        lp.a_matrix_.index_ = made.indices.astype(np.int32)
        lp.a_matrix_.value_ = made.data
        assert (constraint_matrix(lp).toarray() == dense).all()


def _trials(
    seed: int, step: float, slack: float = 0.0, window: bool = False
) -> tuple[SopProblem, float, object] | None:
    """:func:`trial_cutoffs` on SOP ``seed`` from its dearest order and its root bound less
    ``slack`` times its size plus ``slack`` (a weaker valid bound: more trials), with
    ``TRIAL_STEP`` = ``step`` (and, with ``window``, the position-window prices of a
    subgradient aimed at that order's cost); None when the SOP has no order."""
    from taopt.models import sop_dp

    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return None
    model = SopCutModel(problem)
    root = model.root()
    lagrange, credit = model.lagrangian_prices(), model.row_credit()
    worst = _worst(problem)
    lam = window_prices(problem, evaluate_order(problem, worst)).lam if window else None
    old = sop_dp.TRIAL_STEP
    sop_dp.TRIAL_STEP = step
    try:
        found = sop_dp.trial_cutoffs(
            problem,
            worst,
            root.bound - slack * (abs(root.bound) + 1),
            None,
            StateLp(model, share=1.0),
            lagrange,
            credit,
            window=lam,
        )
    finally:
        sop_dp.TRIAL_STEP = old
    return problem, optimum, found


@pytest.mark.parametrize("seed", range(16))
@pytest.mark.parametrize("step", [0.01, 0.2])
@pytest.mark.parametrize("slack", [0.0, 0.3])
@pytest.mark.parametrize("window", [False, True])
def test_trial_cutoffs_prove_at_most_the_optimum(seed, step, slack, window):
    """The trial cutoffs (steps of 1 % and 20 % of the bound) from the dearest order and the
    root bound (or a weaker one), with and without the window prices:
    every bound they prove is at most the brute-force optimum, their order is scored right, and
    an optimal answer is the optimum; each trial's cutoff proven is at most the optimum."""
    got = _trials(seed, step, slack, window)
    if got is None:
        return
    problem, optimum, found = got
    assert found.bound is not None and found.bound <= optimum + 1e-6
    assert evaluate_order(problem, found.order) == pytest.approx(found.objective)
    if found.status == OPTIMAL:
        assert found.objective == pytest.approx(optimum)
    for trial in found.info["trials"]:
        if trial["proven"]:
            assert trial["cutoff"] <= optimum + 1e-6


def test_trial_cutoffs_prove_and_find():
    """On the tiny SOPs the trials both prove cutoffs below the optimum and end optimal (the
    paths of :func:`test_trial_cutoffs_prove_at_most_the_optimum` are exercised)."""
    proven = optimal = 0
    for seed in range(8):
        got = _trials(seed, 0.01, 0.3, window=seed % 2 == 1)
        if got is None:
            continue
        found = got[2]
        proven += sum(t["proven"] for t in found.info["trials"])
        optimal += found.status == OPTIMAL
    assert proven > 0 and optimal > 0


def _portfolio_with_trials(seed: int, monkeypatch) -> tuple[float, object] | None:
    """The portfolio on SOP ``seed`` with the trial cutoffs at every gap (PROOF_GAP below 0),
    its DP stages without the per-state LP stopped after their first state and a root loop of
    one round (so that a gap is left for the trials); ``(optimum, result)``, None
    without an order."""
    from taopt.models import sop, sop_dp

    plain = sop_dp.solve_sop_dp

    def stopped_early(*args, **kwargs):
        if kwargs.get("state_lp") is None:  # a DP stage, not a trial
            kwargs["max_states"] = 1
        return plain(*args, **kwargs)

    root = SopCutModel.root

    def one_round(self, deadline=None, rounds=1):  # a weaker root: a gap to trial
        return root(self, deadline, rounds=1)

    monkeypatch.setattr(sop_dp, "solve_sop_dp", stopped_early)
    monkeypatch.setattr(SopCutModel, "root", one_round)
    monkeypatch.setattr(sop, "PROOF_GAP", -1.0)
    monkeypatch.setattr(sop, "CUTS_FIRST_SHARE", 2.0)  # the DP path, never the cut engine first
    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", True)  # the trials, though the tree follows
    result = _checked_run(seed)
    return None if result is None else (result.objective, result)


def test_portfolio_trial_cutoffs_prove_the_brute_force_optimum(monkeypatch):
    """The portfolio with the trial cutoffs proves the brute-force optimum (checks of
    :func:`_portfolio_with_trials`), and the trials ran (where the root had not closed the
    gap already)."""
    ran = 0
    for seed in range(6):
        got = _portfolio_with_trials(seed, monkeypatch)
        if got is not None:
            ran += "proof_trials" in got[1].info
    assert ran > 0


def test_trials_wanted_only_without_the_tree_next(monkeypatch):
    """The rule of :func:`taopt.models.sop.trials_wanted`: no trial cutoffs where the tree
    follows a complete root loop (unless TRIALS_BEFORE_TREE); they run where the tree does not
    follow or the root loop was cut short; never without TRIAL_CUTOFFS."""
    from taopt.models import sop

    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", False)
    monkeypatch.setattr(sop, "TRIAL_CUTOFFS", True)
    assert not sop.trials_wanted(tree_next=True, root_complete=True)
    assert sop.trials_wanted(tree_next=True, root_complete=False)
    assert sop.trials_wanted(tree_next=False, root_complete=True)
    assert sop.trials_wanted(tree_next=False, root_complete=False)
    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", True)
    assert sop.trials_wanted(tree_next=True, root_complete=True)
    monkeypatch.setattr(sop, "TRIAL_CUTOFFS", False)
    for tree_next in (True, False):
        for complete in (True, False):
            assert not sop.trials_wanted(tree_next, complete)


def _rule_setting(monkeypatch, tree_first: bool) -> None:
    """The setting of the trial and tree-first rules' portfolio tests: a weaker root (one
    round) taken as complete within its share, every gap wide (``PROOF_GAP`` -1), the cut
    engine never first; ``TREE_FIRST`` as given."""
    from taopt.models import sop

    root = SopCutModel.root

    def one_round(self, deadline=None, rounds=1, **kwargs):  # a weaker root: a gap left
        return root(self, deadline, rounds=1, **kwargs)

    stage = sop._root_stage

    def complete(*args, **kwargs):  # taken as complete: the rules' case
        got = stage(*args, **kwargs)
        args[3]["root_stage"]["complete"] = True
        return got

    monkeypatch.setattr(SopCutModel, "root", one_round)
    monkeypatch.setattr(sop, "_root_stage", complete)
    monkeypatch.setattr(sop, "PROOF_GAP", -1.0)
    monkeypatch.setattr(sop, "CUTS_FIRST_SHARE", 2.0)
    monkeypatch.setattr(sop, "TREE_FIRST", tree_first)


def _checked_run(seed: int):
    """The portfolio (no CP-SAT, ideals taken as too many, the worst order as the warm start)
    on the tiny SOP of ``seed``, checked against brute force (optimal, the optimum, its order
    so scored); None when the SOP has no order."""
    from taopt.models import sop

    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return None
    result = sop.solve_sop_problem(problem, ideal_cap=1, cpsat=False, incumbent=_worst(problem))
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)
    return result


def _rule_runs():
    """:func:`_checked_run` on seeds 0-5, the SOPs that have an order."""
    for seed in range(6):
        result = _checked_run(seed)
        if result is not None:
            yield result


def _tree_first_runs(monkeypatch, name: str, value):
    """The runs of :func:`_rule_runs` that took the tree-first path, with the module constant
    ``name`` of :mod:`taopt.models.sop` set to ``value``; at least one does."""
    from taopt.models import sop

    monkeypatch.setattr(sop, name, value)
    straight = 0
    for result in _rule_runs():
        if result.info.get("tree_first"):
            straight += 1
            yield result
    assert straight > 0


def test_portfolio_gives_the_trials_time_to_the_tree(monkeypatch):
    """On the tiny SOPs of :func:`_portfolio_with_trials`'s setting but with the rule's
    default (the tree follows: no trials), the portfolio runs no trial cutoff, still proves
    the brute-force optimum, reports its stages' seconds, and some run reached the cut engine
    past a proof stage skipped on its gap (the rule's path was taken; the one-round root loop
    taken as complete)."""
    from taopt.models import sop_dp

    plain = sop_dp.solve_sop_dp

    def stopped_early(*args, **kwargs):
        if kwargs.get("state_lp") is None:  # a DP stage, not a trial
            kwargs["max_states"] = 1
        return plain(*args, **kwargs)

    monkeypatch.setattr(sop_dp, "solve_sop_dp", stopped_early)
    _rule_setting(monkeypatch, tree_first=False)  # the DP stages first, then the tree
    reached = 0
    for result in _rule_runs():
        assert "proof_trials" not in result.info
        stages = result.info["stage_seconds"]
        assert "root" in stages and all(v >= 0.0 for v in stages.values())
        assert sum(stages.values()) <= result.runtime + 1e-6
        skipped = str(result.info.get("proof", "")).startswith("skipped: the gap")
        reached += skipped and "milp" in result.info["engine"]
    assert reached > 0


def test_tree_first_where_the_trials_leave_the_gap_to_the_tree(monkeypatch):
    """The rule of :func:`taopt.models.sop.tree_first`: only on a gap above PROOF_GAP, where
    :func:`taopt.models.sop.trials_wanted` leaves it to the tree; never with TREE_FIRST off."""
    from taopt.models import sop

    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", False)
    monkeypatch.setattr(sop, "TRIAL_CUTOFFS", True)
    monkeypatch.setattr(sop, "TREE_FIRST", True)
    wide, narrow = sop.PROOF_GAP + 0.01, sop.PROOF_GAP / 2
    assert sop.tree_first(tree_next=True, root_complete=True, gap=wide)
    assert not sop.tree_first(tree_next=True, root_complete=True, gap=narrow)
    assert not sop.tree_first(tree_next=True, root_complete=False, gap=wide)
    assert not sop.tree_first(tree_next=False, root_complete=True, gap=wide)
    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", True)
    assert not sop.tree_first(tree_next=True, root_complete=True, gap=wide)
    monkeypatch.setattr(sop, "TRIALS_BEFORE_TREE", False)
    monkeypatch.setattr(sop, "TREE_FIRST", False)
    assert not sop.tree_first(tree_next=True, root_complete=True, gap=wide)


def test_portfolio_tree_first_proves_the_brute_force_optimum(monkeypatch):
    """With a weak root (one round) taken as complete and a wide gap, the portfolio skips the
    DP stages for the tree (TREE_FIRST, ``info["tree_first"]``, engine "milp", no DP stage's
    seconds) and still ends at the brute-force optimum, its order scored as reported."""

    _rule_setting(monkeypatch, tree_first=True)
    straight = 0
    for result in _rule_runs():
        if result.info.get("tree_first"):
            straight += 1
            assert result.info["engine"] == "milp"
            assert "dp" not in result.info["stage_seconds"]
    assert straight > 0


def test_tree_first_searches_only_on_a_wide_gap(monkeypatch):
    """The portfolio on the tree-first path, on either side of
    :data:`taopt.models.sop.TREE_FIRST_SEARCH_GAP`: the primal search before the tree where
    the gap is wide (``info["ils"]`` its counts), none where it is not (``info["ils"]`` says
    why it was skipped); either way the cut engine is
    warm-started with an order at most the beams' (here made an optimal one after a root
    stage that leaves the dearest: the beams' order is not dropped with the search) and the
    run ends at the brute-force optimum."""
    from taopt.models import sop, sop_bc, sop_cuts
    from taopt.result import Order

    _rule_setting(monkeypatch, tree_first=True)
    beams: list[float] = []
    starts: list[float] = []
    stage = sop._root_stage

    def worst_after(problem, *args, **kwargs):  # the root stage leaves the dearest order
        got = stage(problem, *args, **kwargs)
        return got[0], got[1], Order(_worst(problem)), got[3]

    def recorded(problem, *args, **kwargs):  # the beams find an optimal order
        best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
        beams.append(evaluate_order(problem, best))
        return beams[-1], list(best)

    def warm(engine):
        def run(problem, time_left, known, *args, **kwargs):
            starts.append(evaluate_order(problem, list(known)))
            return engine(problem, time_left, known, *args, **kwargs)

        return run

    monkeypatch.setattr(sop, "_root_stage", worst_after)
    monkeypatch.setattr(sop, "_beamed", recorded)
    monkeypatch.setattr(sop_bc, "solve_sop_bc", warm(sop_bc.solve_sop_bc))
    monkeypatch.setattr(sop_cuts, "solve_sop_cuts", warm(sop_cuts.solve_sop_cuts))
    for gap, searched in ((-1.0, True), (math.inf, False)):
        for result in _tree_first_runs(monkeypatch, "TREE_FIRST_SEARCH_GAP", gap):
            assert ("search" in result.info["stage_seconds"]) == searched
            assert isinstance(result.info["ils"], dict) == searched
            if not searched:
                assert result.info["ils"].startswith("skipped: the gap is")
            assert starts[-1] <= beams[-1] + 1e-9  # this run's: each appends once


def test_tree_first_skips_the_window_stage_unless_asked(monkeypatch):
    """On the tree-first path the window stage does not run (``TREE_FIRST_WINDOW`` off: no
    "window" stage, ``info["window"]`` says why) and runs with it on; the brute-force optimum
    either way (:func:`_checked_run`)."""
    _rule_setting(monkeypatch, tree_first=True)
    for asked in (False, True):
        for result in _tree_first_runs(monkeypatch, "TREE_FIRST_WINDOW", asked):
            assert ("window" in result.info["stage_seconds"]) == asked
            assert str(result.info["window"]).startswith("skipped") != asked


def test_tree_first_splits_the_tree_with_a_peer(monkeypatch):
    """On the tree-first path the tree gets a peer (:data:`taopt.models.sop.TREE_SPLIT`;
    here in a thread, made ready before the tree starts) and still ends at the brute-force
    optimum; with the split off, no peer."""
    from taopt.models import sop_split

    made: list[sop_split.Peer] = []
    plain = sop_split.Peer

    def ready_peer(problem, seconds):
        peer = plain(problem, seconds, in_thread=True)
        while not peer.poll_ready():
            time.sleep(0.002)
        made.append(peer)
        return peer

    monkeypatch.setattr(sop_split, "Peer", ready_peer)
    _rule_setting(monkeypatch, tree_first=True)
    for result in _tree_first_runs(monkeypatch, "TREE_SPLIT", True):
        assert result.info["tree_split"] == "on"
        if result.info.get("cut_engine") == "tree":
            assert result.info["tree_peer"]["loaded"]
    assert made and all(not peer.process.is_alive() for peer in made)
    count = len(made)
    for result in _tree_first_runs(monkeypatch, "TREE_SPLIT", False):
        assert result.info["tree_split"] == "off"
    assert len(made) == count


def test_tree_peer_rule(monkeypatch):
    """:func:`taopt.models.sop._tree_peer`: no peer with too little time left (and no call to
    ``on_tree``: CP-SAT keeps its core), else ``on_tree`` first, then the peer."""
    from taopt.models import sop, sop_split
    from taopt.runtime import Deadline

    calls: list[str] = []
    monkeypatch.setattr(sop_split, "Peer", lambda problem, seconds: calls.append("peer") or "p")
    monkeypatch.setattr(sop_split, "split_wanted", lambda: True)
    info: dict = {}
    problem = _instance(0)
    short = Deadline(sop.TREE_SPLIT_MIN_SECONDS / 2)
    assert sop._tree_peer(problem, short, lambda: calls.append("tree"), info) is None
    assert calls == [] and info["tree_split"].startswith("off")
    assert sop._tree_peer(problem, Deadline(60), lambda: calls.append("tree"), info) == "p"
    assert calls == ["tree", "peer"] and info["tree_split"] == "on"
