"""``python -m taopt``: the ``taopt`` command line (see :mod:`taopt.cli`)."""

import sys

from taopt.cli import main

if __name__ == "__main__":
    sys.exit(main())
