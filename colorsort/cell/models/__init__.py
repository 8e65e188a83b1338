"""robosuite models of the ColorSort cell: the IRB 140, the suction gripper, the conveyor arena."""

from colorsort.cell.models.irb140 import IRB140
from colorsort.cell.models.suction_gripper import SuctionGripper

__all__ = ["IRB140", "SuctionGripper"]
