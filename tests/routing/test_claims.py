"""Executable checks of chapter 2's claims (Lemmas 2.3-2.5, Theorems 2.6-2.7).

The checks must find counterexamples by themselves (random instances, exact
optimum by dynamic programming) and save the smallest as reloadable JSON.
What is asserted here: claims that are theorems for a class hold on every
sample of it, and every counterexample reported reloads and still fails.
"""

from __future__ import annotations

import numpy as np
import pytest

import taopt
import taopt.heuristics
from taopt.orchestration.studies import routing_claims as claims
from taopt.routing import bounds


@pytest.fixture(scope="module")
def cheap_table(tmp_path_factory):
    """120 instances per cheap class (n 2..6, m 1..3), counterexamples saved."""
    out = tmp_path_factory.mktemp("claims")
    table = claims.check_claims(
        samples=120,
        seed=0,
        out_dir=out,
        classes=("euclidean", "uniform-drift", "metric"),
        n_range=(2, 6),
    )
    return table


def row(table, claim_prefix, kind):
    match = table[table.claim.str.startswith(claim_prefix) & (table.instance_class == kind)]
    assert len(match) == 1, (claim_prefix, kind)
    return match.iloc[0]


def test_table_shape(cheap_table):
    assert set(cheap_table.instance_class) == {"euclidean", "uniform-drift", "metric"}
    assert (cheap_table.total == 120).all()
    assert (cheap_table.holds <= cheap_table.total).all()
    # f_da = 2 f_a only applies to the symmetric class.
    assert list(cheap_table[cheap_table.claim.str.contains("symmetric")].instance_class) == [
        "euclidean"
    ]


def test_theorems_that_hold_by_proof(cheap_table):
    """Lemma 2.3 holds by construction on all three classes; on Euclidean costs
    Algorithm 1 is Prim's MST (Lemma 2.4 true) and f_da = 2 f_a; Lemma 2.5's
    f_o <= f_da follows from the triangle inequality (doubled tree, shortcut)."""
    for kind in ("euclidean", "uniform-drift", "metric"):
        assert row(cheap_table, "Lemma 2.3", kind).holds == 120
        assert row(cheap_table, "Lemma 2.5 (f_o", kind).holds == 120
    assert row(cheap_table, "Lemma 2.4", "euclidean").holds == 120
    assert row(cheap_table, "Lemma 2.5 (f_da", "euclidean").holds == 120


def test_lemma_2_4_fails_on_asymmetric_costs_and_the_file_reloads(cheap_table):
    """The check finds f_a > f_o on asymmetric metric costs by itself."""
    for kind in ("uniform-drift", "metric"):
        found = row(cheap_table, "Lemma 2.4", kind)
        assert found.holds < found.total
        problem = taopt.AssignmentProblem.load(found.path)
        assert problem.n == found.smallest_n and problem.m == found.smallest_m
        f_o, routes = claims.exact_optimum(problem)
        assert bounds.thesis_mcga(problem) > f_o + 1e-9
        assert problem.evaluate(routes) == pytest.approx(f_o)  # a witness below f_a
        assert bounds.arborescence_bound(problem) <= f_o + 1e-9  # the valid bound is fine
        assert claims.still_violates(problem, found.claim)


def test_every_reported_counterexample_reloads_and_still_fails(cheap_table):
    reported = cheap_table[cheap_table.holds < cheap_table.total]
    assert len(reported) >= 2
    for _, found in reported.iterrows():
        problem = taopt.AssignmentProblem.load(found.path)
        assert claims.still_violates(problem, found.claim)
        # Independent of the DP: the certified MILP optimum gives the same verdict.
        assert claims.still_violates(problem, found.claim, exact="milp")
        assert np.allclose(problem.cost, found.instance.cost)


def test_theorem_2_7_counterexample_by_hand():
    """Theorem 2.7 (f_MC <= f_EVM) is false even for symmetric Euclidean costs.

    Found by ``check_claims`` (class "euclidean", n 3, m 2); distances rounded.
    Targets 0, 1, 2; vehicles at points 3 and 4.

    MC (2.15): t(3,2) = 7.24 is cheapest: target 2 -> vehicle 3. Next, target 0
    from vehicle 4 costs 16.31 (after target 2: 16.99; in front: 15.86 + 16.99
    - 7.24 = 25.61): target 0 -> vehicle 4. Last, target 1 after target 0 costs
    47.62 (from vehicle 3's end 64.09). f_MC = 7.24 + 16.31 + 47.62 = 71.17.

    EVM (2.12): target 2 joins vehicle 3 (7.24); target 0 is 15.86 from vehicle
    3's start (< 16.31, 16.99): cluster {0, 2}; target 1 is 33.37 from vehicle 4.
    (2.18) orders vehicle 3 as [2, 0] (7.24 + 16.99). f_EVM = 24.23 + 33.37 = 57.60.

    The proof's induction assumes both methods have assigned the same targets
    before the last one; here they differ after step 2.
    """
    cost = np.array(
        [
            [0.00, 47.62, 16.99, 15.86, 16.31],
            [47.62, 0.00, 64.09, 60.39, 33.37],
            [16.99, 64.09, 0.00, 7.24, 33.23],
            [15.86, 60.39, 7.24, 0.00, 31.78],
            [16.31, 33.37, 33.23, 31.78, 0.00],
        ]
    )
    problem = taopt.AssignmentProblem(cost, 3)
    mc = taopt.heuristics.run("MC", problem)
    evm = taopt.heuristics.run("EVM", problem)
    assert mc.routes == [[2], [0, 1]] and mc.objective == pytest.approx(71.17)
    assert evm.routes == [[2, 0], [1]] and evm.objective == pytest.approx(57.60)
    assert claims.triangle_violation(cost) <= 0  # still a metric
    assert claims.still_violates(problem, "Theorem 2.7 (f_MC <= f_EVM)")


def test_theorem_2_7_check_finds_its_own_counterexample(tmp_path):
    """On 300 metric instances the check finds MC > EVM without help."""
    table = claims.check_claims(samples=300, seed=1, out_dir=tmp_path, classes=("metric",))
    found = row(table, "Theorem 2.7", "metric")
    assert found.holds < found.total
    assert claims.still_violates(taopt.AssignmentProblem.load(found.path), found.claim)


def test_drift_class_uses_navigation():
    """A few thesis-field instances (navigation matrices): Lemma 2.3 within tolerance."""
    table = claims.check_claims(samples=6, seed=2, classes=("drift",), pool_reuse=6)
    assert row(table, "Lemma 2.3", "drift").holds == 6
    assert row(table, "Lemma 2.5 (f_o", "drift").holds == 6


def test_same_seed_same_table():
    first = claims.check_claims(samples=20, seed=5, classes=("metric",))
    second = claims.check_claims(samples=20, seed=5, classes=("metric",))
    assert first.drop(columns=["instance"]).equals(second.drop(columns=["instance"]))


def test_unknown_class_is_an_instance_error():
    from taopt.errors import InstanceError

    with pytest.raises(InstanceError, match="class"):
        claims.check_claims(samples=1, classes=("polar",))
