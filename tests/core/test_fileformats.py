"""Strict input files: JSON Schemas, readable errors, and fuzzed loaders that only ever raise
TaoptError (issue 7, item 6)."""

from __future__ import annotations

import copy
import json
import math
import random
import re
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pytest
from conftest import ROOT
from hypothesis import given, settings
from hypothesis import strategies as st

import taopt
from taopt import schemas
from taopt.capability.problem import CapabilityProblem
from taopt.comm.problem import CommProblem
from taopt.delivery import EXAMPLE_PATH
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError, TaoptError
from taopt.fields import field_from_dict
from taopt.instance import Instance
from taopt.io import load_json
from taopt.registry import families
from taopt.result import Solution
from taopt.routing.problem import AssignmentProblem
from taopt.schemas import naming
from taopt.sop.problem import SopProblem

DATA = Path(resources.files("taopt").joinpath("data"))
DEMO_PATH = DATA / "demo.json"
EXAMPLES = DATA / "examples"


def read(path: Path) -> dict[str, Any]:
    """The parsed JSON of a shipped file."""
    return json.loads(path.read_text())


def field_loader(data: Any) -> Any:
    """A field file's loader: the schema, then the field's constructor."""
    return field_from_dict(data)


def _family_loaders() -> dict[str, tuple[Callable[[Any], Any], Callable[[Path], Any], Path]]:
    """Every registered family's kind, from its spec: its loader, a file loader (the class's
    ``load``, or the schema of its kind then the spec's loader) and its shipped example
    ``examples/<kind>.json``."""
    found = {}
    for family in families():

        def load_file(path: Path, family: Any = family) -> Any:
            with naming(str(path)):
                return family.load(load_json(path, family.kind))

        load = getattr(family.problem_type, "load", load_file)  # the class's own, if it has one
        found[family.kind] = (family.load, load, EXAMPLES / f"{family.kind}.json")
    return found


#: kind -> (from_dict-like loader, file loader, shipped document): the kinds that are not a
#: family's (an instance, a field, a solution), then every family's from its spec.
LOADERS: dict[str, tuple[Callable[[Any], Any], Callable[[Path], Any], Path]] = {
    "instance": (Instance.from_dict, Instance.load, DEMO_PATH),
    "field": (
        field_loader,
        lambda p: field_from_dict(load_json(p, "field")),
        EXAMPLES / "field.json",
    ),
    "solution": (Solution.from_dict, Solution.load, EXAMPLES / "solution.json"),
    **_family_loaders(),
}
#: The file kinds a user hands to taopt (``field`` is also read inside an instance).
FILE_KINDS = [kind for kind in sorted(LOADERS) if kind != "field"]


# -- mutation --------------------------------------------------------------------------------------
#: Awkward JSON scalars: wrong types, huge, negative, fractional, non-finite, empty.
SCALARS: list[Any] = [
    None,
    True,
    False,
    0,
    -1,
    1,
    2.7,
    -3.5,
    1e308,
    -1e308,
    10**400,
    5e-324,
    float("nan"),
    float("inf"),
    float("-inf"),
    "",
    "1.0",
    "NaN",
    "Infinity",
    "any",
    "linear",
    "instance",
]
#: Key names to insert: the formats' own keys (so inserts can hit the real fields) and strays.
KEYS = [
    "schema_version", "kind", "name", "region", "field", "vehicles", "targets", "obstacles",
    "metadata", "id", "start", "speed", "capability", "position", "demands", "vertices", "A",
    "b", "x", "y", "vx", "vy", "method", "n_targets", "cost", "customers", "stops", "edges",
    "depot", "v_drone", "v_truck", "flight_range", "precedences", "service_time", "zzz", "",
]  # fmt: skip


def json_values() -> st.SearchStrategy[Any]:
    """Random JSON-like values: the awkward scalars, random numbers and text, nested lists and
    objects (NaN and the infinities included)."""
    leaves = (
        st.sampled_from(SCALARS)
        | st.integers(min_value=-(10**20), max_value=10**20)
        | st.floats(allow_nan=True, allow_infinity=True)
        | st.text(max_size=6)
    )
    return st.recursive(
        leaves,
        lambda inner: (
            st.lists(inner, max_size=5)
            | st.dictionaries(st.sampled_from(KEYS) | st.text(max_size=4), inner, max_size=4)
        ),
        max_leaves=10,
    )


def random_value(rng: random.Random, depth: int = 0) -> Any:
    """A random JSON-like value drawn with ``rng`` (the seeded twin of :func:`json_values`)."""
    roll = rng.random()
    if depth >= 3 or roll < 0.55:
        return rng.choice(SCALARS)
    if roll < 0.65:
        return rng.uniform(-1e6, 1e6)
    if roll < 0.7:
        return rng.randint(-(10**6), 10**6)
    if roll < 0.85:
        return [random_value(rng, depth + 1) for _ in range(rng.randint(0, 5))]
    return {rng.choice(KEYS): random_value(rng, depth + 1) for _ in range(rng.randint(0, 4))}


