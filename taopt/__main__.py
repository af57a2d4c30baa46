"""``python -m taopt``: the ``taopt`` command line (see :mod:`taopt.orchestration.cli`)."""

import sys

from taopt.orchestration.cli import main

if __name__ == "__main__":
    sys.exit(main())
