"""Late pick: demos that show a policy the state "box of a bin colour at the ray, arm still" often.

The expert starts its approach in the very step the ray sees a box of a bin colour, so its demos
hold about one frame per picked box of "box at the ray, belt stopped, arm waiting", labelled with
the start of the approach, against the 0..``late_pass`` frames per let-through box (``late_pass``)
of the same state labelled belt-pass. In the 48 ``camera-snapshot`` demos that is 110 frames that
start a pick against 1,425 that pass (``demos/probe_decisions.py``): a policy that tells a green box
from a yellow one less surely than red from purple lets every green box through, the green-bin
plateau of ``docs/baselines.md``. With ``late_pick = n`` the recorder holds the arm where it is for
a number of steps drawn from 0..n each time the stopping-belt expert starts an approach, storing
the expert's first approach action on every held frame, and then lets the expert go on from there
(the expert's clock stands still while it is held, so its plan is unchanged): noise injection into
the demonstrator's execution (DART, Laskey et al. 2017), as ``late_pass``, for the pick.
"""

from __future__ import annotations

import numpy as np

from colorsort.data.config import check_late_pick
from colorsort.expert.base import Expert
from colorsort.expert.sorter import Phase, SortingExpert

# a generator of its own, seeded from the episode's seed: the env's own draws and late_pass's are untouched
STREAM = 0x1A7E_0002


class LatePick:
    """Holds the arm back for 0..``max_steps`` control steps each time the expert starts a pick."""

    def __init__(self, max_steps: int):
        check_late_pick(max_steps, tracking=False)
        self.max_steps = max_steps
        self.rng = np.random.default_rng()
        self.held = 0  # held steps still to come
        self.pending: np.ndarray | None = None  # the expert's first approach action, held back
        self.last: np.ndarray | None = None  # the action the env got in the previous step

    def reset(self, seed: int) -> None:
        """Start an episode whose env seed is ``seed``."""
        self.rng = np.random.default_rng([seed, STREAM])
        self.held, self.pending, self.last = 0, None, None

    def act(self, expert: Expert, obs: dict) -> tuple[np.ndarray, np.ndarray]:
        """(stored, executed) actions for this step: the expert's own, unless a pick start is held back,
        when the stored one is the expert's first approach action and the executed one the previous step's
        (the expert is not asked again until the hold ends)."""
        if self.held > 0:
            assert self.pending is not None and self.last is not None
            self.held -= 1
            if self.held == 0:
                self.last = self.pending
            return self.pending, self.last
        waiting = self.max_steps > 0 and isinstance(expert, SortingExpert) and expert.phase is not Phase.APPROACH
        action = expert.act(obs).astype(np.float32)
        last, self.last = self.last, action
        if waiting and expert.phase is Phase.APPROACH and last is not None:  # this step starts a pick
            self.held = int(self.rng.integers(0, self.max_steps + 1))
            if self.held > 0:
                self.pending, self.last = action, last
                return action, last
        return action, action