def nodes(doc: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every JSON path in ``doc`` (the root is ``()``)."""
    found = [path]
    if isinstance(doc, dict):
        for key, value in doc.items():
            found += nodes(value, (*path, key))
    elif isinstance(doc, list):
        for k, value in enumerate(doc):
            found += nodes(value, (*path, k))
    return found


def apply(doc: Any, path: tuple[Any, ...], operation: str, value: Any, key: Any) -> Any:
    """Replace the value at ``path``, delete it, or insert ``value`` into the container there
    (under ``key`` in an object, at position ``key`` in a list). Returns the new document."""
    doc = copy.deepcopy(doc)
    if not path:
        if operation == "replace":
            return value
        target = doc
    else:
        parent = doc
        for part in path[:-1]:
            parent = parent[part]
        last = path[-1]
        if operation == "replace":
            parent[last] = value
            return doc
        if operation == "delete":
            del parent[last]
            return doc
        target = parent[last]
    if operation == "insert":
        if isinstance(target, dict):
            target[key if isinstance(key, str) else str(key)] = value
        elif isinstance(target, list):
            target.insert(int(key) % (len(target) + 1) if isinstance(key, int) else 0, value)
    return doc


def mutate_randomly(doc: Any, rng: random.Random, steps: int = 1) -> Any:
    """``steps`` random replace/delete/insert mutations of ``doc`` drawn with ``rng``."""
    for _ in range(steps):
        path = rng.choice(nodes(doc))
        operation = rng.choice(["replace", "replace", "delete", "insert"])
        key = rng.choice(KEYS) if rng.random() < 0.5 else rng.randint(0, 50)
        doc = apply(doc, path, operation, random_value(rng), key)
    return doc


#: Magnitudes that once overflowed or broke a solver (1.3e154 squared is infinite; HiGHS takes
#: 1e20 as infinity) and values just outside the documented bound of 1e9.
HUGE = [1.3e154, -1.3e154, 1e200, -1e200, 1e29, 1e20, 1e9 * (1 + 1e-9), -2e9, 10**18, 1e308]
#: The mutation classes of the fuzz tests (issue 15, item 5).
MUTATIONS = ["ragged", "huge", "numeric_string", "wrong_type", "missing_key", "unknown_key",
             "duplicate", "self_loop"]  # fmt: skip


def _paths_where(doc: Any, test: Callable[[Any], bool]) -> list[tuple[Any, ...]]:
    """The JSON paths of ``doc`` whose value passes ``test``."""
    return [path for path in nodes(doc) if test(_get(doc, path))]


def _get(doc: Any, path: tuple[Any, ...]) -> Any:
    for part in path:
        doc = doc[part]
    return doc


def _is_real(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_int_pair(value: Any) -> bool:
    return (
        isinstance(value, list)
        and len(value) >= 2
        and all(isinstance(v, int) and not isinstance(v, bool) for v in value[:2])
    )


def _is_matrix(value: Any) -> bool:
    return isinstance(value, list) and len(value) > 1 and all(isinstance(r, list) for r in value)


#: Where each mutation class can act: a predicate on the values of a document.
PLACES: dict[str, Callable[[Any], bool]] = {
    "ragged": _is_matrix,  # a row of a matrix made shorter or longer
    "huge": _is_real,
    "numeric_string": _is_real,
    "wrong_type": lambda value: True,
    "missing_key": lambda value: isinstance(value, dict) and bool(value),
    "unknown_key": lambda value: isinstance(value, dict) and bool(value),
    "duplicate": lambda value: isinstance(value, list) and bool(value),  # demands, edges, ...
    "self_loop": _is_int_pair,  # an edge or a precedence from a node to itself
}


def mutate_class(doc: Any, rng: random.Random, how: str) -> Any:
    """One mutation of class ``how`` (see :data:`MUTATIONS`) at a random fitting place of
    ``doc`` (:data:`PLACES`); a class with no fitting place falls back to a wrong type."""
    doc = copy.deepcopy(doc)
    places = _paths_where(doc, PLACES[how]) if how != "wrong_type" else []
    if how == "ragged" and places:
        row = rng.choice(_get(doc, rng.choice(places)))
        if row and rng.random() < 0.5:
            row.pop(rng.randrange(len(row)))
        else:
            row.append(rng.choice(row) if row else 1.0)
        return doc
    if how in ("huge", "numeric_string") and places:
        path = rng.choice(places)
        old = _get(doc, path)
        value = rng.choice(HUGE) if how == "huge" else rng.choice([str(old), f" {old} "])
        return apply(doc, path, "replace", value, None)
    if how in ("missing_key", "unknown_key") and places:
        path = rng.choice(places)
        if how == "missing_key":
            key = rng.choice(sorted(_get(doc, path)))
            return apply(doc, (*path, key), "delete", None, None)
        return apply(doc, path, "insert", random_value(rng), rng.choice(KEYS))
    if how == "duplicate" and places:
        items = _get(doc, rng.choice(places))
        items.insert(rng.randrange(len(items) + 1), copy.deepcopy(rng.choice(items)))
        return doc
    if how == "self_loop" and places:
        pair = _get(doc, rng.choice(places))
        pair[1] = pair[0]
        return doc
    path = rng.choice(nodes(doc))
    return apply(doc, path, "replace", random_value(rng), None)


def mutate_by_classes(doc: Any, rng: random.Random) -> Any:
    """One to three mutations of random classes (most often one)."""
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        doc = mutate_class(doc, rng, rng.choice(MUTATIONS))
    return doc


def check_loader(kind: str, data: Any) -> None:
    """The loader either builds an object whose to_dict is valid and reloads equal, or raises a
    TaoptError; anything else (TypeError, KeyError, OverflowError, ...) fails the test."""
    from_dict = LOADERS[kind][0]
    try:
        built = from_dict(data)
    except TaoptError:
        return
    again = built.to_dict()
    schemas.validate(again, kind)
    assert from_dict(again).to_dict() == again


def check_file_loader(kind: str, text: str, path: Path) -> None:
    """Write ``text`` to ``path`` and load it: an object, or a TaoptError naming the file."""
    path.write_text(text)
    load = LOADERS[kind][1]
    try:
        load(path)
    except TaoptError as exc:
        assert str(path) in str(exc), f"error does not name the file: {exc}"


# -- the schemas themselves ----------------------------------------------------------------------------
def test_schemas_are_valid_draft_2020_12():
    """Every shipped schema is itself a valid draft 2020-12 schema, one per kind."""
    assert set(schemas.kinds()) >= {"instance", "assignment_problem", "delivery_instance", "field"}
    for kind in schemas.kinds():
        contents = schemas.schema(kind)
        assert contents["$schema"] == "https://json-schema.org/draft/2020-12/schema"
        jsonschema.Draft202012Validator.check_schema(contents)


def test_validators_are_compiled_once():
    """The compiled validator of a kind is cached, not rebuilt per call."""
    schemas.validate(read(DEMO_PATH), "instance")
    assert schemas._validator("instance") is schemas._validator("instance")


@pytest.mark.parametrize("kind", sorted(LOADERS))
def test_shipped_examples_load_and_round_trip(kind):
    """Each small example in taopt/data/examples loads with its loader and reloads equal."""
    path = EXAMPLES / f"{kind}.json"
    built = LOADERS[kind][1](path)
    assert built.to_dict() == LOADERS[kind][0](built.to_dict()).to_dict()
    schemas.validate(built.to_dict(), kind)


def test_shipped_data_files_pass_their_schemas():
    """The demo instance, the delivery example and every saved counterexample (each chapter's
    folder too) load with their family's loader; every folder holds at least one."""
    from taopt.registry import family_for_kind

    Instance.load(DEMO_PATH)
    DeliveryInstance.load(EXAMPLE_PATH)
    folder = ROOT / "docs" / "reproduction" / "counterexamples"
    files = sorted(folder.glob("**/*.json"))
    folders = {folder} | {p for p in folder.rglob("*") if p.is_dir()}
    empty = sorted(str(f.relative_to(folder)) for f in folders if not any(f.glob("*.json")))
    assert not empty, f"counterexample folders without a JSON file: {empty}"
    kinds = set()
    for path in files:
        kind = read(path)["kind"]
        problem = family_for_kind(kind).problem_type.load(path)
        assert family_for_kind(kind).problem_type is type(problem)
        kinds.add(kind)
    assert {"assignment_problem", "capability_problem", "comm_problem"} <= kinds


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10**6), n=st.integers(1, 6), m=st.integers(1, 3))
def test_saved_instances_match_the_schema(seed, n, m):
    """Whatever Instance.random and to_dict write is valid, so save then load never fails."""
    inst = Instance.random(n, m, side=1000.0, field=taopt.fields.thesis_field(), seed=seed)
    schemas.validate(inst.to_dict(), "instance")
    assert Instance.from_dict(inst.to_dict()) == inst


