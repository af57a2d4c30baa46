"""Package discovery (the metadata is in pyproject.toml).

The packages are found, not listed: every package under ``taopt/``, and the top-level
``models/`` and ``heuristics/`` folders installed as ``taopt.models`` and
``taopt.heuristics`` (docs/architecture.md, "Layout"). A new family's package is installed
without an edit here or in pyproject.toml.
"""

from setuptools import find_namespace_packages, setup

MAPPED = {"taopt.models": "models", "taopt.heuristics": "heuristics"}


def _packages() -> list[str]:
    found = find_namespace_packages(include=["taopt", "taopt.*"], exclude=["*__pycache__*"])
    for package, folder in MAPPED.items():
        found.append(package)
        found += [
            f"{package}.{sub}"
            for sub in find_namespace_packages(where=folder, exclude=["*__pycache__*"])
        ]
    return found


setup(packages=_packages(), package_dir={"taopt": "taopt", **MAPPED})
