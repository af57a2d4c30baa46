"""Same call, same answer, whatever was imported before it (issue 31, item 4).

Every bound every family declares (``lower`` at each strength) is computed on the reference
problems in two fresh interpreters: one that imports ``taopt.models`` and
``taopt.heuristics`` first and one that does not. The two must agree exactly, and the second
must never load a models or heuristics module (the core never imports them).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from conftest import ROOT

SCRIPT = r"""
import json, sys
import numpy as np
if sys.argv[1] == "methods-first":
    import taopt.models, taopt.heuristics  # noqa: F401
import taopt
from taopt.bounds import STRENGTHS, bound, lower
from taopt.registry import family_of
import reference

problems = [make().problem for make in reference.REFERENCES]
rng = np.random.default_rng(0)  # issue 31's case: the DFJ LP above the degree-penalised bound
points = rng.uniform(0, 10, size=(10, 2))
cost = np.linalg.norm(points[:, None] - points[None], axis=2) + rng.uniform(0, 3, size=(10, 10))
np.fill_diagonal(cost, 0)
problems.append(taopt.AssignmentProblem(cost, n_targets=8, name="issue-31"))
values = {}
for number, problem in enumerate(problems):
    family = family_of(problem)
    for name in family.bounds:
        key = f"{number}:{family.kind}:{name}"
        if name == "lower":
            for strength in STRENGTHS:
                values[f"{key}:{strength}"] = lower(problem, strength)
        else:
            values[key] = bound(problem, name)
loaded = sorted(m for m in sys.modules if m.startswith(("taopt.models", "taopt.heuristics")))
print(json.dumps({"values": values, "loaded": loaded}))
"""


def _bounds(order: str) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")])}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, order],
        capture_output=True, text=True, cwd=ROOT, env=env, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_bound_is_the_same_with_or_without_the_methods_imported():
    """Each declared bound (lower at every strength) is equal in fresh interpreters that do
    and do not import taopt.models and taopt.heuristics first; the core loads neither."""
    core_only = _bounds("core-only")
    methods_first = _bounds("methods-first")
    assert core_only["loaded"] == []
    assert methods_first["loaded"]  # the other side really imported the methods
    assert core_only["values"].keys() == methods_first["values"].keys()
    differ = {
        key: (value, methods_first["values"][key])
        for key, value in core_only["values"].items()
        if value != methods_first["values"][key]
    }
    assert not differ, differ
    families = {key.split(":")[1] for key in core_only["values"]}
    from taopt.registry import families as registered

    assert families == {family.kind for family in registered()}


CERTIFYING = r"""
import json, sys
if sys.argv[1] == "methods-first":
    import taopt.models  # noqa: F401
from taopt.orchestration.pipeline import certifying_method
import reference

print(json.dumps([certifying_method(make().problem) for make in reference.REFERENCES]))
"""


def test_certifying_method_is_the_same_with_or_without_the_models_imported():
    """The public certifying_method (the orchestration's) names the same exact method for every
    reference problem in fresh interpreters that do and do not import taopt.models first (the
    registry's lookup alone gave None without them: verify --exact depended on import order)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")])}
    answers = []
    for order in ("core-only", "methods-first"):
        done = subprocess.run(
            [sys.executable, "-c", CERTIFYING, order],
            capture_output=True, text=True, cwd=ROOT, env=env, check=False,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr[-3000:]
        answers.append(json.loads(done.stdout.strip().splitlines()[-1]))
    assert answers[0] == answers[1]
    assert None not in answers[0]