def test_other_kinds_round_trip_through_their_schemas():
    """CapabilityProblem (one matrix with an untravellable pair, or one per capability),
    SopProblem and Solution: to_dict is valid and from_dict rebuilds the same data."""
    from taopt.capability.problem import CapabilityProblem
    from taopt.sop.problem import SopProblem

    cost = np.full((5, 5), 3.0)
    cost[0, 2] = np.inf  # written as null
    demands = (frozenset({"a"}), frozenset({"a", "b"}), frozenset({"b"}))
    for matrices in (cost, {"a": cost, "b": 2 * cost}):
        data = CapabilityProblem(matrices, 3, ("a", "b"), demands).to_dict()
        schemas.validate(data, "capability_problem")
        assert CapabilityProblem.from_dict(data).to_dict() == data
    data["cost"]["a"][1][2] = "x"
    with pytest.raises(
        InstanceError, match=r'cost\.a\[1\]\[2\]: expected a number or null, got "x"'
    ):
        CapabilityProblem.from_dict(data)
    data["cost"] = {}
    with pytest.raises(InstanceError, match=r"cost: expected at least 1 key, got 0"):
        CapabilityProblem.from_dict(data)
    data = SopProblem(np.ones((4, 4)), ((1, 2),), 0, 3).to_dict()
    schemas.validate(data, "sop_problem")
    assert SopProblem.from_dict(data).to_dict() == data
    solution = taopt.solve(AssignmentProblem(np.ones((4, 4)), 2), "MC")
    data = solution.to_dict()
    schemas.validate(data, "solution")
    assert type(solution).from_dict(data).to_dict() == data


# -- the problems a user measured (issue 7, item 6) ----------------------------------------------------
def test_null_region_names_the_item():
    """A null region is an InstanceError naming 'region', not a TypeError."""
    data = read(DEMO_PATH)
    data["region"] = None
    with pytest.raises(InstanceError, match=r"^instance: region: expected a list, got null$"):
        Instance.from_dict(data)


def test_number_where_a_list_belongs():
    """A number as a position, or targets as an object, is named with its JSON path."""
    data = read(DEMO_PATH)
    data["targets"][3]["position"] = 5
    with pytest.raises(InstanceError, match=r"targets\[3\]\.position: expected a list, got 5"):
        Instance.from_dict(data)
    data = read(DEMO_PATH)
    data["targets"] = {"t0": [1.0, 2.0]}
    with pytest.raises(InstanceError, match=r"targets: expected a list, got an object"):
        Instance.from_dict(data)


def test_wrong_length_position_message():
    """The message for a 5-number position reads `targets[3].position: expected 2 numbers, got 5`."""
    data = read(DEMO_PATH)
    data["targets"][3]["position"] = [1, 2, 3, 4, 5]
    with pytest.raises(InstanceError, match=r"targets\[3\]\.position: expected 2 numbers, got 5"):
        Instance.from_dict(data)


