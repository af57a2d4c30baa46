"""Every registered method and every registered bound on every reference problem
(tests/reference.py)."""

from __future__ import annotations

import functools

import pytest
from conftest import upper_bounds, valid_lower_bounds
from reference import REFERENCES, REL, cases, check_method  # noqa: I001

import taopt
from taopt.registry import families, family_of


@functools.cache
def _references_by_family() -> dict[type, list]:
    """problem type -> the references of that family (built once)."""
    out: dict[type, list] = {}
    for make in REFERENCES:
        reference = make()
        out.setdefault(family_of(reference.problem).problem_type, []).append(reference)
    return out


def _family_ids() -> list[str]:
    return [f.problem_type.__name__ for f in families()]


@pytest.mark.parametrize(
    "make, method", cases(), ids=[f"{make.__name__}-{method}" for make, method in cases()]
)
def test_method_on_reference(make, method):
    """Exact methods hit the known optimum; the others are feasible and never below it."""
    check_method(make(), method)


@pytest.mark.parametrize("family", families(), ids=_family_ids())
def test_every_valid_lower_bound_is_at_most_the_optimum(family):
    """Every valid lower bound a family registers (each strength of ``lower``) is at most the
    known optimum of each of its reference problems."""
    references = _references_by_family().get(family.problem_type, [])
    bounds = valid_lower_bounds(family)
    assert references, f"no reference problem for {family.problem_type.__name__}"
    assert "lower" in bounds, f"{family.kind} registers no 'lower' bound"
    for reference in references:
        for name, bound in bounds.items():
            strengths = taopt.bounds.STRENGTHS if name == "lower" else (None,)
            for strength in strengths:
                value = (
                    bound(reference.problem)
                    if strength is None
                    else bound(reference.problem, strength)
                )
                assert value <= reference.optimum * (1 + REL) + 1e-9, (
                    reference.name, name, strength, value, reference.optimum
                )  # fmt: skip


@pytest.mark.parametrize("family", families(), ids=_family_ids())
def test_every_upper_bound_is_at_least_the_optimum(family):
    """Every registered upper bound (Lemma 3.6's doubled arborescence) is at least the known
    optimum of each reference problem of its family."""
    for reference in _references_by_family().get(family.problem_type, []):
        for name, bound in upper_bounds(family).items():
            value = bound(reference.problem)
            assert value >= reference.optimum * (1 - REL) - 1e-9, (reference.name, name, value)


def test_the_validity_rule_sees_every_kind_of_bound():
    """The rule is not vacuous: across the families it finds valid lower bounds other than
    ``lower``, and every upper bound it knows is registered by some family."""
    lower_names = {n for f in families() for n in valid_lower_bounds(f)}
    upper_names = {n for f in families() for n in upper_bounds(f)}
    assert {"lower", "arborescence", "mst"} <= lower_names
    assert "doubled_arborescence" in upper_names
    assert not lower_names & upper_names


def test_every_family_has_a_reference():
    """A newly registered family needs a reference problem here."""
    covered = set(_references_by_family())
    registered = {f.problem_type for f in families()}
    missing = sorted(t.__name__ for t in registered - covered)
    assert not missing, f"no reference problem for {missing}"


NAMED = [
    "ref_routing_small", "ref_routing_quick_tour", "ref_routing_one_way",
    "ref_routing_idle_vehicle", "ref_routing_asymmetric", "ref_capability", "ref_comm",
    "ref_delivery", "ref_sop", "ref_sop_esc12",
]  # fmt: skip


@pytest.mark.parametrize("name", NAMED)
def test_named_fixture_is_consistent(name, request):
    """A named reference's stored optimal payload scores exactly its optimum, and its optimum is
    never below the family's valid lower bound."""
    reference = request.getfixturevalue(name)
    if reference.solution is not None:
        assert taopt.evaluate(reference.problem, reference.solution) == pytest.approx(
            reference.optimum, rel=REL
        )
    assert taopt.bounds.lower(reference.problem, "fast") <= reference.optimum * (1 + REL) + 1e-9
