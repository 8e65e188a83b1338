"""``robot-start``: the arm starts with its joints offset from its home pose (as LIBERO-Plus's robot initial state)."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift, rounded, unit_vector
from colorsort.shifts.registry import register_shift


@register_shift
class RobotStart(Shift):
    name = "robot-start"
    group = "viewpoint"
    summary = "the arm's starting joint angles offset from home, in a direction drawn per episode"
    unit = "{} rad (norm over the arm's joints)"
    magnitudes = (0.1, 0.2, 0.4)

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        return {"direction": rounded(unit_vector(rng, 6))}  # the IRB 140's six joints (a 7-joint arm: the first six)

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        env = episode.env
        robot = env.robots[0]
        joints, qpos = robot._ref_joint_indexes, robot._ref_joint_pos_indexes
        offset = np.zeros(len(joints))
        direction = np.asarray(drawn["direction"])
        n = min(len(joints), len(direction))
        offset[:n] = self.magnitude(level) * direction[:n] / np.linalg.norm(direction[:n])
        low, high = env.mj_model.jnt_range[joints].T
        data = env.mj_data
        data.qpos[qpos] = np.clip(data.qpos[qpos] + offset, low, high)
        data.qvel[robot._ref_joint_vel_indexes] = 0.0
        env.sim.forward()
        for controller in robot.part_controllers.values():
            controller.update(force=True)