def test_infinite_precedence_in_a_file(tmp_path):
    """A precedence [Infinity, 2] in a file is an InstanceError naming the literal and the file."""
    text = EXAMPLE_PATH.read_text()
    data = json.loads(text)
    data["precedences"][0] = [float("inf"), 2]
    path = tmp_path / "inf.json"
    path.write_text(json.dumps(data))  # Python writes the non-standard literal Infinity
    assert "Infinity" in path.read_text()
    with pytest.raises(
        InstanceError, match=r"inf\.json: Infinity \(line 1, column \d+\) is not a number"
    ):
        DeliveryInstance.load(path)
    with pytest.raises(InstanceError, match=r"precedences\[0\]\[0\]: expected a finite integer"):
        DeliveryInstance.from_dict(data)


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_literals_anywhere(tmp_path, literal):
    """NaN/Infinity literals are refused even where any JSON is allowed (metadata)."""
    data = read(DEMO_PATH)
    data["metadata"]["x"] = "PLACEHOLDER"
    path = tmp_path / "meta.json"
    path.write_text(json.dumps(data).replace('"PLACEHOLDER"', literal))
    with pytest.raises(
        InstanceError, match=rf"meta\.json: {literal} \(line 1, column \d+\) is not a number"
    ):
        Instance.load(path)
    data["metadata"]["x"] = float(literal.lower().replace("infinity", "inf"))
    with pytest.raises(InstanceError, match=r"metadata\.x: non-finite number"):
        Instance.from_dict(data)


def test_overflowing_numbers(tmp_path):
    """1e400 and a 400-digit integer overflow a double: errors, not inf or OverflowError."""
    path = tmp_path / "big.json"
    text = EXAMPLE_PATH.read_text()
    data = json.loads(text)
    data["v_drone"] = "BIG"
    for big, message in (("1e400", "the number 1e400 is too large"), ("9" * 400, "too large")):
        path.write_text(json.dumps(data).replace('"BIG"', big))
        with pytest.raises(InstanceError, match=message):
            DeliveryInstance.load(path)
    data["v_drone"] = 10**400
    with pytest.raises(InstanceError, match="v_drone: expected a finite number"):
        DeliveryInstance.from_dict(data)


@pytest.mark.parametrize("value", ["1.0", True, None, [1.0]])
def test_speed_must_be_a_number(value):
    """ "speed": "1.0" or true (once silently accepted) is an error naming the vehicle's speed."""
    data = read(DEMO_PATH)
    data["vehicles"][1]["speed"] = value
    with pytest.raises(InstanceError, match=r"vehicles\[1\]\.speed: expected a number, got"):
        Instance.from_dict(data)


def test_counts_must_be_integers():
    """n_targets: 2.7 (once silently a different problem) is an error; 2.0 still means 2."""
    data = read(EXAMPLES / "assignment_problem.json")
    data["n_targets"] = 2.7
    with pytest.raises(InstanceError, match=r"n_targets: expected an integer, got 2\.7"):
        AssignmentProblem.from_dict(data)
    data["n_targets"] = True
    with pytest.raises(InstanceError, match=r"n_targets: expected an integer, got true"):
        AssignmentProblem.from_dict(data)
    data["n_targets"] = 2.0
    assert AssignmentProblem.from_dict(data).n == 2
    data = read(EXAMPLE_PATH)
    data["depot"] = 0.5
    with pytest.raises(InstanceError, match=r"depot: expected an integer, got 0\.5"):
        DeliveryInstance.from_dict(data)


def test_ragged_cost_matrix_names_the_row():
    """A cost matrix with a short row is an InstanceError naming the row, not a numpy error."""
    data = read(EXAMPLES / "assignment_problem.json")
    data["cost"][2] = data["cost"][2][:-1]
    with pytest.raises(InstanceError, match=r"cost\[2\]: expected 5 numbers .*got 4"):
        AssignmentProblem.from_dict(data)


def test_stop_moved_away_from_its_streets():
    """A stop moved 5 km from its streets makes them shorter than the straight line: an error
    naming the edge and both lengths."""
    data = read(EXAMPLE_PATH)
    data["stops"][12] = [data["stops"][12][0] + 5000.0, data["stops"][12][1]]
    with pytest.raises(InstanceError) as info:
        DeliveryInstance.from_dict(data)
    message = str(info.value)
    assert "street edge (" in message and "12" in message
    assert "shorter than the straight line" in message
    edge = next(e for e in data["edges"] if 12 in e[:2])
    other = edge[1] if edge[0] == 12 else edge[0]
    straight = math.dist(data["stops"][12], data["stops"][other])
    assert f"{edge[2]:.9g}" in message and f"{straight:.9g}" in message


def test_missing_field_is_an_error_null_is_still_water():
    """A missing "field" is an error (it once meant still water); "field": null is still water."""
    data = read(DEMO_PATH)
    del data["field"]
    with pytest.raises(InstanceError, match=r"^instance: missing 'field'$"):
        Instance.from_dict(data)
    data["field"] = None
    assert Instance.from_dict(data).field is None


def test_unknown_keys_are_refused():
    """A misspelt key ('sped') is named instead of silently meaning the default speed."""
    data = read(DEMO_PATH)
    data["vehicles"][0]["sped"] = 2.0
    with pytest.raises(InstanceError, match=r"vehicles\[0\]: unknown key 'sped'"):
        Instance.from_dict(data)
    data = read(EXAMPLE_PATH)
    data["flight_rnage"] = 3.0
    with pytest.raises(InstanceError, match=r"unknown key 'flight_rnage'"):
        DeliveryInstance.from_dict(data)


def test_kind_and_version_must_match():
    """schema_version must be 1 and kind must name the loader's kind."""
    data = read(DEMO_PATH)
    with pytest.raises(InstanceError, match=r"expected a 'delivery_instance' file, got kind"):
        DeliveryInstance.from_dict(data)
    data["schema_version"] = True
    with pytest.raises(InstanceError, match="unknown schema_version true"):
        Instance.from_dict(data)
    data = read(DEMO_PATH)
    del data["kind"]
    with pytest.raises(InstanceError, match="missing 'kind'"):
        Instance.from_dict(data)
    with pytest.raises(InstanceError, match="expected a JSON object, got a list"):
        Instance.from_dict([data])


