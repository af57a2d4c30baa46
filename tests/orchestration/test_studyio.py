"""The resumable results store shared by the chapter 2 and chapter 5 studies."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time

import pandas as pd
import pytest

from taopt.errors import InstanceError, OutputError
from taopt.io import save_json, unique_temp
from taopt.orchestration.studyio import LOCK, ResultsStore, StudyLocked, folder_lock, normalize_key

COLUMNS = ["k", "ratio", "method", "value", "status"]
KEY = ["k", "ratio", "method"]
SETTINGS = {"seed": 1, "options": {"GA": {"generations": 5}}, "limit": None}


def rows(k, methods=("A", "B"), ratio=0.15):
    return [
        {"k": k, "ratio": ratio, "method": m, "value": 1000.0 / 3 + k, "status": "ok"}
        for m in methods
    ]


def open_store(folder, settings=SETTINGS):
    return ResultsStore(folder, "rows.csv", COLUMNS, KEY, settings)


def strict_lines(path):
    """Every data line of the file parsed strictly: all fields present, complete == 1."""
    with open(path, newline="") as handle:
        table = list(csv.reader(handle))
    assert table[0] == COLUMNS + ["complete"]
    for line in table[1:]:
        assert len(line) == len(COLUMNS) + 1 and line[-1] == "1", line
    return table[1:]


def test_append_read_and_keys(tmp_path):
    store = open_store(tmp_path)
    assert store.append(rows(0)) == 2
    assert store.append(rows(0)) == 0  # a finished row is never written twice
    assert store.done_keys() == {(0, 0.15, "A"), (0, 0.15, "B")}
    assert normalize_key((0.0, pd.Series([0.15]).iloc[0], "A")) in store.done_keys()
    df = store.read()
    assert list(df.columns) == COLUMNS and len(df) == 2
    assert df["value"].iloc[0] == 1000.0 / 3  # floats round-trip exactly
    assert json.loads((tmp_path / "config.json").read_text()) == SETTINGS
    assert len(strict_lines(tmp_path / "rows.csv")) == 2


def test_other_keys_kept_on_reopen(tmp_path):
    open_store(tmp_path).append(rows(0, ("A", "B")) + rows(1, ("C",)))
    again = open_store(tmp_path)  # a later run asking only for method "D"
    again.append(rows(2, ("D",)))
    assert len(again.read()) == 4
    assert set(again.read()["method"]) == {"A", "B", "C", "D"}


@pytest.mark.parametrize(
    "key, value",
    [("seed", 2), ("limit", 60.0), ("options", {"GA": {"generations": 6}}), ("extra", 1)],
)
def test_other_settings_refused_naming_the_key(tmp_path, key, value):
    open_store(tmp_path).append(rows(0))
    before = (tmp_path / "rows.csv").read_bytes(), (tmp_path / "config.json").read_bytes()
    with pytest.raises(InstanceError, match=rf"{key}=.* there, {key}=.* now"):
        open_store(tmp_path, {**SETTINGS, key: value})
    # nothing touched by the refused open
    assert before == ((tmp_path / "rows.csv").read_bytes(), (tmp_path / "config.json").read_bytes())
    assert len(open_store(tmp_path).read()) == 2  # same settings (JSON-equal) still accepted


@pytest.mark.parametrize(
    "cut",
    [
        lambda line: line[: line.index(".") + 3],  # mid-number
        lambda line: line[: line.index(",ok") + 1],  # right after a field's comma
        lambda line: line[: line.rindex(",") + 1],  # everything but the complete flag
        lambda line: line[: line.rindex(",")].replace("ok", "0,ok"),  # too many fields
        lambda line: "\x00" * 12,  # garbage from a crashed filesystem
    ],
)
def test_torn_last_line_dropped_and_next_row_intact(tmp_path, cut):
    store = open_store(tmp_path)
    store.append(rows(0))
    path = tmp_path / "rows.csv"
    text = path.read_text()
    last = text.splitlines()[-1]
    path.write_text(text[: len(text) - len(last) - 1] + cut(last))  # no newline at the end
    again = open_store(tmp_path)
    assert again.dropped == 1
    assert again.done_keys() == {(0, 0.15, "A")}  # row B must be recomputed
    again.append(rows(0, ("B",)) + rows(1, ("A",)))
    table = strict_lines(path)
    assert [line[2] for line in table] == ["A", "B", "A"]
    assert len(open_store(tmp_path).read()) == 3


def test_complete_line_without_newline_is_kept(tmp_path):
    open_store(tmp_path).append(rows(0))
    path = tmp_path / "rows.csv"
    path.write_text(path.read_text().rstrip("\n"))
    again = open_store(tmp_path)
    assert again.dropped == 0
    again.append(rows(1, ("A",)))
    assert len(strict_lines(path)) == 3


def test_duplicates_keep_the_first(tmp_path):
    open_store(tmp_path).append(rows(0, ("A",)))
    path = tmp_path / "rows.csv"
    first = path.read_text().splitlines()[-1]
    path.write_text(path.read_text() + first.replace("ok", "other") + "\n")
    again = open_store(tmp_path)
    assert again.dropped == 1
    df = again.read()
    assert len(df) == 1 and df["status"].iloc[0] == "ok"
    assert len(strict_lines(path)) == 1


def test_foreign_files_refused(tmp_path):
    (tmp_path / "rows.csv").write_text("k,method,value\n0,A,1.0\n")
    (tmp_path / "config.json").write_text(json.dumps(SETTINGS))
    with pytest.raises(InstanceError, match="complete"):
        open_store(tmp_path)
    other = tmp_path / "other"
    open_store(other).append(rows(0))
    (other / "config.json").unlink()
    with pytest.raises(InstanceError, match="config.json is missing"):
        open_store(other)
    with pytest.raises(InstanceError, match="not plain JSON"):
        open_store(tmp_path / "third", {"seed": object()})


def test_torn_header_only(tmp_path):
    (tmp_path / "rows.csv").write_text("k,rat")
    store = open_store(tmp_path)
    store.append(rows(0))
    assert len(strict_lines(tmp_path / "rows.csv")) == 2


# -- one writer, temporary files, read-only folders (issue 15, item 7) --------------------------------
def never_wait(seconds: float) -> None:
    """Stands in for time.sleep where a refusal must come at once: any wait fails the test."""
    raise AssertionError(f"waited {seconds} s for the lock instead of refusing at once")


def test_second_writer_in_this_process_is_refused_at_once(tmp_path, monkeypatch):
    """While a folder is locked, a second lock is refused at once (it never waits), naming
    the folder and pid; after release it can be taken again."""
    with folder_lock(tmp_path / "study"):
        with monkeypatch.context() as patch:
            patch.setattr(time, "sleep", never_wait)
            with pytest.raises(StudyLocked, match=rf"in use by another study \(pid {os.getpid()} "):
                with folder_lock(tmp_path / "study"):
                    pass
    with folder_lock(tmp_path / "study"):
        pass


def test_lock_held_by_another_process_is_refused_and_freed_when_it_dies(tmp_path):
    """A lock held by another process refuses this one with its pid; killed with SIGKILL, the
    holder frees the folder (an OS lock, not a stale file)."""
    folder = tmp_path / "study"
    code = (
        "import sys, time\n"
        "from taopt.orchestration.studyio import folder_lock\n"
        f"with folder_lock({str(folder)!r}):\n"
        "    print('held', flush=True)\n"
        "    time.sleep(60)\n"
    )
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(StudyLocked, match=rf"{folder}.*pid {holder.pid} "):
            with folder_lock(folder):
                pass
    finally:
        holder.kill()
        holder.wait()
    with folder_lock(folder):
        assert (folder / LOCK).exists()


def test_unique_temp_names_per_call_and_process(tmp_path):
    """Temporary names are hidden, carry the pid and never repeat."""
    names = {unique_temp(tmp_path / "m.npy", ".tmp.npy") for _ in range(50)}
    assert len(names) == 50
    assert all(p.name.startswith(".m.npy.") and f".{os.getpid()}." in p.name for p in names)
    assert all(p.name.endswith(".tmp.npy") for p in names)


def test_failed_rewrite_leaves_no_temporary_file(tmp_path, monkeypatch):
    """When the CSV cannot be replaced (an immutable file), the error names it and no .tmp
    is left behind; save_json cleans up the same way."""
    store = open_store(tmp_path)
    store.append(rows(0))
    with open(store.path, "a") as handle:
        handle.write("torn,line")  # forces a rewrite on the next open

    def refuse(src, dst):
        raise PermissionError(1, "Operation not permitted", str(dst))

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(InstanceError, match=r"rows\.csv: cannot be rewritten"):
        open_store(tmp_path)
    with pytest.raises(OutputError, match=r"x\.json: cannot be written \(Operation not permitted"):
        save_json({"a": 1}, tmp_path / "x.json")
    assert not [p.name for p in tmp_path.iterdir() if "tmp" in p.name]


def test_read_only_store_writes_nothing(tmp_path):
    """write=False reads the finished rows of a folder without creating, saving or rewriting
    anything, and refuses to append."""
    store = open_store(tmp_path / "study")
    store.append(rows(0) + rows(1))
    before = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "study").iterdir()}
    reader = ResultsStore(tmp_path / "study", "rows.csv", COLUMNS, KEY, SETTINGS, write=False)
    assert len(reader.read()) == 4 and len(reader.done_keys()) == 4
    with pytest.raises(InstanceError, match="read-only"):
        reader.append(rows(2))
    after = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "study").iterdir()}
    assert after == before
    missing = ResultsStore(tmp_path / "none", "rows.csv", COLUMNS, KEY, SETTINGS, write=False)
    assert missing.done_keys() == set() and not (tmp_path / "none").exists()


def test_clean_file_is_not_rewritten(tmp_path):
    """Reopening a clean file with the same settings leaves both files untouched."""
    store = open_store(tmp_path)
    store.append(rows(0))
    before = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
    time.sleep(0.01)
    open_store(tmp_path)
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == before
