"""The README runs as written: its Python blocks, its quick tour from the checkout root, its
command lines and its table of methods (a newcomer copies them first)."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys

from conftest import ROOT

README = ROOT / "README.md"
TEXT = README.read_text()
PYTHON_BLOCKS = re.findall(r"```python\n(.*?)```", TEXT, re.S)
BASH_BLOCKS = re.findall(r"```bash\n(.*?)```", TEXT, re.S)


def test_fresh_machine_commands_are_the_two_documented_ones() -> None:
    """The two fresh-machine commands are in the README exactly as the issue fixes them."""
    assert BASH_BLOCKS[0].strip() == (
        "python3 -m venv .venv && . .venv/bin/activate && pip install . && taopt demo"
    )
    assert BASH_BLOCKS[1].strip() == (
        'python3 -m venv .venv && . .venv/bin/activate && pip install ".[test]" && pytest -q'
    )


def test_readme_python_blocks_run(capsys) -> None:
    """Each Python block after the quick tour runs on its own (a newcomer copies one at a time)."""
    assert len(PYTHON_BLOCKS) >= 5, "README lost its examples"
    for block in PYTHON_BLOCKS[1:]:
        exec(compile(block, str(README), "exec"), {})
    out = capsys.readouterr().out
    assert "exact: optimal, objective=1675" in out  # the certified TSPLIB ESC12 optimum
    assert "Lemma 2.3" in out and "bytes relayed" in out


def test_quick_tour_runs_from_the_checkout_root() -> None:
    """The quick tour pasted into Python started in the checkout root runs, on the whole package."""
    tour = PYTHON_BLOCKS[0]
    check = "\nimport taopt.models, taopt.heuristics\nprint('package:', taopt.__file__)\n"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [sys.executable, "-c", tour + check],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env=dict(env, MPLBACKEND="Agg"),
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert any(line.startswith("exact: optimal") for line in lines), done.stdout
    assert any(line.startswith("methods: ['exact', 'VN'") for line in lines), done.stdout
    assert lines[-1] == f"package: {ROOT / 'taopt' / '__init__.py'}"


def _commands() -> list[list[str]]:
    """Every ``taopt ...`` command line of the README's bash blocks, as argv lists."""
    found = []
    for block in BASH_BLOCKS:
        for line in block.splitlines():
            line = line.split("&&")[-1].strip()
            if line.startswith("taopt "):
                found.append(shlex.split(line, comments=True)[1:])
    return found


def test_readme_command_lines_parse_without_deprecated_flags(capsys) -> None:
    """Every taopt command the README shows is valid in today's grammar and warns of nothing."""
    from taopt.orchestration.cli import build_parser

    commands = _commands()
    named = {argv[0] if argv[0] != "study" else " ".join(argv[:2]) for argv in commands}
    assert {"demo", "navigate", "solve", "verify", "claims", "simulate"} <= named
    assert {"study drift", "study delivery", "study capability", "study comm"} <= named
    parser = build_parser()
    for argv in commands:
        parser.parse_args(argv)
    assert capsys.readouterr().err == ""


def _generated():
    """docs/generated.py, loaded by path (the docs folder is no package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("generated", ROOT / "docs" / "generated.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_readme_families_block_is_current() -> None:
    """The README's families block is what docs/generated.py writes from the specs today
    (stale: run ``python docs/generated.py --write-readme``), and the docs site has the same table."""
    generated = _generated()
    assert generated.readme_with_block(TEXT) == TEXT, (
        "README.md's families block is stale: python docs/generated.py --write-readme"
    )
    assert generated.families_table() in generated.generated_pages()["kinds.md"]


def test_readme_families_block_lists_what_available_methods_lists() -> None:
    """Each row's methods are taopt.available_methods of the family's example (peers aside)."""
    import taopt
    from taopt.orchestration.solving import load_problem_file
    from taopt.registry import file_kinds

    for kind in file_kinds():
        problem, _ = load_problem_file(ROOT / "taopt" / "data" / "examples" / f"{kind}.json")
        name = type(problem).__name__
        row = re.search(rf"^\| `{name}` \| [^|]+ \| ([^|]+) \|", TEXT, re.M)
        assert row, f"no README row for {name}"
        listed = [m.strip() for m in row.group(1).split(",")]
        peers = set(taopt.available_methods(problem, "peer"))
        assert listed == [m for m in taopt.available_methods(problem) if m not in peers], name


def test_file_formats_doc_lists_every_kind() -> None:
    """docs/file-formats.md's table names the kinds that are no family's; the generated pages
    (docs/generated.py, from the family specs and the schema folder) name every kind."""
    from taopt.registry import file_kinds
    from taopt.result import payload_schemas
    from taopt.schemas import kinds

    doc = (ROOT / "docs" / "file-formats.md").read_text()
    table = set(re.findall(r"^\| `(\w+)` \| \[`\w+\.schema\.json`\]", doc, re.M))
    assert set(kinds()) - set(file_kinds()) <= table  # instance, field, solution
    pages = _generated().generated_pages()
    assert "```{include} _includes/payload-kinds.md" in doc  # the payload kinds: generated
    for name in payload_schemas():
        assert f"| `{name}` |" in pages["_includes/payload-kinds.md"], name
    assert "```{include} _includes/family-kinds.md" in doc  # the problem kinds: generated
    for kind in file_kinds():
        assert f"| `{kind}` |" in pages["kinds.md"], kind
        assert f"| `{kind}` |" in pages["_includes/family-kinds.md"], kind
        assert f"`{kind}`" not in TEXT or kind in ("instance", "field", "solution"), kind
    for kind in kinds():
        assert f"## `{kind}`" in pages["schemas.md"], kind
    assert "taopt kinds" in TEXT
