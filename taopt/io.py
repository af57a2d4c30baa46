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
import errno
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from taopt import schemas
from taopt.errors import OutputError


def unique_temp(path: str | os.PathLike[str], suffix: str = ".tmp") -> Path:
    """A temporary name beside ``path`` that no other process or call uses:
    ``.<name>.<pid>.<random>.tmp`` (hidden, so a folder listing does not show it)."""
    import secrets

    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(6)}{suffix}")


def _cannot_write(path: Path, exc: OSError) -> OutputError:
    detail = exc.strerror or str(exc) or type(exc).__name__
    return OutputError(f"{path}: cannot be written ({detail})")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix) to write; renamed into place on success.

    On any failure the temporary file is removed and ``path`` is left as it was; an
    ``OSError`` (a full disk, a read-only folder) becomes an :class:`OutputError` naming
    ``path``.

    Example
    -------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     target = pathlib.Path(folder) / "a.txt"
    ...     with atomic_path(target) as tmp:
    ...         _ = tmp.write_text("hello")
    ...     target.read_text()
    'hello'
    """
    path = Path(path)
    tmp = unique_temp(path, f".tmp{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise _cannot_write(path, exc) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def save_json(data: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Write JSON atomically (a temporary file renamed into place): nothing is written half.

    The temporary file has a name of its own (:func:`unique_temp`), so two processes saving
    the same path never write into one temporary file, and it is removed if anything fails.

    Raises
    ------
    OutputError
        The file cannot be written (a full disk, a read-only folder); the message names it.
    """
    path = Path(path)
    text = json.dumps(data, indent=1, allow_nan=False)
    with atomic_path(path) as tmp, open(tmp, "x", encoding="utf-8") as out:
        out.write(text)


def check_writable(
    folder: str | os.PathLike[str], what: str = "output folder", create: bool = True
) -> Path:
    """Check that files can be created in ``folder``, before any work.

    ``create=True`` makes the folder (parents too) and creates and removes a probe file in
    it; ``create=False`` writes nothing: an existing folder is probed the same way (a file
    created and removed at once), a missing one must sit under a writable existing folder.

    Returns the folder as a Path. Raises :class:`OutputError` naming it otherwise (a path
    under a file, a read-only folder, no space left for even an empty file).
    """
    where = Path(folder)
    try:
        if create:
            where.mkdir(parents=True, exist_ok=True)
        if where.is_dir():
            probe = unique_temp(where / "probe")
            with open(probe, "x", encoding="utf-8"):
                pass
            probe.unlink()
            return where
        if where.exists():
            raise NotADirectoryError(errno.ENOTDIR, "not a folder")
        ancestor = where.absolute().parent
        while not ancestor.exists():
            ancestor = ancestor.parent
        if not ancestor.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, f"{ancestor} is a file")
        if not os.access(ancestor, os.W_OK | os.X_OK):
            raise PermissionError(errno.EACCES, f"{ancestor} is not writable")
    except OSError as exc:
        detail = exc.strerror or str(exc) or type(exc).__name__
        raise OutputError(f"{what} {where}: cannot be written ({detail})") from None
    return where


def check_writable_file(path: str | os.PathLike[str] | None, what: str) -> None:
    """:func:`check_writable` (``create=False``: nothing written) on the folder of an output
    file; nothing for None."""
    if path is None:
        return
    parent = Path(path).parent
    check_writable(parent if str(parent) else ".", f"{what}: folder", create=False)


def load_json(path: str | os.PathLike[str], kind: str | None = None) -> Any:
    """Read a JSON file strictly and, given ``kind``, check it against that kind's schema.

    Raises
    ------
    InstanceError
        Missing or unreadable file, not UTF-8, invalid JSON, a ``NaN``/``Infinity``
        literal or an overflowing number, or (given ``kind``) a schema violation; the
        message starts with the path; a file longer than the size guard
        (``TAOPT_MAX_FILE_MB``, default 256) or nested deeper than 64 levels is refused. See
        :func:`taopt.schemas.load_json`.
    """
    return schemas.load_json(path, kind)


__all__ = [
    "atomic_path",
    "check_writable",
    "check_writable_file",
    "save_json",
    "load_json",
    "unique_temp",
]
