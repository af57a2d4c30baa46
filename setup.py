"""Package discovery (the metadata is in pyproject.toml).

The packages are found, not listed: every package under ``taopt/``. The top-level folders
``models/`` and ``heuristics/`` are reached through the symbolic links ``taopt/models`` and
``taopt/heuristics`` (docs/architecture.md, "Layout"), so they install as ``taopt.models`` and
``taopt.heuristics`` and tools (mypy, IDEs) resolve them from the source tree. A new family's
package is installed without an edit here or in pyproject.toml.
"""

from setuptools import find_namespace_packages, setup

setup(packages=find_namespace_packages(include=["taopt", "taopt.*"], exclude=["*__pycache__*"]))
