"""A vacuum cup as a robosuite ``GripperModel``.

Suction is MuJoCo physics in two parts. The ``adhesion`` actuator on the cup body adds an
attracting normal force to the contacts the cup pad already has, so the cup only acts on what
it touches (nothing is grasped through the air). Once the pad lies flat on a box face the
vacuum seals: ``colorsort.cell.suction.VacuumSeal`` switches on a weld equality at the pose the two
bodies have (no teleporting, no reparenting), and switches it off the physics step after the
command drops, so a released box falls at once.
"""

from __future__ import annotations

import numpy as np
from robosuite.models.grippers import GRIPPER_MAPPING, GripperModel

from colorsort.paths import asset_path

SUCTION_FORCE_N = 20.0  # adhesion gain at full command, mirrored from the MJCF for documentation
CUP_LENGTH_M = 0.095  # flange face to cup pad face


class SuctionGripper(GripperModel):
    """Vacuum cup; action in [-1, 1], positive means suction on.

    Args:
        idn: unique identifier of this gripper instance (robosuite's naming prefix).
    """

    def __init__(self, idn: int | str = 0):
        super().__init__(asset_path("suction_gripper", "suction_gripper.xml"), idn=idn)

    def format_action(self, action: np.ndarray) -> np.ndarray:
        """Map the policy's command to the actuator's normalised command: on (+1) or off (-1).

        Suction is binary, like a vacuum valve: any positive command opens it fully.
        """
        assert len(action) == self.dof, f"SuctionGripper expects {self.dof} action, got {len(action)}"
        return np.where(np.asarray(action) > 0.0, 1.0, -1.0)

    @property
    def init_qpos(self) -> np.ndarray:
        return np.zeros(0)

    @property
    def speed(self) -> float:
        return 1.0

    @property
    def _important_geoms(self) -> dict[str, list[str]]:
        return {"left_finger": [], "right_finger": [], "left_fingerpad": [], "right_fingerpad": [], "cup": ["cup_pad"]}


GRIPPER_MAPPING.setdefault("SuctionGripper", SuctionGripper)
