"""ColorSort: an ABB IRB 140 with a vacuum cup sorts coloured boxes off a conveyor.

Importing the package registers the ``IRB140`` robot, the ``SuctionGripper`` and the
``ColorSort`` task with robosuite, so that ``suite.make("ColorSort", robots="IRB140")`` works.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from colorsort import models  # noqa: E402  (registers IRB140 and SuctionGripper)

__all__ = ["models"]
from colorsort.env import ColorSort  # noqa: E402  (registers the task with robosuite)

__all__ += ["ColorSort"]
