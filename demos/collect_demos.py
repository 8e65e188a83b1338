"""Record the scripted expert's demonstrations as a LeRobot dataset: ``colorsort-collect`` as a script.

    python demos/collect_demos.py --episodes 2 --out datasets/example
    python demos/collect_demos.py --episodes 50 --workers 2 --out datasets/colorsort

Every option of ``colorsort-collect`` (``python demos/collect_demos.py --help``; docs/data.md) works here:
the cameras and their size, the variant, the demonstrator's perturbations (``--late-pass``, ``--late-pick``,
``--brightness``), ``--resume`` after an interruption, Ray (``--executor ray``). The dataset loads with
``LeRobotDataset("local/colorsort", root="datasets/colorsort")``.
"""

import sys

from colorsort.cli.collect import main

if __name__ == "__main__":
    sys.exit(main())
