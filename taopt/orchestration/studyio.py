"""Resumable result files for the thesis studies (chapter 2 §2.5 and chapter 5 §5.5).

A study computes many independent rows (one per scenario and method, or per
instance, ratio and method) and may be stopped at any moment. :class:`ResultsStore`
keeps them in one CSV file so that a re-run computes only what is missing:

* **Settings.** Everything that changes the numbers (sizes, seed, field, time
  limits, per-method options, ...) is a JSON dict saved next to the rows
  (``config.json`` by default, written atomically). Opening the folder again with
  other settings raises :class:`~taopt.errors.InstanceError` naming the keys that
  differ, so rows of two different studies are never mixed. A folder that holds no
  rows yet takes the new settings. What identifies a row
  (the method, the scenario, the ratio) is its *key*, not a setting: asking for
  other methods or more scenarios extends the same file.
* **Rows.** Each row ends with a ``complete`` column equal to 1 and is appended
  with a single write, flushed and fsync'd, as soon as it is known. A line cut by
  a crash lacks that last field (or has fewer fields), so it is recognised.
* **Opening.** Torn or unreadable lines and repeated keys (the first is kept) are
  dropped and the file is rewritten atomically (a temporary file of this process,
  ``os.replace``; removed if anything fails) before anything is appended, so a torn
  line never joins the next row. Finished rows are never dropped, whichever methods
  are asked for now. A store opened with ``write=False`` only reads (a finished,
  read-only folder can be reported on).
* **One writer.** :func:`folder_lock` holds an OS-level lock (``filelock``) on the
  folder while a study writes to it; a second writer is refused at once with
  :class:`StudyLocked`, naming the folder and the holder's pid.

Example
-------
>>> store = ResultsStore(tmp, "rows.csv", ["k", "method", "value"], ["k", "method"],
...                      settings={"seed": 1})  # doctest: +SKIP
>>> store.append([{"k": 0, "method": "A", "value": 2.5}])  # doctest: +SKIP
>>> store.done_keys()  # doctest: +SKIP
{(0, 'A')}
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import socket
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from taopt.errors import InstanceError, OutputError, TaoptError
from taopt.io import load_json, save_json, unique_temp

COMPLETE = "complete"
CONFIG = "config.json"
#: The lock file of a study folder, and the note naming its holder.
LOCK = ".taopt-study.lock"
OWNER = ".taopt-study.owner.json"

__all__ = [
    "COMPLETE",
    "CONFIG",
    "LOCK",
    "ResultsStore",
    "StudyLocked",
    "folder_lock",
    "normalize_key",
]


class StudyLocked(TaoptError, RuntimeError):
    """Another process is writing to this study folder."""


def _holder(folder: Path) -> str:
    """`` (pid 123 on host, since ...)`` from the owner note, or ``""``."""
    try:
        note = json.loads((folder / OWNER).read_text(encoding="utf-8"))
        return f" (pid {int(note['pid'])} on {note['host']}, since {note['since']})"
    except (OSError, ValueError, KeyError, TypeError):
        return ""


@contextlib.contextmanager
def folder_lock(folder: str | os.PathLike[str]) -> Iterator[Path]:
    """Hold the one-writer lock of a study folder (created if missing) while the block runs.

    The lock is the operating system's (``flock`` through :mod:`filelock`), so it is freed
    when the holder exits, however it exits (``kill -9`` included); a note beside it names
    the holder's pid for the message a second writer gets. Reading a folder needs no lock.

    Raises
    ------
    StudyLocked
        Another process (or another study of this one) holds the folder; raised at once.
    InstanceError
        The folder cannot be created or written.
    """
    from filelock import FileLock, Timeout

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InstanceError(f"{folder}: cannot create the study folder ({exc.strerror})") from None
    lock = FileLock(str(folder / LOCK), timeout=0)
    try:
        lock.acquire()
    except Timeout:
        raise StudyLocked(
            f"{folder} is in use by another study{_holder(folder)}; wait for it to finish "
            "or give another output folder"
        ) from None
    except OSError as exc:
        detail = exc.strerror or str(exc)
        raise InstanceError(f"{folder}: cannot lock the study folder ({detail})") from None
    try:
        note = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "since": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        with contextlib.suppress(OSError, OutputError):  # the note is a courtesy
            save_json(note, folder / OWNER)
        yield folder
    finally:
        with contextlib.suppress(OSError):
            (folder / OWNER).unlink()
        lock.release()


def normalize_key(values: Iterable[Any]) -> tuple[Any, ...]:
    """A row key in a comparable form: strings kept, numbers as int when integral else float.

    So a key read back from the CSV (``0.15``, ``3``, ``"MC"``) equals the one the
    study builds (``np.float64(0.15)``, ``np.int64(3)``, ``"MC"``).
    """
    out: list[Any] = []
    for value in values:
        if isinstance(value, str):
            out.append(value)
            continue
        number = float(value)
        out.append(int(number) if number.is_integer() else number)
    return tuple(out)


def _plain(settings: Mapping[str, Any]) -> dict[str, Any]:
    """``settings`` as plain JSON data (tuples become lists), or InstanceError."""
    try:
        return json.loads(json.dumps(dict(settings), allow_nan=False))
    except (TypeError, ValueError) as exc:
        raise InstanceError(f"study settings are not plain JSON data: {exc}") from None


class ResultsStore:
    """Rows of one study in ``folder/filename``, resumable and checked against its settings.

    Parameters
    ----------
    folder : path
        Created if missing.
    filename : str
        The CSV file inside ``folder``.
    columns : sequence of str
        The data columns; ``complete`` is added as the last column.
    key_columns : sequence of str
        The columns that identify a row (e.g. ``["scenario", "method"]``).
    settings : dict
        JSON-able description of everything that changes the results.
    config : str
        Name of the settings file inside ``folder`` (``config.json``).
    write : bool
        False: only read (nothing is created or rewritten, :meth:`append` refuses), so a
        finished folder on a read-only disk can be reported on. True (the default):
        create the folder, save the settings and clean the file; hold
        :func:`folder_lock` around a writing store.

    Raises
    ------
    InstanceError
        ``folder`` holds rows computed with other settings (the message names the
        keys), rows without a settings file, or a CSV with other columns.
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        filename: str,
        columns: Sequence[str],
        key_columns: Sequence[str],
        settings: Mapping[str, Any],
        config: str = CONFIG,
        write: bool = True,
    ) -> None:
        self.data_columns = [c for c in columns if c != COMPLETE]
        self.columns = self.data_columns + [COMPLETE]
        self.key_columns = list(key_columns)
        missing = [c for c in self.key_columns if c not in self.data_columns]
        if missing or not self.key_columns:
            raise InstanceError(f"key columns {missing or '[]'} are not among {self.data_columns}")
        self.folder = Path(folder)
        self.path = self.folder / filename
        self.config_path = self.folder / config
        self.settings = _plain(settings)
        self.writable = bool(write)
        # 1. settings first: a refused open touches nothing
        lines, self.dropped = self._clean_lines()
        self._check_settings(has_rows=bool(lines))
        self._done = {self._line_key(line) for line in lines}
        if not self.writable:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        if self._saved_settings() != self.settings:
            save_json(self.settings, self.config_path)
        # 2. a clean file (header + finished rows) before any append
        self._rewrite(lines)

    # -- settings --------------------------------------------------------------------------
    def _saved_settings(self) -> Any:
        """The settings file's data, or None if it is missing or unreadable."""
        if not self.config_path.exists():
            return None
        try:
            return load_json(self.config_path)
        except InstanceError:
            return None

    def _check_settings(self, has_rows: bool) -> None:
        if not self.config_path.exists():
            if has_rows:
                raise InstanceError(
                    f"{self.path} holds rows but {self.config_path.name} is missing, so their "
                    "settings are unknown; use another folder"
                )
            return
        if not has_rows:
            return  # no results yet: the new settings simply replace the saved ones
        saved = load_json(self.config_path)
        if not isinstance(saved, dict):
            raise InstanceError(f"{self.config_path}: not a settings dict")
        keys = sorted(set(saved) | set(self.settings))
        differ = [k for k in keys if saved.get(k, "<unset>") != self.settings.get(k, "<unset>")]
        if differ:
            detail = "; ".join(
                f"{k}={saved.get(k, '<unset>')!r} there, {k}={self.settings.get(k, '<unset>')!r} "
                "now"
                for k in differ
            )
            raise InstanceError(
                f"{self.folder} holds results computed with other settings ({detail}); "
                "use another folder"
            )

    # -- reading ---------------------------------------------------------------------------
    def _clean_lines(self) -> tuple[list[str], int]:
        """Finished, parsable, first-of-their-key data lines on disk (each ending in newline).

        Returns the lines and how many were dropped.
        """
        if not self.path.exists():
            return [], 0
        with open(self.path, encoding="utf-8", errors="replace", newline="") as handle:
            raw = handle.read().splitlines()
        if not raw:
            return [], 0
        header = _fields(raw[0])
        if header != self.columns:
            if len(raw) == 1 and ",".join(self.columns).startswith(raw[0]):
                return [], 0  # a header cut by a crash, nothing else
            raise InstanceError(
                f"{self.path}: columns {header} are not {self.columns}; not a results file of "
                "this study (or written by an older version without the 'complete' column)"
            )
        kept, seen, dropped = [], set(), 0
        positions = [self.columns.index(c) for c in self.key_columns]
        for line in raw[1:]:
            fields = _fields(line)
            if fields is None or len(fields) != len(self.columns) or fields[-1] != "1":
                dropped += 1
                continue
            try:
                key = _parse_key([fields[p] for p in positions])
            except ValueError:
                dropped += 1
                continue
            if key in seen:
                dropped += 1
                continue
            seen.add(key)
            kept.append(line + "\n")
        return kept, dropped

    def _line_key(self, line: str) -> tuple[Any, ...]:
        fields = _fields(line.rstrip("\n"))
        assert fields is not None  # the lines kept by _clean_lines parse
        return _parse_key([fields[self.columns.index(c)] for c in self.key_columns])

    def _rewrite(self, lines: list[str]) -> None:
        """Write the header and ``lines`` atomically, unless the file already holds exactly
        that (a clean file is left alone: a finished folder is not rewritten)."""
        text = ",".join(self.columns) + "\n" + "".join(lines)
        with contextlib.suppress(OSError):
            if self.path.read_bytes() == text.encode("utf-8"):
                return
        tmp = unique_temp(self.path)
        try:
            with open(tmp, "x", encoding="utf-8", newline="") as handle:
                handle.write(text)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(tmp, self.path)
        except OSError as exc:
            raise InstanceError(
                f"{self.path}: cannot be rewritten ({exc.strerror or exc}); is the folder "
                "read-only?"
            ) from None
        finally:
            tmp.unlink(missing_ok=True)

    def done_keys(self) -> set[tuple[Any, ...]]:
        """Keys (normalised with :func:`normalize_key`) of the finished rows."""
        return set(self._done)

    def key(self, *values: Any) -> tuple[Any, ...]:
        """``normalize_key(values)``: the form :meth:`done_keys` uses."""
        return normalize_key(values)

    def read(self) -> pd.DataFrame:
        """The finished rows on disk, columns ``data_columns`` (``complete`` left out)."""
        lines, _ = self._clean_lines()
        if not lines:
            return pd.DataFrame(columns=self.data_columns)
        text = ",".join(self.columns) + "\n" + "".join(lines)
        return pd.read_csv(io.StringIO(text))[self.data_columns]

    # -- writing ---------------------------------------------------------------------------
    def append(self, rows: Sequence[Mapping[str, Any]]) -> int:
        """Append finished rows with one write (flushed, fsync'd); return how many.

        Rows whose key is already finished are skipped: a finished row is never
        replaced.
        """
        if not self.writable:
            raise InstanceError(f"{self.path}: opened read-only (write=False); cannot append")
        fresh: list[tuple[tuple[Any, ...], Mapping[str, Any]]] = []
        for row in rows:
            missing = [c for c in self.data_columns if c not in row]
            if missing:
                raise InstanceError(f"row {dict(row)} lacks columns {missing}")
            key = normalize_key(row[c] for c in self.key_columns)
            if key in self._done or any(k == key for k, _ in fresh):
                continue
            fresh.append((key, row))
        if not fresh:
            return 0
        frame = pd.DataFrame([row for _, row in fresh], columns=self.data_columns)
        frame[COMPLETE] = 1
        text = frame.to_csv(header=False, index=False, lineterminator="\n")
        try:
            with open(self.path, "a", encoding="utf-8", newline="") as handle:
                handle.write(text)
                handle.flush()
                os.fsync(handle.fileno())
        except OSError as exc:  # e.g. a full disk: name the file (a torn line is dropped later)
            detail = exc.strerror or str(exc) or type(exc).__name__
            raise OutputError(
                f"{self.path}: cannot be written ({detail}); the rows written before are kept"
            ) from None
        self._done.update(key for key, _ in fresh)
        return len(fresh)


def _fields(line: str) -> list[str] | None:
    try:
        rows = list(csv.reader([line]))
    except csv.Error:
        return None
    return rows[0] if rows else []


def _parse_key(texts: Sequence[str]) -> tuple[Any, ...]:
    """Key fields of a CSV line: numbers parsed, text kept; an empty or NaN field is an error."""
    values: list[Any] = []
    for text in texts:
        if text == "":
            raise ValueError("empty key field")
        try:
            number = float(text)
        except ValueError:
            values.append(text)
            continue
        if not math.isfinite(number):
            raise ValueError("non-finite key field")
        values.append(number)
    return normalize_key(values)
