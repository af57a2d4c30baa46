"""taopt.check_formulation: wrong textbook models get a small counterexample, right ones none."""

from __future__ import annotations

import numpy as np
import pytest
import reference
import teaching_models as tm
from conftest import ROOT

import taopt
from taopt.errors import InstanceError
from taopt.orchestration.checker import FAILURES, shrink_steps
from taopt.orchestration.solving import load_problem_file

ROUTING = "assignment_problem"
DELIVERY = "delivery_instance"


def _shown_in_docs(report) -> bool:
    """The report's lines (but the plans, which may tie, and the saved path) appear in
    docs/export-and-checker.md, which prints it."""
    page = (ROOT / "docs" / "export-and-checker.md").read_text(encoding="utf-8")
    lines = [
        line for line in str(report).splitlines() if "plan:" not in line and "saved:" not in line
    ]
    return "\n".join(lines[:4]) in page and "\n".join(lines[4:]) in page


def _references(kind: str) -> list:
    """The reference problems of tests/reference.py of one family."""
    problems = [make().problem for make in reference.REFERENCES]
    return [p for p in problems if type(p).__name__ == kind]


@pytest.mark.parametrize(
    ("build", "family", "failed", "why"),
    [
        (tm.mtz_no_start_rows, ROUTING, "infeasible plan", "never visited ((2.3))"),
        (tm.dfj_pairs_only, ROUTING, "infeasible plan", "never visited ((2.3))"),
        (tm.drone_without_range, DELIVERY, "infeasible plan", "(5.6)"),
    ],
    ids=["mtz-without-start-rows", "subtour-rows-for-pairs-only", "truck-drone-without-5.6"],
)
def test_wrong_textbook_model_gets_a_small_counterexample(build, family, failed, why, tmp_path):
    """Each of the three wrong models: a counterexample of at most 5 targets/customers, the
    failed property named, the violated constraint from evaluate, the instance saved."""
    out = tmp_path / "counterexample.json"
    report = taopt.check_formulation(build, family, trials=20, seed=0, out=out)
    assert report.failed == failed and why in report.detail
    items = report.sizes.get("targets", report.sizes.get("customers"))
    assert items is not None and items <= 5
    assert report.path == out
    saved, _ = load_problem_file(out, progress=False)  # through the schema
    assert type(saved) is type(report.instance)
    assert taopt.solve(saved, "exact").objective == pytest.approx(report.optimum, rel=1e-6)
    with pytest.raises(taopt.FeasibilityError):
        taopt.evaluate(report.instance, report.student_plan)
    text = str(report)
    assert f"failed property: {failed}" in text and "optimal plan" in text
    assert _shown_in_docs(report)


def test_counterexample_is_minimal_by_one_removal():
    """No instance one target or vehicle smaller than the counterexample still disagrees."""
    report = taopt.check_formulation(tm.dfj_pairs_only, ROUTING, trials=20, seed=0)
    assert report.sizes["targets"] == 3  # a subtour of |S| = 3 is the smallest the rows miss
    for smaller in shrink_steps(report.instance):
        again = taopt.check_formulation(tm.dfj_pairs_only, ROUTING, trials=0, instances=[smaller])
        assert again.ok


def test_objective_too_low_for_a_missing_cost_term():
    """A model whose plans are feasible but whose objective forgets the first legs is
    'objective too low'."""
    report = taopt.check_formulation(tm.forgets_start_legs, ROUTING, trials=20, seed=0)
    assert report.failed == "objective too low"
    assert report.student_objective < report.optimum
    assert taopt.evaluate(report.instance, report.student_plan) >= report.optimum - 1e-9
    assert _shown_in_docs(report)


def test_over_constraint_is_too_high_or_infeasible():
    """(2.4) at the starts written '= 1' cuts off idle vehicles: objective too high, or no
    solution when vehicles outnumber targets; shrunk to a single target."""
    report = taopt.check_formulation(tm.every_vehicle_leaves, ROUTING, trials=20, seed=0)
    assert report.failed in ("objective too high", "student model infeasible/unbounded")
    assert report.sizes["targets"] == 1 and report.sizes["vehicles"] == 2
    assert report.failed in FAILURES
    assert _shown_in_docs(report)


@pytest.mark.parametrize("build", [tm.mtz_complete, tm.toolkit_routing], ids=["mtz", "toolkit"])
def test_correct_routing_model_has_no_counterexample(build):
    """The same textbook model with its start rows, and the toolkit's own model: none in 20
    random instances, the packaged example and the reference instances."""
    report = taopt.check_formulation(
        build, ROUTING, trials=20, seed=1, instances=_references("AssignmentProblem")
    )
    assert report.ok, str(report)
    assert report.tried == 20 + 1 + len(_references("AssignmentProblem"))


def test_correct_delivery_model_has_no_counterexample():
    """The toolkit's truck-drone model (with (5.6)): none in 20 random instances."""
    report = taopt.check_formulation(tm.toolkit_delivery, DELIVERY, sizes=(2, 3), trials=20)
    assert report.ok, str(report)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("build", "family"),
    [(tm.mtz_complete, ROUTING), (tm.toolkit_routing, ROUTING), (tm.toolkit_delivery, DELIVERY)],
    ids=["mtz", "toolkit-routing", "toolkit-delivery"],
)
def test_correct_models_survive_200_trials(build, family):
    """The correct models: no counterexample in 200 random instances (sizes 2-5) and the
    family's reference instances."""
    kind = "AssignmentProblem" if family == ROUTING else "DeliveryInstance"
    references = _references(kind)
    report = taopt.check_formulation(build, family, trials=200, seed=7, instances=references)
    assert report.ok, str(report)
    assert report.tried == 200 + len(references) + 1


def test_same_seed_same_report():
    """The same seed gives the same counterexample."""
    first = taopt.check_formulation(tm.mtz_no_start_rows, ROUTING, trials=20, seed=3)
    second = taopt.check_formulation(tm.mtz_no_start_rows, ROUTING, trials=20, seed=3)
    assert first.failed == second.failed and first.tried == second.tried
    assert np.array_equal(first.instance.cost, second.instance.cost)


def test_unknown_family_is_refused():
    """A family the checker has no generator for is an InstanceError listing the ones it has."""
    with pytest.raises(InstanceError, match="assignment_problem"):
        taopt.check_formulation(tm.mtz_complete, "comm_problem")


def test_sop_models():
    """SOP: the toolkit's model agrees on 10 random instances; without its precedence rows the
    plan breaks a precedence, which evaluate names."""
    assert taopt.check_formulation(tm.toolkit_sop, "sop_problem", trials=10, seed=2).ok
    report = taopt.check_formulation(tm.sop_without_precedences, "SopProblem", trials=10)
    assert report.failed == "infeasible plan" and "precedence" in report.detail
    assert report.sizes["nodes"] <= 7
