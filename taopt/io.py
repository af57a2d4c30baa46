"""Reading and writing taopt's JSON files: one place for every problem family.

:func:`save_json` writes atomically (a temporary file with a name of its own, renamed into
place), :func:`load_json` reads strictly and, given a kind, checks the file against that
kind's JSON Schema (:mod:`taopt.schemas`). Every family's ``save``/``load`` goes through
these two functions, so a file is never written half and every read error names the file.

Example
-------
>>> import tempfile, pathlib
>>> from taopt.io import load_json, save_json
>>> with tempfile.TemporaryDirectory() as folder:
...     path = pathlib.Path(folder) / "field.json"
...     save_json({"kind": "uniform", "vx": 0.1, "vy": 0.0}, path)
...     load_json(path, "field")
{'kind': 'uniform', 'vx': 0.1, 'vy': 0.0}
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any

from taopt import schemas


def unique_temp(path: str | os.PathLike[str], suffix: str = ".tmp") -> Path:
    """A temporary name beside ``path`` that no other process or call uses:
    ``.<name>.<pid>.<random>.tmp`` (hidden, so a folder listing does not show it)."""
    import secrets

    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(6)}{suffix}")


def save_json(data: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Write JSON atomically (a temporary file renamed into place): nothing is written half.

    The temporary file has a name of its own (:func:`unique_temp`), so two processes saving
    the same path never write into one temporary file, and it is removed if anything fails.
    """
    path = Path(path)
    text = json.dumps(data, indent=1, allow_nan=False)
    tmp = unique_temp(path)
    try:
        with open(tmp, "x", encoding="utf-8") as out:
            out.write(text)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def load_json(path: str | os.PathLike[str], kind: str | None = None) -> Any:
    """Read a JSON file strictly and, given ``kind``, check it against that kind's schema.

    Raises
    ------
    InstanceError
        Missing or unreadable file, not UTF-8, invalid JSON, a ``NaN``/``Infinity``
        literal or an overflowing number, or (given ``kind``) a schema violation; the
        message starts with the path. See :func:`taopt.schemas.load_json`.
    """
    return schemas.load_json(path, kind)


__all__ = ["save_json", "load_json", "unique_temp"]