def test_duplicate_street_is_named():
    """The same street listed twice (perhaps with two lengths) is an error naming both entries."""
    data = read(EXAMPLE_PATH)
    u, v, length = data["edges"][0]
    data["edges"].append([v, u, length + 1.0])
    last = len(data["edges"]) - 1
    with pytest.raises(
        InstanceError, match=rf"edges\[{last}\]: the street .* is already edges\[0\]"
    ):
        DeliveryInstance.from_dict(data)


def test_field_file_errors_name_the_key():
    """A field file with a string velocity or a bad method is named by key."""
    with pytest.raises(InstanceError, match=r'^field: vx: expected a number, got "0\.1"$'):
        field_from_dict({"kind": "uniform", "vx": "0.1", "vy": 0.0})
    data = read(EXAMPLES / "field.json")
    data["method"] = "cubic"
    with pytest.raises(InstanceError, match=r"method: expected one of \"bspline\", \"linear\""):
        field_from_dict(data)


# -- files that cannot be read -----------------------------------------------------------------------
def test_unreadable_files_name_the_path(tmp_path, monkeypatch):
    """Missing, a folder, refused by the OS, not UTF-8, not JSON, nested too deep: each an
    InstanceError starting with the path."""
    missing = tmp_path / "nowhere.json"
    with pytest.raises(InstanceError, match=r"nowhere\.json: no such file"):
        Instance.load(missing)
    with pytest.raises(InstanceError, match="is a folder"):
        DeliveryInstance.load(tmp_path)
    latin = tmp_path / "latin.json"
    latin.write_bytes('{"name": "café"}'.encode("latin-1"))
    with pytest.raises(InstanceError, match=r"latin\.json: not UTF-8 text \(byte 13"):
        AssignmentProblem.load(latin)
    broken = tmp_path / "broken.json"
    broken.write_text('{"kind": ')
    with pytest.raises(InstanceError, match=r"broken\.json: not valid JSON"):
        load_json(broken)
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InstanceError, match=r"deep\.json: the JSON is nested too deeply"):
        Instance.load(deep)
    with pytest.raises(InstanceError, match="not a file path"):
        load_json(None)  # type: ignore[arg-type]
    refused = tmp_path / "refused.json"
    refused.write_text("{}")

    def deny(self, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "open", deny)  # the reader opens the file and reads with a cap
    with pytest.raises(InstanceError, match=r"refused\.json: cannot be read \(Permission denied\)"):
        Instance.load(refused)


def test_utf8_names_and_bom_are_read(tmp_path):
    """Non-ASCII names in UTF-8 (with or without a byte-order mark) load unchanged."""
    data = read(EXAMPLES / "assignment_problem.json")
    data["name"] = "Café — 東京"
    path = tmp_path / "utf8.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(data, ensure_ascii=False).encode("utf-8"))
    assert AssignmentProblem.load(path).name == "Café — 東京"


# -- Python-built delivery instances: the street check lives in the constructor ------------------------
def test_grid_and_example_pass_the_street_check():
    """DeliveryInstance.grid and the shipped 20-customer example satisfy length >= straight line."""
    for inst in (
        DeliveryInstance.grid([[150, 40], [420, 380]], 3, 1000, 1.0, 1.0, 600),
        DeliveryInstance.grid([[15, 4]], 11, 1000, 1.0, 1.0, 600),
        DeliveryInstance.load(EXAMPLE_PATH),
    ):
        for u, v, length in inst.graph.edges(data="length"):
            assert length >= np.hypot(*(inst.stops[u] - inst.stops[v])) * (1 - 1e-9)


# -- fuzzing -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", sorted(LOADERS))
@settings(max_examples=60, deadline=None, derandomize=True)
@given(data=st.data())
def test_mutated_dicts_only_raise_taopt_errors(kind, data):
    """Replace, delete or insert random JSON values at random paths of a valid document: the
    loader builds a valid object or raises a TaoptError, never anything else."""
    doc = read(LOADERS[kind][2])
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        path = data.draw(st.sampled_from(nodes(doc)), label="path")
        operation = data.draw(st.sampled_from(["replace", "delete", "insert"]), label="operation")
        value = data.draw(json_values(), label="value")
        key = data.draw(st.sampled_from(KEYS) | st.integers(0, 50), label="key")
        doc = apply(doc, path, operation, value, key)
    check_loader(kind, doc)


@pytest.mark.parametrize("kind", sorted(LOADERS))
@settings(max_examples=60, deadline=None, derandomize=True)
@given(data=st.data())
def test_fast_path_gives_the_same_errors(kind, data):
    """The fast path for numeric arrays reports exactly the errors plain jsonschema reports."""
    doc = read(LOADERS[kind][2])
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        path = data.draw(st.sampled_from(nodes(doc)), label="path")
        operation = data.draw(st.sampled_from(["replace", "delete", "insert"]), label="operation")
        doc = apply(doc, path, operation, data.draw(json_values()), data.draw(st.integers(0, 50)))
    registry = schemas._registry()
    contents = schemas.schema(kind)
    fast = schemas.strict_validator_class(fast=True)(contents, registry=registry)
    plain = schemas.strict_validator_class(fast=False)(contents, registry=registry)

    def errors(validator):
        found = [(list(e.absolute_path), e.message) for e in validator.iter_errors(doc)]
        return sorted(found, key=repr)

    assert errors(fast) == errors(plain)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(cut=st.integers(0, 10**9), byte=st.integers(0, 255), how=st.sampled_from(["cut", "flip"]))
