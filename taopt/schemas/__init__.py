"""JSON Schemas of taopt's file formats, and the strict reader that applies them.

Every file taopt reads is checked here before any object is built
(docs/architecture.md, invariant 8): the text must be UTF-8 JSON without the
``NaN``/``Infinity`` literals Python's :mod:`json` accepts, and the data must match the JSON Schema
(draft 2020-12) of its kind, shipped beside this module as
``<kind>.schema.json``. A failure is an :class:`~taopt.errors.InstanceError`
whose message names the file, the JSON path and the value, e.g.
``demo.json: targets[3].position: expected 2 numbers, got 5``. The
constructors then run their own checks (duplicate ids, points outside the
region, precedence cycles, ...), which a schema cannot express.

Kinds: ``instance``, ``assignment_problem``, ``delivery_instance`` and
``field`` (a drift field on its own; also the ``field`` of an instance). A
new kind is one more ``<kind>.schema.json`` file in this folder. The formats
are described field by field in ``docs/file-formats.md``.

Strictness beyond plain JSON Schema: a "number" is a finite real number (not a
string such as ``"1.0"``, not ``true``, not NaN or infinite, not an integer too
large for a double), an "integer" is a number with no fractional part, and a
non-finite number is an error anywhere in the data, free-form ``metadata``
included.

Example
-------
>>> from taopt.schemas import validate
>>> validate({"kind": "uniform", "vx": 0.1, "vy": 0.0}, "field")
>>> validate({"kind": "uniform", "vx": "0.1", "vy": 0.0}, "field")
Traceback (most recent call last):
    ...
taopt.errors.InstanceError: field: vx: expected a number, got "0.1"
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import json
import math
import numbers
import os
import re
from collections.abc import Callable, Iterable, Iterator
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from taopt.errors import InstanceError

if TYPE_CHECKING:  # jsonschema is imported on first use: ~0.1 s that `import taopt` need not pay
    from jsonschema.exceptions import ValidationError
    from referencing import Registry

#: Schema versions this taopt reads (the ``schema_version`` of every top-level file).
SUPPORTED_VERSIONS = (1,)

_SUFFIX = ".schema.json"


# -- the schemas -------------------------------------------------------------------------------
def _schema_files() -> dict[str, Any]:
    folder = resources.files(__name__)
    return {
        entry.name[: -len(_SUFFIX)]: entry
        for entry in folder.iterdir()
        if entry.name.endswith(_SUFFIX)
    }


@functools.cache
def _registry() -> Registry:
    """All shipped schemas, keyed by file name, so ``"$ref": "field.schema.json"`` resolves
    offline (a reference to anything else fails instead of being fetched)."""
    from referencing import Registry, Resource

    resources_ = [
        (kind + _SUFFIX, Resource.from_contents(json.loads(entry.read_text(encoding="utf-8"))))
        for kind, entry in sorted(_schema_files().items())
    ]
    return Registry().with_resources(resources_).crawl()


def kinds() -> tuple[str, ...]:
    """The file kinds that have a schema, e.g. ``('assignment_problem', ..., 'instance')``."""
    return tuple(sorted(_schema_files()))


#: kind -> functions completing its schema in place (see :func:`extend`)
_EXTENSIONS: dict[str, list[Callable[[dict[str, Any]], None]]] = {}


def extend(kind: str, complete: Callable[[dict[str, Any]], None]) -> None:
    """Register ``complete(schema)``, which adds to the schema of ``kind`` in place each time
    :func:`schema` reads it.

    A schema part that the code declares elsewhere is added here instead of being listed by
    hand in the shipped file: :mod:`taopt.result` adds one rule and one ``$defs`` entry per
    registered payload kind to the solution schema, each declared with its payload type
    (:func:`taopt.result.register_payload`).
    """
    found = _EXTENSIONS.setdefault(kind, [])
    if complete not in found:
        found.append(complete)


def schema(kind: str) -> dict[str, Any]:
    """The JSON Schema of ``kind``: a fresh copy of the shipped ``<kind>.schema.json``,
    completed by the functions registered with :func:`extend` (every family imported
    first, so the answer does not depend on what was imported before).

    Raises
    ------
    KeyError
        ``kind`` has no schema (this is a programming error, not bad input).
    """
    from taopt.families import ensure_families

    uri = kind + _SUFFIX
    try:
        contents = _registry().contents(uri)
    except LookupError:
        raise KeyError(f"no schema for kind {kind!r}; known kinds: {', '.join(kinds())}") from None
    contents = json.loads(json.dumps(contents))
    ensure_families()  # every payload type (and other extension) registered
    for complete in _EXTENSIONS.get(kind, ()):
        complete(contents)
    return contents


# -- strict types --------------------------------------------------------------------------------
def _finite(value: Any) -> bool:
    try:
        return math.isfinite(value)
    except OverflowError:  # an int too large for a double
        return False


def _is_number(checker: Any, value: Any) -> bool:
    """A finite real number: bool is not a number here, nor is NaN or an infinity."""
    return not isinstance(value, bool) and isinstance(value, numbers.Real) and _finite(value)


def _is_integer(checker: Any, value: Any) -> bool:
    if not _is_number(checker, value):
        return False
    return isinstance(value, numbers.Integral) or float(value).is_integer()


def _is_array(checker: Any, value: Any) -> bool:
    """JSON arrays; Python callers may also pass tuples."""
    return isinstance(value, (list, tuple))


# -- a fast path for long numeric arrays ------------------------------------------------------------
# jsonschema checks every array element through its full machinery (~40 us each), which makes a
# 140 x 140 cost matrix take most of a second. For "items" whose schema is a plain number,
# integer or an array of them (the cost rows, the points, the edges), a compiled predicate first
# tries the whole array; only if some element fails does the standard keyword run, so the
# errors, and what is accepted, are exactly those of the schema.
_PLAIN = {"description", "title", "$comment"}
_NUMBER_KEYS = {"type", "minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"} | _PLAIN
_ARRAY_KEYS = {"type", "minItems", "maxItems", "items", "prefixItems"} | _PLAIN


def _compile(validator: Any, subschema: Any, depth: int = 0) -> Callable[[Any], bool] | None:
    """A predicate that is True only for values ``subschema`` accepts, or None if the schema is
    not one of the simple shapes handled here."""
    if not isinstance(subschema, dict) or depth > 4:
        return None
    if set(subschema) <= {"$ref"} | _PLAIN and "$ref" in subschema:
        try:  # referencing's resolver is private API; without it the fast path is just skipped
            target = validator._resolver.lookup(subschema["$ref"]).contents
        except Exception:
            return None
        return _compile(validator, target, depth + 1)
    kind = subschema.get("type")
    nullable = False
    if isinstance(kind, list) and len(kind) == 2 and "null" in kind:  # e.g. ["number", "null"]
        nullable, kind = True, next(k for k in kind if k != "null")
    if kind in ("number", "integer") and set(subschema) <= _NUMBER_KEYS:
        low = subschema.get("minimum", -math.inf)
        above = subschema.get("exclusiveMinimum", -math.inf)
        high = subschema.get("maximum", math.inf)
        below = subschema.get("exclusiveMaximum", math.inf)
        whole = kind == "integer"

        def number(x: Any) -> bool:
            if x is None:
                return nullable
            if type(x) is float:  # exact types: bool, numpy scalars etc. take the full path
                if whole and not x.is_integer():
                    return False
            elif type(x) is not int or not _finite(x):
                return False
            return low <= x <= high and above < x < below and math.isfinite(x)

        return number
    if kind == "array" and set(subschema) <= _ARRAY_KEYS and not nullable:
        items: Callable[[Any], bool] | None = None
        if "items" in subschema:
            items = _compile(validator, subschema["items"], depth + 1)
            if items is None:
                return None
        compiled = [
            _compile(validator, part, depth + 1) for part in subschema.get("prefixItems", [])
        ]
        prefix = [part for part in compiled if part is not None]
        if len(prefix) < len(compiled):
            return None
        shortest = subschema.get("minItems", 0)
        longest = subschema.get("maxItems", math.inf)
        start = len(prefix)

        def array(x: Any) -> bool:
            if type(x) not in (list, tuple) or not shortest <= len(x) <= longest:
                return False
            if not all(check(part) for check, part in zip(prefix, x, strict=False)):
                return False
            return items is None or all(map(items, x[start:]))

        return array
    return None


@functools.cache
def strict_validator_class(fast: bool = True) -> Any:
    """Draft 2020-12 with the strict ``number``, ``integer`` and ``array`` types above, and
    (``fast``) the fast path for long arrays of simple items (same verdicts, same errors)."""
    import jsonschema

    types = jsonschema.Draft202012Validator.TYPE_CHECKER.redefine_many(
        {"number": _is_number, "integer": _is_integer, "array": _is_array}
    )
    if not fast:
        return jsonschema.validators.extend(jsonschema.Draft202012Validator, type_checker=types)
    standard_items = jsonschema.Draft202012Validator.VALIDATORS["items"]
    # id -> (the subschema itself, its predicate); holding the subschema keeps its id unique
    compiled: dict[int, tuple[Any, Callable[[Any], bool] | None]] = {}

    def items(validator: Any, subschema: Any, instance: Any, schema: Any) -> Iterator[Any]:
        if type(instance) in (list, tuple) and "prefixItems" not in schema:
            entry = compiled.get(id(subschema))
            if entry is None or entry[0] is not subschema:
                entry = compiled[id(subschema)] = (subschema, _compile(validator, subschema))
            check = entry[1]
            if check is not None and all(map(check, instance)):
                return
        yield from standard_items(validator, subschema, instance, schema)

    return jsonschema.validators.extend(
        jsonschema.Draft202012Validator, validators={"items": items}, type_checker=types
    )


@functools.cache
def _validator(kind: str) -> Any:
    """The compiled validator of ``kind`` (built once per process)."""
    contents = schema(kind)
    cls = strict_validator_class()
    cls.check_schema(contents)
    return cls(contents, registry=_registry())


# -- readable messages -------------------------------------------------------------------------
def json_path(path: Iterable[Any]) -> str:
    """``['targets', 3, 'position']`` -> ``'targets[3].position'``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        elif isinstance(part, str) and part.isidentifier():
            out += f".{part}" if out else part
        else:
            out += f"[{part!r}]"
    return out


