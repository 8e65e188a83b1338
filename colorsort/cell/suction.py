"""The vacuum seal: the run-time half of the suction gripper.

The cup's ``adhesion`` actuator pulls on whatever the pad touches, which seats a box against
the pad but, being a soft contact force, lets a hanging box peel and creep under the arm's
fastest motions. A real vacuum cup is rigid once sealed, so while suction is commanded and the
pad lies flat on a box face (a pad-box contact whose normal is within ``SEAL_ANGLE_DEG`` of the
cup axis) a weld equality between cup and box is switched on, at the pose the two have at that
instant (no jump). It is switched off the physics step after the command drops.
"""

from __future__ import annotations

import mujoco
import numpy as np
from robosuite.utils.mjcf_utils import new_element

from colorsort.errors import ConfigError

SEAL_ANGLE_DEG = 15.0  # max angle between the cup axis and a box face normal to seal


class VacuumSeal:
    """Switches cup-box weld equalities from the suction command and the pad's contacts.

    Args:
        model, data: the compiled MuJoCo model and its data.
        cup_body: name of the cup body (welds' body1).
        pad_geom: name of the cup pad's collision geom.
        actuator: name of the suction (adhesion) actuator; on when its ctrl > half its range.
        box_bodies, box_geoms: the pooled boxes' body and geom names, in pool order.
        welds: the weld equality names, one per box, in pool order.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, cup_body: str, pad_geom: str, actuator: str,
                 box_bodies: list[str], box_geoms: list[str], welds: list[str]):
        self.model, self.data = model, data
        self.cup = model.body(cup_body).id
        self.pad = model.geom(pad_geom).id
        self.actuator = model.actuator(actuator).id
        self.box_bodies = np.array([model.body(b).id for b in box_bodies])
        self.box_of_geom = {model.geom(g).id: i for i, g in enumerate(box_geoms)}
        self.welds = np.array([model.equality(w).id for w in welds])
        self.held: int | None = None  # pool index of the sealed box
        self._cos_seal = np.cos(np.deg2rad(SEAL_ANGLE_DEG))

    @property
    def commanded(self) -> bool:
        lo, hi = self.model.actuator_ctrlrange[self.actuator]
        return bool(self.data.ctrl[self.actuator] > (lo + hi) / 2)

    def update(self) -> None:
        """Seal or release; call once per physics step, after the controller wrote ``ctrl``."""
        if not self.commanded:
            self.release()
        elif self.held is None:
            box = self._box_flat_on_pad()
            if box is not None:
                self._seal(box)

    def release(self, box: int | None = None) -> None:
        """Break the seal (with ``box``: only if that box is the one held)."""
        if self.held is not None and (box is None or box == self.held):
            self.data.eq_active[self.welds[self.held]] = 0
            self.held = None

    def grip(self) -> tuple[float, float]:
        """Where the cup holds the sealed box, from its weld: the box centre's distance from the cup axis [m]
        and the box's turn against the cup about that axis [deg], in [-45, 45) (a cube's side faces repeat
        every 90 deg)."""
        if self.held is None:
            raise ConfigError("no box is sealed to the cup")
        weld = self.model.eq_data[self.welds[self.held]]
        turn = np.zeros(9)
        mujoco.mju_quat2Mat(turn, weld[6:10])
        yaw = float(np.degrees(np.arctan2(turn[3], turn[0])))  # rows of the 3x3: R[1, 0], R[0, 0]
        return float(np.hypot(weld[3], weld[4])), (yaw + 45.0) % 90.0 - 45.0

    def get_state(self) -> tuple[int, np.ndarray]:
        """(the sealed box's pool index or -1, the weld's ``eq_data`` (mjNEQDATA,), zeros when none)."""
        held = self.held if self.held is not None else -1
        weld = self.model.eq_data[self.welds[held]].copy() if held >= 0 else np.zeros(mujoco.mjNEQDATA)
        return held, weld

    def set_state(self, held: int, weld: np.ndarray) -> None:
        """The seal as ``get_state`` saved it (whether its weld is active is MuJoCo's state)."""
        self.held = held if held >= 0 else None
        if held >= 0:
            self.model.eq_data[self.welds[held]] = weld

    def _box_flat_on_pad(self) -> int | None:
        d = self.data
        axis = d.xmat[self.cup].reshape(3, 3)[:, 2]
        for k in range(d.ncon):
            g1, g2 = d.contact.geom1[k], d.contact.geom2[k]
            other = g2 if g1 == self.pad else g1 if g2 == self.pad else None
            if other is None or other not in self.box_of_geom:
                continue
            if abs(d.contact.frame[k][:3] @ axis) >= self._cos_seal:
                return self.box_of_geom[other]
        return None

    def _seal(self, box: int) -> None:
        d, m = self.data, self.model
        body = self.box_bodies[box]
        R_cup = d.xmat[self.cup].reshape(3, 3)
        rel_quat, cup_inv = np.zeros(4), np.zeros(4)
        mujoco.mju_negQuat(cup_inv, d.xquat[self.cup])
        mujoco.mju_mulQuat(rel_quat, cup_inv, d.xquat[body])
        eq = self.welds[box]
        m.eq_data[eq, 0:3] = 0.0  # anchor at the box's origin
        m.eq_data[eq, 3:6] = R_cup.T @ (d.xpos[body] - d.xpos[self.cup])  # box pose in the cup frame
        m.eq_data[eq, 6:10] = rel_quat
        d.eq_active[eq] = 1
        self.held = box


def add_welds(task_model, cup_body: str, box_names: list[str]) -> list[str]:
    """Add one inactive weld equality per box, between ``cup_body`` and the box, to a robosuite task
    model (``ManipulationTask``); returns their names, in ``box_names``' order."""
    names = [f"suction_{name}" for name in box_names]
    for weld, box in zip(names, box_names, strict=True):
        task_model.equality.append(
            new_element("weld", weld, body1=cup_body, body2=box, active="false", solref="0.01 1"))
    return names