def test_corrupted_text_only_raises_taopt_errors(tmp_path_factory, cut, byte, how):
    """Truncated files and files with one byte changed load or raise a TaoptError naming the file."""
    path = tmp_path_factory.mktemp("corrupt") / "file.json"
    raw = EXAMPLE_PATH.read_bytes()
    k = cut % len(raw)
    raw = raw[:k] if how == "cut" else raw[:k] + bytes([byte]) + raw[k + 1 :]
    path.write_bytes(raw)
    try:
        DeliveryInstance.load(path)
    except TaoptError as exc:
        assert str(path) in str(exc)


def run_file_mutations(kind: str, count: int, tmp_path: Path, seed: int) -> dict[str, int]:
    """``count`` seeded random mutations of the shipped document, each written to a file (with
    Python's NaN/Infinity literals where they occur) and loaded; returns outcome counts."""
    rng = random.Random(seed)
    source = read(LOADERS[kind][2])
    outcomes = {"loaded": 0, "refused": 0}
    path = tmp_path / f"mutant-{kind}.json"
    for _ in range(count):
        doc = mutate_randomly(source, rng, steps=rng.randint(1, 3))
        text = json.dumps(doc, allow_nan=True)
        path.write_text(text)
        try:
            LOADERS[kind][1](path)
            outcomes["loaded"] += 1
        except TaoptError as exc:
            assert str(path) in str(exc), f"error does not name the file: {exc}"
            outcomes["refused"] += 1
    return outcomes


def run_class_mutations(kind: str, count: int, folder: Path, seed: int) -> dict[str, int]:
    """``count`` seeded mutations of the shipped example of ``kind`` by class (ragged rows,
    huge magnitudes, numeric strings, wrong types, missing and unknown keys, duplicates,
    self-loops), each written to its own file and loaded: a loaded file round-trips through
    its schema, a refused one raised a TaoptError whose message starts with the path."""
    rng = random.Random(seed)
    source = read(LOADERS[kind][2])
    from_dict, load = LOADERS[kind][0], LOADERS[kind][1]
    outcomes = {"loaded": 0, "refused": 0}
    for k in range(count):
        doc = mutate_by_classes(source, rng)
        path = folder / f"mutant-{kind}-{k}.json"
        path.write_text(json.dumps(doc, allow_nan=True))
        try:
            built = load(path)
        except TaoptError as exc:
            assert str(exc).startswith(f"{path}: "), f"error does not start with the file: {exc}"
            outcomes["refused"] += 1
        else:
            again = built.to_dict()
            schemas.validate(again, kind)
            assert from_dict(again).to_dict() == again
            outcomes["loaded"] += 1
        path.unlink()
    return outcomes


@pytest.mark.parametrize("kind", FILE_KINDS)
def test_mutated_files_of_every_kind_only_raise_taopt_errors(tmp_path, kind):
    """300 mutations by class of each kind's example, loaded from files: only TaoptErrors,
    each starting with the file's path, and some mutants of every kind are refused."""
    outcomes = run_class_mutations(kind, 300, tmp_path, seed=15)
    assert outcomes["refused"] > 0 and sum(outcomes.values()) == 300


@pytest.mark.slow
@pytest.mark.parametrize("kind", FILE_KINDS)
def test_3000_mutated_files_of_every_kind_only_raise_taopt_errors(tmp_path, kind):
    """3,000 mutations by class per kind (the issue's count): only TaoptErrors naming the file."""
    outcomes = run_class_mutations(kind, 3000, tmp_path, seed=2026)
    assert sum(outcomes.values()) == 3000


def test_mutation_classes_find_their_places():
    """Each mutation class has places to act in the examples it is meant for: matrices to make
    ragged in every matrix kind, numbers and objects everywhere, index pairs to turn into
    self-loops in the delivery, SOP and solution examples."""
    fits = {
        how: {kind for kind in FILE_KINDS if _paths_where(read(LOADERS[kind][2]), PLACES[how])}
        for how in MUTATIONS
    }
    every = set(FILE_KINDS)
    assert fits["huge"] == fits["numeric_string"] == fits["missing_key"] == every
    assert fits["duplicate"] == every
    matrices = {"assignment_problem", "capability_problem", "sop_problem", "comm_problem"}
    assert matrices | {"delivery_instance", "solution"} <= fits["ragged"]
    assert {"delivery_instance", "sop_problem", "solution"} <= fits["self_loop"]


@pytest.mark.parametrize("kind", ["instance", "delivery_instance"])
def test_200_mutated_files_only_raise_taopt_errors(tmp_path, kind):
    """200 random mutations of demo.json / delivery_example_20.json, loaded from files: every
    failure is a TaoptError naming the file."""
    outcomes = run_file_mutations(kind, 200, tmp_path, seed=7)
    assert outcomes["refused"] > 0 and sum(outcomes.values()) == 200


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["instance", "delivery_instance"])
def test_2000_mutated_files_only_raise_taopt_errors(tmp_path, kind):
    """2,000 random mutations of each shipped document, loaded from files: only TaoptErrors."""
    outcomes = run_file_mutations(kind, 2000, tmp_path, seed=2021)
    assert sum(outcomes.values()) == 2000


def test_file_mutation_is_reproducible():
    """The same seed gives the same mutants."""
    source = read(DEMO_PATH)
    first, second = random.Random(3), random.Random(3)
    a = [mutate_randomly(source, first, steps=2) for _ in range(20)]
    b = [mutate_randomly(source, second, steps=2) for _ in range(20)]
    assert json.dumps(a, allow_nan=True) == json.dumps(b, allow_nan=True)
    assert len({json.dumps(x, allow_nan=True) for x in a}) > 1


