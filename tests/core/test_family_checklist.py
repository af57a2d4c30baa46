"""The add-a-family checklist of docs/architecture.md, checked for every registered family.

A family is found on disk and changes no existing file; what it must bring instead is listed
in docs/architecture.md ("Adding a family") and checked here, so the list stays true.
"""

from __future__ import annotations

import pytest
from conftest import DATA, ROOT
from reference import BRUTE_FORCE, REFERENCES

import taopt.orchestration.pipeline  # noqa: F401  (registers every method)
from taopt.registry import Family, families, family_of, methods
from taopt.result import payload_schemas

FAMILIES = {family.kind: family for family in families()}


def _package(family: Family) -> str:
    return family.problem_type.__module__.split(".")[1]


@pytest.mark.parametrize("kind", sorted(FAMILIES))
def test_family_has_kind_schema_example_scorer_and_payload_schema(kind):
    """Its schema file, an example that loads and round-trips, a scorer, a payload with a
    declared schema (the solution schema's payload kinds are built from these)."""
    family = FAMILIES[kind]
    assert (ROOT / "taopt" / "schemas" / f"{kind}.schema.json").is_file()
    example = DATA / "examples" / f"{kind}.json"
    assert example.is_file(), f"no example {example}"
    problem = family.problem_type.load(example)
    assert family_of(problem) is family
    assert family.load(family.to_dict(problem)).to_dict() == family.to_dict(problem)
    assert callable(family.evaluate)
    assert getattr(family.payload, "payload_kind", None) in payload_schemas()


@pytest.mark.parametrize("kind", sorted(FAMILIES))
def test_family_has_a_valid_lower_bound_a_plot_and_a_docs_page(kind):
    """At least one valid lower bound, a plot, and a page of docs/families/ (its own
    ``<package>.md``, or its chapter's) that names its problem type."""
    family = FAMILIES[kind]
    assert any(b.valid and b.side == "lower" for b in family.bounds.values())
    assert family.plots
    pages = sorted((ROOT / "docs" / "families").glob("*.md"))
    name = family.problem_type.__name__
    assert any(name in page.read_text(encoding="utf-8") for page in pages), (
        f"no page of docs/families/ names {name} (expected {_package(family)}.md)"
    )


@pytest.mark.parametrize("kind", sorted(FAMILIES))
def test_family_has_an_exact_method_references_and_a_brute_force_check(kind):
    """An exact method, a reference problem with a known optimum (tests/reference.py or
    tests/reference_<family>.py) and a brute-force check of an exact method."""
    family = FAMILIES[kind]
    assert methods(family.problem_type, "exact")
    assert any(family_of(make().problem) is family for make in REFERENCES)
    assert any(family_of(check.cases(range(1))[0][0]) is family for check in BRUTE_FORCE)


def test_describe_hooks_spell_the_reference_payloads():
    """Each family's describe hook gives one text line per route / sortie / order for the
    reference optima that come with a payload."""
    for make in REFERENCES:
        reference = make()
        family = family_of(reference.problem)
        if family.describe is None or reference.solution is None:
            continue
        payload = family.payload(reference.solution)
        lines = family.describe(reference.problem, payload, None)
        assert lines and all(isinstance(line, str) for line in lines), reference.name
