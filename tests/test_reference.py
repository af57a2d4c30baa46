"""Every registered method on every reference problem (tests/reference.py)."""

from __future__ import annotations

import pytest
from reference import REFERENCES, REL, cases, check_method  # noqa: I001

import taopt


@pytest.mark.parametrize(
    "make, method", cases(), ids=[f"{make.__name__}-{method}" for make, method in cases()]
)
def test_method_on_reference(make, method):
    """Exact methods hit the known optimum; the others are feasible and never below it."""
    check_method(make(), method)


@pytest.mark.parametrize("make", REFERENCES, ids=[m.__name__ for m in REFERENCES])
def test_bounds_on_reference(make):
    """Every valid bound a family registers is at most the known optimum."""
    reference = make()
    family = taopt.registry.family_of(reference.problem)
    if "arborescence" in family.bounds:
        bound = taopt.bounds.arborescence(reference.problem)
        assert bound <= reference.optimum * (1 + REL) + 1e-9


def test_every_family_has_a_reference():
    """A newly registered family needs a reference problem here."""
    covered = {taopt.registry.family_of(make().problem).problem_type for make in REFERENCES}
    registered = {f.problem_type for f in taopt.registry.families()}
    missing = sorted(t.__name__ for t in registered - covered)
    assert not missing, f"no reference problem for {missing}"