def test_docs_examples_are_the_shipped_examples():
    """Every JSON example in docs/file-formats.md is one of taopt/data/examples, byte for byte
    after parsing, and every shipped example appears in the docs: there, or (a family's
    example) on the kinds page generated from the specs (docs/generated.py)."""
    docs = ROOT / "docs" / "file-formats.md"
    blocks = re.findall(r"```json\n(.*?)```", docs.read_text(encoding="utf-8"), flags=re.S)
    shown = [json.loads(block) for block in blocks]
    shipped = [read(path) for path in sorted(EXAMPLES.glob("*.json"))]
    assert len(shipped) >= 7
    shown_set = set(map(json.dumps, shown))
    assert shown_set <= set(map(json.dumps, shipped))
    generated = {f"../taopt/data/examples/{f.kind}.json" for f in families()}
    for path in sorted(EXAMPLES.glob("*.json")):
        in_generated = f"../taopt/data/examples/{path.name}" in generated
        assert json.dumps(read(path)) in shown_set or in_generated, path.name


# -- magnitudes, ragged rows and file names (issue 15, item 5) -----------------------------------------
@pytest.mark.parametrize(
    "kind, path, value, message",
    [
        ("instance", ("vehicles", 0, "speed"), 1.3e154, r"vehicles\[0\]\.speed: must be <= 1000000000"),
        ("instance", ("targets", 0, "position", 0), 1e200, r"targets\[0\]\.position\[0\]: must be <="),
        ("comm_problem", ("targets", 1, 0), 1e200, r"targets\[1\]\[0\]: must be <= 1000000000"),
        ("comm_problem", ("vehicles", 0, 1), -1e200, r"vehicles\[0\]\[1\]: must be >= -1000000000"),
        ("sop_problem", ("cost", 0, 1), 1e29, r"cost\[0\]\[1\]: must be <= 1000000000, got 1e\+29"),
        ("delivery_instance", ("v_drone",), 1.3e154, r"v_drone: must be <= 1000000000"),
        ("delivery_instance", ("v_truck",), 1e-12, r"v_truck: must be >= 1e-09"),
        ("assignment_problem", ("cost", 1, 2), 2e9, r"cost\[1\]\[2\]: must be <= 1000000000"),
        ("capability_problem", ("cost", "boat", 1, 2), 2e9, r"cost\.boat\[1\]\[2\]: must be <="),
        ("solution", ("payload", "routes", 1, 0), 10**12, r"payload\.routes\[1\]\[0\]: must be <="),
    ],
)  # fmt: skip
def test_magnitudes_above_the_bound_are_refused_by_name(tmp_path, kind, path, value, message):
    """Coordinates, speeds, costs and indices beyond the documented 1e9 are refused at the
    edge, with the file, the JSON path and the bound in the message."""
    doc = apply(read(LOADERS[kind][2]), path, "replace", value, None)
    file = tmp_path / f"{kind}.json"
    file.write_text(json.dumps(doc))
    with pytest.raises(InstanceError, match=rf"^{re.escape(str(file))}: {message}"):
        LOADERS[kind][1](file)


def test_values_at_the_bound_still_load():
    """1e9 itself is allowed: a coordinate, a cost and a speed at the bound load."""
    doc = read(EXAMPLES / "comm_problem.json")
    doc["targets"][0] = [1e9, -1e9]
    doc["comm_range"] = 1e9
    assert CommProblem.from_dict(doc).targets[0].tolist() == [1e9, -1e9]
    doc = read(EXAMPLES / "sop_problem.json")
    doc["cost"][0][1] = 1e9
    assert SopProblem.from_dict(doc).cost[0, 1] == 1e9


def test_net_speed_of_huge_speeds_does_not_overflow():
    """(3.4) at speeds of 1.3e154 (whose square overflows) gives the scaled root, not an
    OverflowError: v_net(s v_c, s v) = s v_net(v_c, v)."""
    from taopt.navigation.uniform import net_speed, uniform_travel_times

    small_ = float(net_speed([0.3, 0.1], [1.0, 0.0], 1.0))
    huge = float(net_speed([0.3e154, 0.1e154], [1.0, 0.0], 1.3e154 / 1.3))
    assert huge == pytest.approx(small_ * 1e154, rel=1e-12)
    times = uniform_travel_times([0.0, 0.0], [0.0, 0.0], [3.0, 4.0], speed=1.3e154)
    assert float(times) == pytest.approx(5.0 / 1.3e154, rel=1e-12)


def test_ragged_sop_cost_names_the_row_and_the_file(tmp_path):
    """A short row of an SOP cost matrix is an InstanceError naming the file and the row, not
    numpy's 'inhomogeneous shape' ValueError."""
    doc = read(EXAMPLES / "sop_problem.json")
    doc["cost"][3] = doc["cost"][3][:-1]
    file = tmp_path / "ragged.json"
    file.write_text(json.dumps(doc))
    with pytest.raises(InstanceError, match=rf"^{re.escape(str(file))}: cost\[3\]: expected 5"):
        SopProblem.load(file)


def test_tsplib_errors_start_with_the_path(tmp_path):
    """A broken TSPLIB .sop file (bad dimension, a non-number, a huge weight) is named by its
    full path."""
    good = "NAME: x\nTYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
    good += "EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n3\n0 1 1000000\n-1 0 1\n-1 -1 0\nEOF\n"
    file = tmp_path / "x.sop"
    file.write_text(good)
    assert SopProblem.load(file).n == 3
    for old, new, message in [
        ("DIMENSION: 3", "DIMENSION: x", "DIMENSION 'x' is not a whole number"),
        ("0 1 1000000", "0 one 1000000", "EDGE_WEIGHT_SECTION holds a non-number"),
        ("0 1 1000000", "0 1e29 1000000", r"weight \[0\]\[1\] = 1e\+29"),
    ]:
        file.write_text(good.replace(old, new))
        with pytest.raises(InstanceError, match=rf"^{re.escape(str(file))}: {message}"):
            SopProblem.load(file)


