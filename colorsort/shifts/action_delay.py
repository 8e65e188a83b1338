"""``action-delay``: each action reaches the cell a number of control steps late (50 ms each at 20 Hz).

Until the first action arrives the cell holds: joint targets where the arm starts, suction and belt pass off.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class ActionDelay(Shift):
    name = "action-delay"
    group = "dynamics"
    summary = "every action applied this many control steps after the policy gave it"
    unit = "{} control steps late ({} ms at 20 Hz)"
    magnitudes = ((1, 50), (2, 100), (3, 150))
    trainable = False  # whole control steps: nothing lies between 0 and 1

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        env = episode.env
        q = np.array([env.mj_data.joint(j).qpos[0] for j in env.robots[0].robot_joints])
        hold = np.concatenate([q, [-1.0, -1.0]])
        queue = deque([hold.copy() for _ in range(self.magnitude(level)[0])])

        def delay(action: np.ndarray) -> np.ndarray:
            queue.append(np.array(action, dtype=float))
            return queue.popleft()

        episode.on_action(delay)
