"""``camera-pose``: every camera moved and turned, the colour sensor's (and its snapshot) included."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from colorsort.shifts.base import Episode, Shift, rounded, unit_vector
from colorsort.shifts.registry import register_shift

# The snapshot is the sensor camera's photo: it moves with it.
MOVED_TOGETHER = {"snapshot": "sensor"}


@register_shift
class CameraPose(Shift):
    name = "camera-pose"
    group = "viewpoint"
    summary = "every camera (scene, sensor and its snapshot, wrist) moved and turned, each its own way"
    unit = "{} cm moved, {} deg turned"
    magnitudes = ((0.5, 1.0), (1.0, 2.5), (2.0, 5.0))

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        return {camera: {"move": rounded(unit_vector(rng)), "axis": rounded(unit_vector(rng))}
                for camera in ("scene", "sensor", "wrist")}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        move_cm, turn_deg = self.magnitude(level)
        m = episode.model
        for cam in range(m.ncam):
            name = m.camera(cam).name
            alias = "wrist" if name.endswith("_wrist") else MOVED_TOGETHER.get(name, name)
            if alias not in drawn:
                continue
            move, axis = (np.asarray(drawn[alias][k], float) for k in ("move", "axis"))
            m.cam_pos[cam] += 0.01 * move_cm * move / np.linalg.norm(move)  # in the camera's body frame
            turn = np.zeros(4)
            mujoco.mju_axisAngle2Quat(turn, axis / np.linalg.norm(axis), np.deg2rad(turn_deg))
            q = np.zeros(4)
            mujoco.mju_mulQuat(q, m.cam_quat[cam].copy(), turn)  # turned about an axis of the camera's own frame
            m.cam_quat[cam] = q
