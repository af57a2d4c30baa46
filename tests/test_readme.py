"""The README's Python quick tour runs as written (a newcomer copies it first)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).parent.parent / "README.md"


def test_readme_python_blocks_run(capsys) -> None:
    """Each Python block runs on its own (a newcomer copies one at a time)."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert len(blocks) >= 2, "README has no python blocks"
    spaces = []
    for block in blocks:
        namespace: dict = {}
        exec(compile(block, str(README), "exec"), namespace)
        spaces.append(namespace)
    exact, mc = spaces[0]["exact"], spaces[0]["mc"]
    assert exact.status == "optimal" and mc.objective >= exact.objective * (1 - 1e-9)
    assert "exact: optimal, objective=1675" in capsys.readouterr().out
