"""Thin wrapper of ``colorsort-sort``: run the scripted expert and report per box (see colorsort/sort.py)."""

import sys

from colorsort.cli.sort import main

if __name__ == "__main__":
    sys.exit(main())
