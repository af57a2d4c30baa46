"""Issue 30 (a user's second week): every bad input a one-line answer naming the file, one grammar.

Defects 5 and 6 (deep JSON, unknown kinds, numpy reprs, full disks, endless files) and the
frictions 8-12 (study defaults, packaged examples, method sets, flag names, readable output).
"""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

from taopt import examples
from taopt.errors import InstanceError, OutputError
from taopt.io import load_json, save_json
from taopt.orchestration.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _error_line(capsys) -> str:
    """The one line ``main`` printed on stderr (asserting there is exactly one)."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


# -- defect 5: one reader for every JSON file, with a depth guard -----------------------------


@pytest.mark.parametrize("command", ["navigate", "solve"])
def test_deeply_nested_file_is_one_line_naming_it(command, tmp_path, capsys):
    """100,000 nested '[' is refused in one line naming the file, by navigate as by solve."""
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000)
    argv = (
        ["navigate", "--field", str(deep), "--from", "0,0", "--to", "1,1"]
        if command == "navigate"
        else ["solve", str(deep)]
    )
    assert main(argv) == 2
    line = _error_line(capsys)
    assert str(deep) in line and "nested" in line


def test_moderately_deep_file_is_refused_by_the_depth_guard(tmp_path):
    """A nesting the parser survives (500 levels) is still refused, naming the file."""
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 500 + "]" * 500)
    with pytest.raises(InstanceError, match=r"deep\.json: .*nested more than 64"):
        load_json(deep)


# -- defect 6: messages name the file -------------------------------------------------------------


def test_field_file_given_to_solve_points_at_navigate(capsys):
    """A drift field file given to solve names the file and says to use navigate --field."""
    field = ROOT / "taopt/data/examples/field.json"
    assert main(["solve", str(field)]) == 2
    line = _error_line(capsys)
    assert str(field) in line and "taopt navigate --field" in line and "unknown" not in line


def test_unknown_kind_names_the_file(tmp_path, capsys):
    """An unknown kind names the file and lists the kinds, 'instance' among them."""
    odd = tmp_path / "odd.json"
    odd.write_text('{"kind": "zebra"}')
    assert main(["solve", str(odd)]) == 2
    line = _error_line(capsys)
    assert line.startswith(f"taopt solve: error: {odd}: unknown file kind")
    assert "instance" in line and "delivery_instance" in line


def test_navigate_field_error_names_the_file(tmp_path, capsys):
    """A malformed field file given to navigate is named in the error."""
    bad = tmp_path / "bad_field.json"
    bad.write_text('{"kind": "uniform", "vx": "fast", "vy": 0}')
    assert main(["navigate", "--field", str(bad), "--from", "0,0", "--to", "1,1"]) == 2
    line = _error_line(capsys)
    assert str(bad) in line and "vx" in line


def test_target_inside_obstacle_names_file_with_plain_floats(tmp_path, capsys):
    """A target inside an obstacle: the file is named, the point in plain floats (no np.float64)."""
    data = json.loads((ROOT / "taopt/data/examples/instance.json").read_text())
    data["targets"][2]["position"] = [50.0, 45.0]  # inside the triangle 'rock'
    path = tmp_path / "inst.json"
    path.write_text(json.dumps(data))
    assert main(["solve", str(path), "--quiet"]) == 2
    line = _error_line(capsys)
    assert str(path) in line and "(50.0, 45.0)" in line and "np." not in line


def test_endless_device_is_refused_after_the_size_guard(capsys, monkeypatch):
    """/dev/zero is refused once the size guard is read, not read until killed."""
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero here")
    monkeypatch.setenv("TAOPT_MAX_FILE_MB", "1")
    assert main(["solve", "/dev/zero"]) == 2
    line = _error_line(capsys)
    assert "/dev/zero" in line and "size guard" in line


def test_fifo_is_read_with_a_cap(tmp_path, monkeypatch):
    """A FIFO fed without end is refused after the cap (the read is chunked, never unbounded)."""
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    import threading

    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    stop = threading.Event()

    def feed() -> None:
        try:
            with open(fifo, "wb") as out:
                while not stop.is_set():
                    out.write(b" " * 65536)
        except (BrokenPipeError, OSError):
            pass

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    monkeypatch.setenv("TAOPT_MAX_FILE_MB", "0.5")
    try:
        with pytest.raises(InstanceError, match="pipe.json: longer than 0.5 MB"):
            load_json(fifo)
    finally:
        stop.set()
    writer.join(timeout=5)


def _full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_full_disk_names_the_file_and_leaves_no_temp(tmp_path, monkeypatch):
    """ENOSPC while saving JSON: an OutputError naming the path, no temp or partial file left."""
    monkeypatch.setattr("taopt.io.os.replace", _full_disk)
    target = tmp_path / "sol.json"
    with pytest.raises(OutputError, match=r"sol\.json: cannot be written \(No space left"):
        save_json({"a": 1}, target)
    assert list(tmp_path.iterdir()) == []


def test_unwritable_out_folder_refused_before_solving(tmp_path, capsys, monkeypatch):
    """solve --out into an unwritable folder fails before any method runs, naming the folder."""
    import taopt.orchestration.solving as solving

    ran = []
    monkeypatch.setattr(solving, "method_table", lambda *a, **k: ran.append(1))
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / "sub"  # a folder under a file: cannot be made
    code = main(["solve", "example:assignment_problem", "--out", str(out), "--quiet"])
    assert code == 2 and not ran
    line = _error_line(capsys)
    assert str(out) in line and "--out folder" in line


def test_study_cache_leaves_no_orphan_npy(tmp_path, monkeypatch):
    """A failure writing a cached matrix's description removes its .npy; the error names it."""
    import taopt.routing.scenarios as scenarios

    def failing_save(data, path):
        raise OutputError(f"{path}: cannot be written (No space left on device)")

    monkeypatch.setattr(scenarios, "save_json", failing_save)
    with pytest.raises(OutputError, match="No space left"):
        scenarios.drift_scenario(3, 1, 0, field="thesis", cache_dir=tmp_path, method="pmp")
    assert [p.name for p in tmp_path.iterdir()] == []


def test_study_cache_npy_write_failure_names_the_file(tmp_path, monkeypatch):
    """ENOSPC while writing the cached matrix: OutputError naming the .npy, nothing left."""
    import taopt.routing.scenarios as scenarios

    monkeypatch.setattr(scenarios.np, "save", _full_disk)
    with pytest.raises(OutputError, match=r"\.npy: cannot be written"):
        scenarios.drift_scenario(3, 1, 0, field="thesis", cache_dir=tmp_path, method="pmp")
    assert [p.name for p in tmp_path.iterdir()] == []


# -- friction 9: packaged examples ------------------------------------------------------------------


def test_examples_path_finds_every_kind():
    """taopt.examples.path gives an existing file for every listed example."""
    names = examples.names()
    assert {"budgeted_problem", "field", "demo", "delivery_example_20"} <= set(names)
    for name in names:
        assert examples.path(name).is_file()
    with pytest.raises(InstanceError, match="no example 'nope'; examples: assignment_problem"):
        examples.path("nope")


def test_example_prefix_in_solve_from_another_folder(tmp_path, capsys, monkeypatch):
    """taopt solve example:budgeted_problem works from a folder other than the clone's root."""
    monkeypatch.chdir(tmp_path)
    assert main(["solve", "example:budgeted_problem", "--methods", "MC", "--quiet"]) == 0
    assert "budgeted_problem.json" in capsys.readouterr().out
