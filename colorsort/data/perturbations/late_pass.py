"""Late belt-pass: demos that show a policy the states it reaches when it lets a box through late.

The expert lets a box with no bin through in the very step the ray sees it, so its demos hold
one frame per such box of "box at the ray, belt stopped, arm waiting", labelled belt-pass. A
policy trained on them predicts belt-pass off even on those very frames (0 of 35 decisions on),
so it holds there until the time limit (0% on ``distractors``): under ACT's L1 loss a command that
is on in about 5% of the frames stays at its usual value. With ``late_pass = n`` the recorder keeps
each of the expert's belt-pass commands from the belt for a number of steps drawn from 0..n, while
the stored action stays the expert's: the state the policy would sit in is then in the data about
n/2 times per such box, each labelled with what the expert does there. Measured (docs/baselines.md):
n = 9 was not enough, n = 40 taught the pass.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from colorsort.data.perturbations.base import Hook, Step
from colorsort.data.perturbations.holds import Holds
from colorsort.data.perturbations.registry import register_perturbation
from colorsort.expert.base import Expert

# a generator of its own, seeded from the episode's seed: the env's own draws (boxes, lights) are
# untouched, so an episode recorded with late_pass differs from one without only by the delays
LATE_PASS_STREAM = 0x1A7E


@register_perturbation
@dataclass(frozen=True)
class LatePass(Holds):
    """Holds back the expert's belt-pass command for 0..``max_steps`` control steps each time it turns on."""

    name = "late_pass"
    tag_prefix = "late"
    help = ("hold each belt pass back 0..N control steps, the stored action staying the expert's: demos that show "
            "a box with no bin waiting at the ray (0: off)")
    order = 20  # around late_pick: a held pick's step still passes through here

    def describe(self) -> str:
        return f"every belt pass held back 0-{self.max_steps} steps"

    def episode(self, seed: int, expert: Expert) -> Hook:
        return _LatePassHook(self.max_steps, np.random.default_rng([seed, LATE_PASS_STREAM]))


class _LatePassHook(Hook):
    def __init__(self, max_steps: int, rng: np.random.Generator):
        self.max_steps, self.rng = max_steps, rng
        self.commanded = False  # the belt-pass asked for in the previous step
        self.held = 0  # steps still to hold back

    def act(self, inner: Callable[[], Step]) -> Step:
        step = inner()
        action = step.executed
        on = bool(action[-1] > 0.0)
        if on and not self.commanded:
            self.held = int(self.rng.integers(0, self.max_steps + 1))
        self.commanded = on
        if not (on and self.held > 0):
            return step
        self.held -= 1
        executed = action.copy()
        executed[-1] = -1.0
        return Step(step.stored, executed)
