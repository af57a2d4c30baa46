"""The README's Python quick tour runs as written (a newcomer copies it first)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).parent.parent / "README.md"


def test_readme_python_blocks_run(capsys) -> None:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert blocks, "README has no python block"
    namespace: dict = {}
    exec(compile("\n".join(blocks), str(README), "exec"), namespace)
    exact, mc = namespace["exact"], namespace["mc"]
    assert exact.status == "optimal" and mc.objective >= exact.objective * (1 - 1e-9)
    assert "exact-sop-flow: optimal, objective=1675" in capsys.readouterr().out