# -- nothing changed silently on load (issue 15, item 9) -------------------------------------------------
def test_duplicate_demands_are_refused_not_merged():
    """["boat", "boat"] in a capability or instance file is an error naming both positions; in
    Python a list with a repeat is read as a set with a warning."""
    doc = read(EXAMPLES / "capability_problem.json")
    doc["demands"][1] = ["boat", "boat"]
    with pytest.raises(InstanceError, match=r'demands\[1\]: \[1\] = "boat" is listed twice'):
        CapabilityProblem.from_dict(doc)
    doc = read(DEMO_PATH)
    doc["targets"][0]["demands"] = ["any", "any"]
    with pytest.raises(InstanceError, match=r"targets\[0\]\.demands: \[1\] = \"any\" is listed"):
        Instance.from_dict(doc)
    cost = np.ones((3, 3))
    with pytest.warns(UserWarning, match=r"demands\[0\] lists a capability twice"):
        problem = CapabilityProblem(cost, 1, ("a", "a"), (["a", "a"],))
    assert problem.demands == (frozenset({"a"}),)


def test_duplicate_precedences_are_refused():
    """A precedence listed twice in a delivery or SOP file is refused by name."""
    doc = read(EXAMPLE_PATH)
    doc["precedences"].append(list(doc["precedences"][0]))
    with pytest.raises(InstanceError, match=r"precedences: \[\d+\] = .* is listed twice"):
        DeliveryInstance.from_dict(doc)
    doc = read(EXAMPLES / "sop_problem.json")
    doc["precedences"].append([2, 1])
    with pytest.raises(InstanceError, match=r"precedences: \[1\] = .* is listed twice"):
        SopProblem.from_dict(doc)


def test_street_self_loop_is_refused_in_a_file_and_warned_in_python():
    """A street [3, 3, 0] in a file is an error naming the edge; a self-loop in a Python graph
    is dropped with a warning (documented)."""
    doc = read(EXAMPLE_PATH)
    doc["edges"].append([3, 3, 0.0])
    last = len(doc["edges"]) - 1
    with pytest.raises(InstanceError, match=rf"edges\[{last}\]: the street \(3, 3\) joins stop 3"):
        DeliveryInstance.from_dict(doc)
    base = DeliveryInstance.load(EXAMPLE_PATH)
    graph = nx_graph_with_loop(base)
    with pytest.warns(UserWarning, match=r"graph edge \(3, 3\) is a self-loop"):
        again = base.replace(graph=graph)
    assert again.graph.number_of_edges() == base.graph.number_of_edges()


def nx_graph_with_loop(instance: DeliveryInstance) -> Any:
    """The instance's street graph plus a self-loop at stop 3."""
    import networkx as nx

    graph = nx.Graph(instance.graph)
    graph.add_edge(3, 3, length=0.0)
    return graph


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d["payload"].update(extra=1), r"payload: unknown key 'extra'"),
        (lambda d: d["payload"].pop("routes"), r"payload: missing 'routes'"),
        (lambda d: d.update(payload_kind=None), r"payload: expected null"),
        (lambda d: d["payload"].update(routes=[[0, "1"]]), r"payload\.routes\[0\]\[1\]: expected an integer"),
        (lambda d: d.update(payload_kind="plan"), r"payload: missing 'order'"),
        (lambda d: d.update(payload_kind="nope"), r"unknown payload kind 'nope'"),
    ],
)  # fmt: skip
def test_solution_payloads_are_checked_not_dropped(tmp_path, change, message):
    """Unknown or missing payload keys, a payload without a kind, wrong index types and an
    unknown kind are InstanceErrors starting with the file (once KeyError/TypeError or a
    silent drop)."""
    doc = read(EXAMPLES / "solution.json")
    change(doc)
    file = tmp_path / "solution.json"
    file.write_text(json.dumps(doc))
    with pytest.raises(InstanceError, match=rf"^{re.escape(str(file))}: {message}"):
        Solution.load(file)


def test_seed_2_0_stays_2():
    """A seed written 2.0 is the seed 2 (it became null); a Generator still records none."""
    doc = read(EXAMPLES / "solution.json")
    doc["seed"] = 2.0
    assert Solution.from_dict(doc).seed == 2
    assert Solution(1.0, "feasible", seed=np.float64(3.0)).seed == 3
    assert Solution(1.0, "feasible", seed=np.random.default_rng(0)).seed is None


def test_messages_print_plain_numbers():
    """numpy scalars in constructor arguments are shown as plain numbers in messages."""
    from taopt.instance import Target, Vehicle

    f = np.float64
    with pytest.raises(InstanceError) as info:
        Instance(
            vehicles=(Vehicle("v", (f(0), f(0)), f(1)),),
            targets=(Target("t", (f(20), f(20))),),
            region=(f(100), f(0), f(0), f(100)),
            field=None,
        )
    assert "np." not in str(info.value) and "(100.0, 0.0, 0.0, 100.0)" in str(info.value)
    with pytest.raises(InstanceError, match=r"^start = 5 is not a node index"):
        SopProblem(np.ones((3, 3)), (), np.int64(5), 2)
    base = DeliveryInstance.load(EXAMPLE_PATH)
    with pytest.raises(InstanceError, match=r"precedence \(0, 0\.5\) must be an integer"):
        base.replace(precedences=((np.int64(0), np.float64(0.5)),))
