"""The referee: what became of each box, the episode's tally, and whether an episode succeeded.

One outcome model for every layer. A box leaves play with one ``Outcome``:

- ``placed``: it came to rest in the bin of its colour;
- ``misplaced``: it came to rest in another bin;
- ``dropped``: a box of a bin colour fell to the floor or off the belt's end;
- ``rejected``: a box with no bin (a distractor) left the belt's end: it was let through.

``placed`` and ``rejected`` are the boxes handled right. ``judge`` decides an episode of N boxes
from its events (the benchmark, the collector, replay); ``Tally.success`` is robosuite's task
success (``boxes_to_sort`` placed, none misplaced or dropped).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from colorsort.cell.boxes import Box, BoxPool, BoxStatus
from colorsort.config import BIN_COLORS, CellLayout, is_distractor

logger = logging.getLogger("colorsort")

SETTLED_SPEED = 0.05  # [m/s] a box slower than this inside a bin counts as resting there


FLOOR_MARGIN = 0.02  # [m] a box whose centre is this close to resting on the floor (no bin) has fallen


class Outcome(StrEnum):
    """How a box left play; the value is what reports and JSON files print."""

    PLACED = "placed"
    MISPLACED = "misplaced"
    DROPPED = "dropped"
    REJECTED = "rejected"

    @property
    def handled_right(self) -> bool:
        """Placed in its own bin, or (no bin) let through."""
        return self in (Outcome.PLACED, Outcome.REJECTED)

    @property
    def reward(self) -> float:
        """The task's sparse reward for it: +1 placed, -1 misplaced or dropped, 0 let through."""
        return {Outcome.PLACED: 1.0, Outcome.REJECTED: 0.0}.get(self, -1.0)


@dataclass(frozen=True)
class BoxEvent:
    """A box leaving play."""

    time: float  # [s] sim time
    serial: int
    color: str
    outcome: Outcome
    bin: str | None  # the bin it rests in; None when it left the belt or fell


def describe_box(color: str, outcome: str, bin: str | None) -> str:
    """A box's outcome in words (``BoxEvent`` fields, or their JSON): ``red box -> red bin``,
    ``blue box -> red bin (misplaced)``, ``green box dropped``, ``purple box let through``."""
    if outcome == Outcome.REJECTED:
        return f"{color} box let through"
    if bin is not None:
        return f"{color} box -> {bin} bin" + (" (misplaced)" if outcome == Outcome.MISPLACED else "")
    return f"{color} box {Outcome(outcome).value}"


@dataclass
class Tally:
    """Episode counters reported in ``info``; ``placed`` counts boxes in the bin of their colour, per bin."""

    placed: dict[str, int] = field(default_factory=lambda: {c: 0 for c in BIN_COLORS})
    misplaced: int = 0
    dropped: int = 0
    rejected: int = 0
    spawned: int = 0
    bins_emptied: int = 0

    def count(self, event: BoxEvent) -> None:
        if event.outcome is Outcome.PLACED:
            assert event.bin is not None, "a placed box rests in a bin"
            self.placed[event.bin] += 1
        else:
            name = event.outcome.value
            setattr(self, name, getattr(self, name) + 1)

    def success(self, boxes_to_sort: int) -> bool:
        """robosuite's task success: ``boxes_to_sort`` boxes placed, none misplaced or dropped."""
        return sum(self.placed.values()) >= boxes_to_sort and self.misplaced == 0 and self.dropped == 0

    @property
    def failed(self) -> bool:
        return self.misplaced > 0 or self.dropped > 0


@dataclass(frozen=True)
class Verdict:
    """An episode of ``boxes`` boxes, judged from its events."""

    done: bool  # that many boxes have left play
    success: bool  # done, and each of them handled right
    failed: bool  # one of them was misplaced or dropped (done or not)
    reason: str  # "ok", the first wrong outcome of a finished episode, or "timeout" for an unfinished one


def episode_rule(done: Any, failed: Any) -> tuple[Any, Any]:
    """The benchmark's rule for an episode whose counted boxes have all left play (``done``) and of which one was
    misplaced or dropped (``failed``): (success, terminated), on bools or on arrays of them (a row per world) alike.
    An episode succeeds when done with none failed, and ends at either (truncation is its env's step limit)."""
    return np.logical_and(done, np.logical_not(failed)), np.logical_or(done, failed)


def judge(events: list[BoxEvent], boxes: int) -> Verdict:
    """The verdict on an episode that ends when ``boxes`` boxes have left play; later events do not count."""
    first = events[:boxes]
    wrong = [e.outcome for e in first if not e.outcome.handled_right]
    done = len(first) >= boxes
    reason = ("timeout" if not done else wrong[0].value if wrong else "ok")
    success, _ = episode_rule(done, bool(wrong))
    return Verdict(done, bool(success), bool(wrong), reason)


@dataclass(frozen=True)
class EpisodeTally:
    """What an episode's counted boxes came to: its verdict, a count per ``Outcome``, the distractors among them and
    the times [s] of those handled right (``EpisodeResult`` and the Gymnasium env's ``info`` both read it)."""

    verdict: Verdict
    counts: dict[Outcome, int]
    distractors: int
    sorted_times: list[float]

    @classmethod
    def of(cls, events: Sequence[BoxEvent], boxes: int) -> EpisodeTally:
        """The tally of the first ``boxes`` of ``events`` (the boxes that left play, in order)."""
        counted = list(events[:boxes])
        return cls(judge(counted, boxes), outcome_counts(counted), sum(is_distractor(e.color) for e in counted),
                   [e.time for e in counted if e.outcome.handled_right])


