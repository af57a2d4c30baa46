"""JSON Schemas of taopt's file kinds, and :func:`validate` (checked before any object is built).

Interim version (the lead's): validates the kinds whose schema file is shipped here.
"""

from __future__ import annotations

import functools
import json
from importlib import resources
from typing import Any

from taopt.errors import InstanceError


@functools.cache
def _validator(kind: str) -> Any:
    import jsonschema

    name = f"{kind}.schema.json"
    path = resources.files("taopt.schemas") / name
    if not path.is_file():
        return None
    schema = json.loads(path.read_text())
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def _where(path: Any) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


def validate(data: Any, kind: str) -> None:
    """Raise InstanceError naming the JSON path and value unless ``data`` is a valid ``kind``."""
    import jsonschema

    validator = _validator(kind)
    if validator is None:
        return
    error = jsonschema.exceptions.best_match(validator.iter_errors(data))
    if error is not None:
        value = json.dumps(error.instance)[:80]
        raise InstanceError(
            f"{kind} file: {_where(error.absolute_path)}: {error.message[:200]} (got {value})"
        )


__all__ = ["validate"]
