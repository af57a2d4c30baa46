"""Build the documentation site: ``python docs/build.py`` (after ``pip install ".[docs]"``).

Runs ``sphinx-build -W --keep-going -n -b html docs docs/_build/html``: every warning is an
error (all of them are reported before the build fails), ``-n`` makes every cross-reference
into taopt and every internal link resolve, and the notebooks are executed (myst-nb). Extra
arguments are passed to sphinx-build (e.g. ``-q``, or ``-E`` to rebuild every page).
Exit status: sphinx-build's.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
OUT = DOCS / "_build" / "html"


def main(argv: list[str] | None = None) -> int:
    """Build the site into ``docs/_build/html`` with warnings as errors; return the exit code."""
    from sphinx.cmd.build import build_main

    extra = list(sys.argv[1:] if argv is None else argv)
    return build_main(["-W", "--keep-going", "-n", "-b", "html", *extra, str(DOCS), str(OUT)])


if __name__ == "__main__":
    sys.exit(main())
