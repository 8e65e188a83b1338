"""Late pick: demos that show a policy the state "box of a bin colour at the ray, arm still" often.

The expert starts its approach in the very step the ray sees a box of a bin colour, so its demos
hold about one frame per picked box of "box at the ray, belt stopped, arm waiting", labelled with
the start of the approach, against the 0..``late_pass`` frames per let-through box of the same state
labelled belt-pass: in the 48 ``camera-snapshot`` demos 110 frames that start a pick against 1,425
that pass. A policy that tells a green box from a yellow one less surely than red from purple lets
every green box through (the green-bin plateau of ``docs/baselines.md``). With ``late_pick = n`` the
recorder holds the arm where it is for a number of steps drawn from 0..n each time the expert starts
an approach (``Expert.approaching`` turns on), storing the expert's first approach action on every
held frame, and then lets the expert go on from there (its clock stands still while it is held, so
its plan is unchanged). Stopping belt only: on a tracking belt the held pick's box would move on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from colorsort.data.perturbations.base import Hook, Step
from colorsort.data.perturbations.holds import Holds
from colorsort.data.perturbations.registry import register_perturbation
from colorsort.expert.base import Expert
from colorsort.variants import Variant

# a generator of its own, seeded from the episode's seed: the env's own draws and late_pass's are untouched
LATE_PICK_STREAM = 0x1A7E_0002


@register_perturbation
@dataclass(frozen=True)
class LatePick(Holds):
    """Holds the arm back for 0..``max_steps`` control steps each time the expert starts a pick."""

    name = "late_pick"
    tag_prefix = "pick"
    help = ("hold the arm back 0..N control steps at each pick's start, the stored action the expert's first "
            "approach (stopping belt only; 0: off)")
    order = 10  # next to the expert: it decides whether the expert is asked at all

    def applies_to(self, variant: Variant | None, tracking: bool) -> bool:
        return not tracking

    def refusal(self, variant: Variant | None) -> str:
        return (f"late_pick={self.max_steps} holds a pick back on a stopped belt; on a tracking belt the box "
                "would move on: give late_pick=0")

    def describe(self) -> str:
        return f"every pick held back 0-{self.max_steps} steps"

    def episode(self, seed: int, expert: Expert) -> Hook:
        return _LatePickHook(self.max_steps, np.random.default_rng([seed, LATE_PICK_STREAM]), expert)


class _LatePickHook(Hook):
    def __init__(self, max_steps: int, rng: np.random.Generator, expert: Expert):
        self.max_steps, self.rng, self.expert = max_steps, rng, expert
        self.held = 0  # held steps still to come
        self.pending: np.ndarray | None = None  # the expert's first approach action, held back
        self.last: np.ndarray | None = None  # the action executed in the previous step

    def act(self, inner: Callable[[], Step]) -> Step:
        if self.held > 0:  # the expert is not asked until the hold ends
            assert self.pending is not None and self.last is not None
            self.held -= 1
            if self.held == 0:  # the last held step executes the approach itself
                self.last = self.pending
            return Step(self.pending, self.last)
        was_approaching = self.expert.approaching
        step = inner()
        last, self.last = self.last, step.executed
        if not was_approaching and self.expert.approaching and last is not None:  # this step starts a pick
            self.held = int(self.rng.integers(0, self.max_steps + 1))
            if self.held > 0:
                self.pending, self.last = step.stored, last
                return Step(step.stored, last)
        return step
