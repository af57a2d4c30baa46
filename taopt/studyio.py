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
  dropped and the file is rewritten atomically (temporary file, ``os.replace``)
  before anything is appended, so a torn line never joins the next row. Finished
  rows are never dropped, whichever methods are asked for now.

Example
-------
>>> store = ResultsStore(tmp, "rows.csv", ["k", "method", "value"], ["k", "method"],
...                      settings={"seed": 1})  # doctest: +SKIP
>>> store.append([{"k": 0, "method": "A", "value": 2.5}])  # doctest: +SKIP
>>> store.done_keys()  # doctest: +SKIP
{(0, 'A')}
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from taopt.errors import InstanceError
from taopt.instance import load_json, save_json

COMPLETE = "complete"
CONFIG = "config.json"

__all__ = ["COMPLETE", "CONFIG", "ResultsStore", "normalize_key"]


def normalize_key(values: Iterable[Any]) -> tuple[Any, ...]:
    """A row key in a comparable form: strings kept, numbers as int when integral else float.

    So a key read back from the CSV (``0.15``, ``3``, ``"MC"``) equals the one the
    study builds (``np.float64(0.15)``, ``np.int64(3)``, ``"MC"``).
    """
    out = []
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
    ) -> None:
        self.data_columns = [c for c in columns if c != COMPLETE]
        self.columns = self.data_columns + [COMPLETE]
        self.key_columns = list(key_columns)
        missing = [c for c in self.key_columns if c not in self.data_columns]
        if missing or not self.key_columns:
            raise InstanceError(f"key columns {missing or '[]'} are not among {self.data_columns}")
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path = self.folder / filename
        self.config_path = self.folder / config
        self.settings = _plain(settings)
        # 1. settings first: a refused open touches nothing
        lines, self.dropped = self._clean_lines()
        self._check_settings(has_rows=bool(lines))
        save_json(self.settings, self.config_path)
        # 2. a clean file (header + finished rows) before any append
        self._rewrite(lines)
        self._done = {self._line_key(line) for line in lines}

    # -- settings --------------------------------------------------------------------------
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
        return _parse_key([fields[self.columns.index(c)] for c in self.key_columns])

    def _rewrite(self, lines: list[str]) -> None:
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8", newline="") as handle:
            handle.write(",".join(self.columns) + "\n")
            handle.writelines(lines)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, self.path)

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
        fresh = []
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
        with open(self.path, "a", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
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
