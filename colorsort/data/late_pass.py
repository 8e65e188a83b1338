"""Late belt-pass: demos that show a policy the states it reaches when it lets a box through late.

The expert lets a box with no bin through in the very step the ray sees it, so its demos hold
one frame per such box of "box at the ray, belt stopped, arm waiting", labelled belt-pass. A
policy trained on them predicts belt-pass off even on those very frames (``demos/probe_pass.py``:
0 of 35 decisions on), so it holds there until the time limit (0% on ``distractors``): under
ACT's L1 loss a command that is on in about 5% of the frames stays at its usual value. With
``late_pass = n`` the recorder keeps each of the expert's belt-pass commands from the belt for a
number of steps drawn from 0..n, while the stored action stays the expert's: the state the policy
would sit in is then in the data about n/2 times per such box, each labelled with what the expert
does there. This is noise injection into the demonstrator's execution (DART, Laskey et al. 2017),
limited to the one command whose delay cannot make the expert fail. Measured (docs/baselines.md):
n = 9 was not enough, n = 40 taught the pass.
"""

from __future__ import annotations

import numpy as np

from colorsort.errors import ConfigError

# a generator of its own, seeded from the episode's seed: the env's own draws (boxes, lights) are
# untouched, so an episode recorded with late_pass differs from one without only by the delays
STREAM = 0x1A7E


class LatePass:
    """Holds back the expert's belt-pass command for 0..``max_steps`` steps each time it turns on."""

    def __init__(self, max_steps: int):
        if max_steps < 0:
            raise ConfigError(f"late_pass={max_steps}: give 0 (off) or more control steps")
        self.max_steps = max_steps
        self.rng = np.random.default_rng()
        self.commanded = False  # the expert's belt-pass in the previous step
        self.held = 0  # steps still to hold back

    def reset(self, seed: int) -> None:
        """Start an episode whose env seed is ``seed``."""
        self.rng = np.random.default_rng([seed, STREAM])
        self.commanded, self.held = False, 0

    def executed(self, action: np.ndarray) -> np.ndarray:
        """The action the env receives for the expert's ``action`` (the last element is belt-pass)."""
        on = bool(action[-1] > 0.0)
        if self.max_steps and on and not self.commanded:
            self.held = int(self.rng.integers(0, self.max_steps + 1))
        self.commanded = on
        if not (on and self.held > 0):
            return action
        self.held -= 1
        out = action.copy()
        out[-1] = -1.0
        return out