def outcome_counts(events: list[BoxEvent]) -> dict[Outcome, int]:
    """How many of ``events`` ended each way."""
    return {o: sum(e.outcome is o for e in events) for o in Outcome}


class Referee:
    """Watches the boxes in play, records how each leaves (``events``, ``tally``) and empties full bins.

    Args:
        layout: the cell's geometry [m].
        bin_capacity: boxes a bin holds before it is emptied.
    """

    def __init__(self, layout: CellLayout, bin_capacity: int):
        self.layout, self.bin_capacity = layout, bin_capacity
        self.reset()

    def reset(self) -> None:
        self.tally = Tally()
        self.events: list[BoxEvent] = []

    def update(self, pool: BoxPool, now: float, remove: Callable[[Box], None]) -> float:
        """Judge every box in play at sim time ``now`` [s]; boxes that left the belt or fell are handed
        to ``remove`` (back to the pool), a full bin's boxes too. Returns the step's sparse reward."""
        reward = 0.0
        for box in pool.boxes:
            if box.status is not BoxStatus.IN_PLAY:
                continue
            outcome, bin_color = self.outcome(box.color, pool.pos(box), pool.speed(box))
            if outcome is None:
                continue
            event = BoxEvent(now, box.serial, box.color, outcome, bin_color)
            self.events.append(event)
            self.tally.count(event)
            reward += outcome.reward
            if bin_color is not None:
                box.status, box.bin = BoxStatus.IN_BIN, bin_color
                logger.info("A %s box landed in the %s bin.", box.color, bin_color)
                inside = pool.in_bin(bin_color)
                if len(inside) >= self.bin_capacity:
                    logger.info("Emptying %s bin because it's full.", bin_color)
                    for b in inside:
                        remove(b)
                    self.tally.bins_emptied += 1
            else:
                if outcome is Outcome.DROPPED:
                    logger.info("A %s box was dropped.", box.color)
                remove(box)
        return reward

    def bin_under(self, x: float, y: float) -> str | None:
        """Colour of the bin whose inner footprint contains (x, y) [m], or None."""
        L = self.layout
        inner_x = L.bin_size[0] / 2 - L.bin_wall
        inner_y = L.bin_size[1] / 2 - L.bin_wall
        for k, color in enumerate(BIN_COLORS):
            bx, by = L.bin_center(k)
            if abs(x - bx) < inner_x and abs(y - by) < inner_y:
                return color
        return None

    def outcome(self, color: str, pos: np.ndarray, speed: float) -> tuple[Outcome | None, str | None]:
        """What became of a box of ``color`` in play at ``pos`` [m] moving at ``speed`` [m/s]:
        (outcome, bin it rests in), or (None, None) while it is still in play."""
        L = self.layout
        x, y, z = pos
        half = L.box_size / 2
        bin_color = self.bin_under(x, y)
        if bin_color is not None and z < L.bin_size[2] and speed < SETTLED_SPEED:
            return (Outcome.PLACED if color == bin_color else Outcome.MISPLACED), bin_color
        on_floor = z < half + FLOOR_MARGIN and bin_color is None
        past_end = x < L.belt_end_x and abs(y - L.belt_y) < L.belt_width and z < L.belt_top_z + half
        if on_floor or past_end:
            return (Outcome.DROPPED if color in BIN_COLORS else Outcome.REJECTED), None
        return None, None

    def staged_rewards(self, pool: BoxPool, pad_pos: np.ndarray, held: int | None) -> dict[str, float]:
        """Dense progress on the next box that has a bin (lowest serial in play), by stage.

        ``reach`` in [0, 0.25]: 0.25 (1 - tanh(10 d)), d [m] from the cup pad (at ``pad_pos``) to the
        box's top face; ``seal``: 0.5 while the cup holds the box (``held`` is its pool index);
        ``carry`` in [0.5, 0.75] while it holds it: 0.5 + 0.25 (1 - tanh(5 e)), e [m] the box's
        horizontal distance to its bin's centre; ``place``: 1 while the box, held or falling, is over
        the inside of its own bin. ``progress`` is the largest; all are 0 when no box with a bin is in
        play. Boxes with no bin (let through on the belt) earn nothing here.
        """
        stages = {"reach": 0.0, "seal": 0.0, "carry": 0.0, "place": 0.0}
        targets = [b for b in pool.in_play() if b.color in BIN_COLORS]
        if targets:
            box = min(targets, key=lambda b: b.serial)
            L = self.layout
            x, y, z = pool.pos(box)
            stages["reach"] = 0.25 * (1 - np.tanh(10 * np.linalg.norm(pad_pos - (x, y, z + L.box_size / 2))))
            if held == box.index:
                bx, by = L.bin_center(BIN_COLORS.index(box.color))
                stages["seal"] = 0.5
                stages["carry"] = 0.5 + 0.25 * (1 - np.tanh(5 * np.hypot(x - bx, y - by)))
            if self.bin_under(x, y) == box.color:
                stages["place"] = 1.0
        return {**{k: float(v) for k, v in stages.items()}, "progress": float(max(stages.values()))}