def show(value: Any) -> str:
    """A short JSON-style rendering of ``value`` for an error message."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return "an object" if value else "an empty object"
    if isinstance(value, (list, tuple)):
        count = len(value)
        return f"a list of {count} item{'s' if count != 1 else ''}" if count else "an empty list"
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        text = (
            str(int(value))
            if abs(int(value)) < 10**30
            else f"an integer of {len(str(value))} digits"
        )
        return text
    try:
        text = json.dumps(value, allow_nan=True)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


_NOUNS = {
    "number": ("a number", "numbers"),
    "integer": ("an integer", "integers"),
    "string": ("a string", "strings"),
    "boolean": ("true or false", "booleans"),
    "null": ("null", "nulls"),
    "array": ("a list", "lists"),
    "object": ("an object", "objects"),
}
_REF_NOUNS = {"point": "points [x, y]", "pair": "rows of 2 numbers", "index": "indices"}


def _item_noun(subschema: Any) -> str:
    items = subschema.get("items") if isinstance(subschema, dict) else None
    if isinstance(items, dict):
        if isinstance(items.get("type"), str):
            return _NOUNS.get(items["type"], (None, "items"))[1]
        ref = items.get("$ref")
        if isinstance(ref, str):
            return _REF_NOUNS.get(ref.rsplit("/", 1)[-1], "items")
    return "items"


def _expected_type(expected: Any, value: Any) -> str:
    names = [expected] if isinstance(expected, str) else list(expected)
    words = [_NOUNS.get(name, (name, name))[0] for name in names]
    text = " or ".join(words)
    numeric = {"number", "integer"} & set(names)
    if numeric and isinstance(value, numbers.Real) and not isinstance(value, bool):
        if not _finite(value):
            text = "a finite number" if "number" in numeric else "a finite integer"
    return text


def reason(error: ValidationError) -> str:
    """A short, plain-words reason for one schema violation."""
    keyword, expected, value = error.validator, error.validator_value, error.instance
    if keyword == "type":
        return f"expected {_expected_type(expected, value)}, got {show(value)}"
    if keyword in ("minItems", "maxItems"):
        noun = _item_noun(error.schema)
        low, high = error.schema.get("minItems"), error.schema.get("maxItems")
        if low is not None and low == high:
            return f"expected {low} {noun}, got {len(value)}"
        bound = "at least" if keyword == "minItems" else "at most"
        return f"expected {bound} {expected} {noun}, got {len(value)}"
    if keyword == "minProperties":
        return f"expected at least {expected} key{'s' if expected != 1 else ''}, got {len(value)}"
    if keyword == "required":
        missing = [key for key in expected if key not in value]
        return f"missing {missing[0]!r}" if missing else error.message
    if keyword == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        extra = sorted(str(key) for key in value if key not in allowed)
        return f"unknown key {extra[0]!r} (allowed: {', '.join(allowed)})"
    if keyword == "const":
        return f"expected {show(expected)}, got {show(value)}"
    if keyword == "enum":
        return f"expected one of {', '.join(show(v) for v in expected)}, got {show(value)}"
    if keyword == "minimum":
        return f"must be >= {show(expected)}, got {show(value)}"
    if keyword == "exclusiveMinimum":
        return f"must be > {show(expected)}, got {show(value)}"
    if keyword == "maximum":
        return f"must be <= {show(expected)}, got {show(value)}"
    if keyword == "exclusiveMaximum":
        return f"must be < {show(expected)}, got {show(value)}"
    if keyword == "uniqueItems" and isinstance(value, (list, tuple)):
        seen: list[Any] = []
        for k, item in enumerate(value):
            if item in seen:
                return f"[{k}] = {show(item)} is listed twice (first at [{seen.index(item)}])"
            seen.append(item)
    return error.message


def _message(source: str, path: Iterable[Any], text: str) -> str:
    where = json_path(path)
    return f"{source}: {where}: {text}" if where else f"{source}: {text}"


_SAFE_INT = 2**1000  # far inside the double range


def _plain_leaf(value: Any) -> bool:
    """A str, bool, None, finite float or moderate int (exact types: the quick test)."""
    kind = type(value)
    if kind is float:
        return math.isfinite(value)
    if kind is int:
        return -_SAFE_INT < value < _SAFE_INT
    return kind is str or kind is bool or value is None


def _non_finite(data: Any) -> Iterator[tuple[list[Any], Any]]:
    """Every non-finite number (NaN, an infinity, an int too large for a double) with its
    path, walking iteratively so deep nesting cannot exhaust the stack."""
    stack: list[tuple[list[Any], Any]] = [([], data)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, dict):
            stack.extend((path + [key], item) for key, item in reversed(list(value.items())))
        elif isinstance(value, (list, tuple)):
            if all(map(_plain_leaf, value)):  # the common case: a row of ordinary numbers
                continue
            if all(type(row) is list and all(map(_plain_leaf, row)) for row in value):
                continue  # a matrix, or a long list of pairs: no per-row stack entries
            stack.extend((path + [k], item) for k, item in reversed(list(enumerate(value))))
        elif isinstance(value, numbers.Real) and not isinstance(value, bool) and not _finite(value):
            yield path, value


# -- validation ---------------------------------------------------------------------------------
def _check_header(data: dict[str, Any], kind: str, contents: dict[str, Any], source: str) -> None:
    """The schema version and the kind first, with messages that say what to do."""
    properties = contents.get("properties", {})
    # the kind first: a file of another kind is named as such, whatever its version
    if properties.get("kind", {}).get("const") == kind and "kind" in data:
        if data["kind"] != kind:
            raise InstanceError(
                f"{source}: expected a {kind!r} file, got kind {show(data['kind'])}"
            )
    if "schema_version" in properties:
        version = data.get("schema_version")
        if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
            raise InstanceError(
                f"{source}: unknown schema_version {show(version)} for {kind} "
                f"(this taopt reads {list(SUPPORTED_VERSIONS)})"
            )


#: How many schema errors :func:`validate` ranks with ``best_match`` (it reports one).
_ERRORS_CONSIDERED = 64


def validate(data: Any, kind: str, source: str | None = None) -> None:
    """Check ``data`` (parsed JSON) against the schema of ``kind``; raise on the first problem.

    Parameters
    ----------
    data : Any
        The parsed JSON (dicts, lists, str, numbers, bool, None; tuples are taken as lists).
    kind : str
        ``"instance"``, ``"assignment_problem"``, ``"delivery_instance"``, ``"field"``, or
        any other kind with a ``<kind>.schema.json`` here.
    source : str, optional
        What to call the data in the message (a file path); default ``kind``.

    Raises
    ------
    InstanceError
        The data breaks the schema or holds a non-finite number. The message names the
        source, the JSON path and the value, e.g.
        ``instance: vehicles[0].speed: expected a number, got "1.0"``; of several
        problems it reports the most relevant one (``jsonschema``'s ``best_match``).
    """
    source = kind if source is None else str(source)
    validator = _validator(kind)
    if not isinstance(data, dict) and validator.schema.get("type") == "object":
        raise InstanceError(f"{source}: expected a JSON object, got {show(data)}")
    if isinstance(data, dict):
        _check_header(data, kind, validator.schema, source)
    from jsonschema.exceptions import best_match

    try:
        # best_match consumes every error it is given: on a million-element array of strings
        # that is a million errors (26 s for a 1000 x 1000 matrix); the first few suffice
        error = best_match(itertools.islice(validator.iter_errors(data), _ERRORS_CONSIDERED))
        if error is not None:
            raise InstanceError(_message(source, error.absolute_path, reason(error)))
        for path, value in _non_finite(data):
            raise InstanceError(_message(source, path, f"non-finite number {show(value)}"))
    except RecursionError:
        raise InstanceError(f"{source}: the data is nested too deeply") from None


@contextlib.contextmanager
def naming(source: str) -> Iterator[None]:
    """Prefix ``source`` (a file path, or the kind) to any :class:`InstanceError` raised inside,
    so a constructor's complaint about loaded data names the file it came from. A message
    that already starts with ``source`` is left as it is (no ``file: file: ...``)."""
    try:
        yield
    except InstanceError as exc:
        if str(exc).startswith(str(source)):
            raise
        raise InstanceError(f"{source}: {exc}") from None


# -- reading files ----------------------------------------------------------------------------------
_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|(-?Infinity|NaN)')


def _position(text: str, literal: str) -> str:
    """`` (line L, column C)`` of the first ``literal`` outside a string, or ``""``."""
    for match in _TOKENS.finditer(text):
        if match.group(1) == literal:
            line = text.count("\n", 0, match.start()) + 1
            column = match.start() - (text.rfind("\n", 0, match.start()) + 1) + 1
            return f" (line {line}, column {column})"
    return ""


def parse_json(text: str, source: str = "JSON") -> Any:
    """Parse JSON text strictly: no ``NaN``/``Infinity`` literals, no number that overflows
    a double; every failure an :class:`InstanceError` naming ``source``."""

    def constant(literal: str) -> Any:
        raise InstanceError(
            f"{source}: {literal}{_position(text, literal)} is not a number JSON allows "
            "(non-finite values are not accepted)"
        )

    def real(literal: str) -> float:
        value = float(literal)
        if not math.isfinite(value):
            raise InstanceError(f"{source}: the number {literal[:40]} is too large for a double")
        return value

    def integer(literal: str) -> int:
        if len(literal) > 400:
            raise InstanceError(
                f"{source}: an integer of {len(literal)} digits is too large for a double"
            )
        value = int(literal)
        if not _finite(value):
            raise InstanceError(
                f"{source}: the integer {literal[:40]}... is too large for a double"
            )
        return value

    try:
        return json.loads(text, parse_constant=constant, parse_float=real, parse_int=integer)
    except json.JSONDecodeError as exc:
        raise InstanceError(f"{source}: not valid JSON ({exc})") from None
    except RecursionError:
        raise InstanceError(f"{source}: the JSON is nested too deeply") from None


#: Largest JSON file taopt reads, in bytes (``TAOPT_MAX_FILE_MB`` overrides it): a longer file,
#: or an endless stream such as ``/dev/zero`` or a FIFO, is refused after reading this much.
MAX_FILE_BYTES = 256 * 2**20
#: Environment variable overriding :data:`MAX_FILE_BYTES` (megabytes).
FILE_SIZE_ENV = "TAOPT_MAX_FILE_MB"
#: Deepest nesting of lists and objects in a file taopt reads (its formats nest at most 5).
MAX_DEPTH = 64

_CHUNK = 2**20


def max_file_bytes() -> int:
    """The size guard of :func:`load_json`: ``TAOPT_MAX_FILE_MB`` if set, else
    :data:`MAX_FILE_BYTES`."""
    text = os.environ.get(FILE_SIZE_ENV, "").strip()
    if text:
        try:
            value = float(text)
        except ValueError:
            raise InstanceError(f"{FILE_SIZE_ENV}={text!r}: expected megabytes") from None
        if not (math.isfinite(value) and value > 0):
            raise InstanceError(f"{FILE_SIZE_ENV}={text!r}: expected positive megabytes")
        return int(value * 2**20)
    return MAX_FILE_BYTES


def read_capped(where: Path, limit: int | None = None) -> bytes:
    """At most ``limit`` bytes of ``where`` (default :func:`max_file_bytes`), read in chunks
    so that a device or a FIFO that never ends is refused too; InstanceError naming the
    file when it is longer, missing, a folder or unreadable."""
    limit = max_file_bytes() if limit is None else limit
    try:
        with where.open("rb") as handle:
            chunks, size = [], 0
            while size <= limit:
                chunk = handle.read(min(_CHUNK, limit + 1 - size))
                if not chunk:
                    break
                chunks.append(chunk)
                size += len(chunk)
    except FileNotFoundError:
        raise InstanceError(f"{where}: no such file") from None
    except IsADirectoryError:
        raise InstanceError(f"{where}: is a folder, not a file") from None
    except (OSError, ValueError) as exc:
        detail = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InstanceError(f"{where}: cannot be read ({detail})") from None
    if size > limit:
        raise InstanceError(
            f"{where}: longer than {limit / 2**20:g} MB, the size guard of taopt's files "
            f"(set {FILE_SIZE_ENV} to read it)"
        )
    return b"".join(chunks)


def check_depth(data: Any, source: str, limit: int = MAX_DEPTH) -> None:
    """InstanceError naming ``source`` when lists and objects nest deeper than ``limit``
    (walked iteratively: no recursion, whatever the depth)."""
    stack: list[tuple[int, Any]] = [(1, data)]
    while stack:
        depth, value = stack.pop()
        if depth > limit:
            raise InstanceError(
                f"{source}: the JSON is nested more than {limit} levels deep "
                "(taopt's files nest a few levels)"
            )
        if isinstance(value, dict):
            stack.extend(
                (depth + 1, item) for item in value.values() if isinstance(item, (dict, list))
            )
        elif isinstance(value, list):
            if all(map(_plain_leaf, value)):
                continue
            stack.extend((depth + 1, item) for item in value if isinstance(item, (dict, list)))


def load_json(path: str | os.PathLike[str], kind: str | None = None) -> Any:
    """Read a JSON file strictly and, given ``kind``, validate it (:func:`validate`).

    The one reader of every JSON file taopt takes (problems, solutions, fields, study
    configurations): at most :func:`max_file_bytes` bytes are read (a device such as
    ``/dev/zero`` is refused, not read for ever), lists and objects nest at most
    :data:`MAX_DEPTH` levels.

    Raises
    ------
    InstanceError
        The file does not exist or cannot be read, is longer than the size guard, is not
        UTF-8, is not valid JSON, nests too deeply, holds ``NaN``/``Infinity`` or an
        overflowing number, or breaks the schema; the message starts with the path.
    """
    try:
        where = Path(path)
    except TypeError:
        raise InstanceError(f"not a file path: {path!r}") from None
    raw = read_capped(where)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InstanceError(
            f"{where}: not UTF-8 text (byte {exc.start} is {raw[exc.start : exc.start + 1]!r})"
        ) from None
    data = parse_json(text, str(where))
    check_depth(data, str(where))
    if kind is not None:
        validate(data, kind, str(where))
    return data


__all__ = [
    "SUPPORTED_VERSIONS",
    "strict_validator_class",
    "json_path",
    "kinds",
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "check_depth",
    "load_json",
    "max_file_bytes",
    "naming",
    "read_capped",
    "parse_json",
    "reason",
    "schema",
    "show",
    "validate",
]
