"""One evaluated episode, typed: what the CPU cell's evaluator (``evaluate.EpisodeRunner``) and the batched one
(``batched/evaluate.py``) both return, judged by one rule, and written as the JSON ``--json``, the printout and
the report page read (``metrics.aggregate``: ``EvalReport.per_episode``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from typing import Any

from colorsort.cell.referee import BoxEvent, EpisodeTally, Outcome


def box_record(event: BoxEvent, offset: float, yaw_deg: float, grip_offset: float | None,
               grip_yaw: float | None) -> dict[str, Any]:
    """One box of an episode as ``--json`` holds it: when and how it left play, where the spawner set it down
    (``offset`` [m] off the centre line, turned ``yaw_deg``), and how the cup held it (None: never sealed)."""
    return {"time": event.time, "color": event.color, "outcome": event.outcome.value, "bin": event.bin,
            "offset": round(offset, 4), "yaw": round(yaw_deg, 2),
            "grip_offset": None if grip_offset is None else round(grip_offset, 4),
            "grip_yaw": None if grip_yaw is None else round(grip_yaw, 2)}


@dataclass
class EpisodeResult:
    """An episode's outcome: the figures of its first ``boxes`` boxes (counts, times) and how it ended.

    Attributes:
        ended: "success" (every box where it belongs), "failed" (a box misplaced or dropped), or "time limit".
        sim_time: [s] of sim time when it ended.
        sorted_times: [s] when each box handled right left play (cycle times; not in the JSON).
        boxes: each box, ``box_record``'s.
        shift: each held-out shift's level and the values drawn for this episode (none: unshifted).
        video: the episode's film as mp4 bytes, when it was filmed (not in the JSON).
    """

    seed: int
    success: bool
    ended: str
    steps: int
    correct: int
    misplaced: int
    dropped: int
    let_through: int
    distractors: int
    sim_time: float
    sorted_times: list[float]
    boxes: list[dict[str, Any]]
    shift: dict[str, Any] = field(default_factory=dict)
    video: bytes | None = None

    @classmethod
    def judged(cls, seed: int, steps: int, sim_time: float, events: Sequence[BoxEvent], expected: int,
               boxes: list[dict[str, Any]], shift: dict[str, Any] | None = None) -> EpisodeResult:
        """The result of an episode whose first ``expected`` boxes count (``referee.judge``), ``events`` the
        boxes that left play in order and ``boxes`` their records."""
        tally = EpisodeTally.of(events, expected)
        verdict, count = tally.verdict, tally.counts
        return cls(seed=seed, success=verdict.success,
                   ended="success" if verdict.success else "failed" if verdict.failed else "time limit",
                   steps=steps, correct=count[Outcome.PLACED], misplaced=count[Outcome.MISPLACED],
                   dropped=count[Outcome.DROPPED], let_through=count[Outcome.REJECTED],
                   distractors=tally.distractors, sim_time=sim_time, sorted_times=tally.sorted_times,
                   boxes=boxes[:expected], shift=dict(shift or {}))

    def to_json(self) -> dict[str, Any]:
        """The episode as ``EvalReport.per_episode`` holds it: every figure and box, its shift if it had one."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("sorted_times", "shift", "video")}
        if self.shift:
            out["shift"] = self.shift
        return out
