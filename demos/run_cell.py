"""Thin wrapper: ``python demos/run_cell.py --seconds 60`` (see ``colorsort.demo``)."""

import sys

from colorsort.demo import main

if __name__ == "__main__":
    sys.exit(main())
