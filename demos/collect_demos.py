"""Thin wrapper of ``colorsort-collect``: record the scripted expert as a LeRobot dataset (see colorsort/collect.py).

Example: ``python demos/collect_demos.py --episodes 50 --workers 2 --out datasets/colorsort``
"""

import sys

from colorsort.cli.collect import main

if __name__ == "__main__":
    sys.exit(main())
