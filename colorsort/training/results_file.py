"""The pipeline's results as typed records, and their JSON (``results.json``, a shipped ``scores.json``).

- ``ScoreRow``: one training run's policy scored on one variant: the run (demos, frames, seed, updates, minutes),
  colorsort-eval's ``EvalReport``, and where validation seeds chose the checkpoint, the choice and its points.
- ``ValidationPoint``: one checkpoint on the validation seeds of every training variant.
- ``CurvePoint``: one checkpoint on the main variant's first evaluation seeds (the learning curve).
- ``Sitting``: a later run that added training seeds to a shipped baseline (``colorsort-baseline --add-to``), or
  ran seeds it held again to keep their policies.
- ``PipelineResults``: a run of the pipeline: the recipe (as JSON), the command, when, how long, its rows and curve, and
  the sittings that added seeds to it or kept their policies.

Each record's ``to_json`` writes the flat objects ``scores.json`` has always held, and ``from_json`` reads them,
those of baselines shipped before the records included.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

from colorsort.benchmark.metrics import EvalReport

REPORT_FIELDS = tuple(f.name for f in fields(EvalReport))


def report_from_json(data: dict) -> EvalReport:
    """colorsort-eval's ``--json`` report (or a row that holds its fields) as an ``EvalReport``."""
    found = {k: data[k] for k in REPORT_FIELDS if k in data}
    if "success_ci95" in found:
        found["success_ci95"] = tuple(found["success_ci95"])
    return EvalReport(**found)


@dataclass(frozen=True)
class ValidationPoint:
    """A checkpoint on validation seeds; counts summed over the training variants."""

    step: int  # [updates]
    minutes: float  # of training when it was saved
    episodes: int
    successes: int
    correct: int
    misplaced: int
    dropped: int
    success_by_variant: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict) -> ValidationPoint:
        return cls(**{f.name: data[f.name] for f in fields(cls) if f.name in data})


@dataclass(frozen=True)
class CurvePoint:
    """A checkpoint on the main variant's first ``episodes`` evaluation seeds."""

    step: int  # [updates]
    minutes: float  # of training when it was saved
    episodes: int
    successes: int
    success_rate: float
    success_ci95: tuple[float, float]
    correct: int
    misplaced: int
    dropped: int

    def to_json(self) -> dict:
        return {**asdict(self), "success_ci95": list(self.success_ci95)}

    @classmethod
    def from_json(cls, data: dict) -> CurvePoint:
        return cls(**{**{f.name: data[f.name] for f in fields(cls)}, "success_ci95": tuple(data["success_ci95"])})


@dataclass(frozen=True)
class ScoreRow:
    """One training run's policy scored on one variant."""

    demos_tried: int  # the demo count asked for
    demos: int  # the demos kept (every box handled right)
    frames: int
    seed: int  # lerobot-train's
    steps: int  # the run's updates
    passes: float | None  # over the frames
    train_minutes: float  # the run's training time
    report: EvalReport  # colorsort-eval's
    checkpoint: int | None = None  # the update validation seeds chose, where they chose
    validation: tuple[ValidationPoint, ...] = ()

    @property
    def variant(self) -> str:
        return self.report.variant

    @property
    def scored_minutes(self) -> float:
        """[min] of training behind the checkpoint scored: when the chosen one was saved, else the whole run."""
        if self.checkpoint is None:
            return self.train_minutes
        return next(p.minutes for p in self.validation if p.step == self.checkpoint)

    @property
    def scored_step(self) -> int:
        return self.steps if self.checkpoint is None else self.checkpoint

    def to_json(self) -> dict:
        out: dict[str, Any] = {"demos_tried": self.demos_tried, "demos": self.demos, "frames": self.frames,
                               "seed": self.seed, "steps": self.steps, "passes": self.passes,
                               "train_minutes": self.train_minutes,
                               **{**asdict(self.report), "success_ci95": list(self.report.success_ci95)}}
        if self.report.shift == "none":
            del out["shift"]  # a baseline is scored as built: its rows name no held-out shift
        if self.checkpoint is not None:
            out.update(checkpoint=self.checkpoint, validation=[p.to_json() for p in self.validation])
        return out

    @classmethod
    def from_json(cls, data: dict) -> ScoreRow:
        return cls(data["demos_tried"], data["demos"], data["frames"], data["seed"], data["steps"],
                   data.get("passes"), data["train_minutes"], report_from_json(data), data.get("checkpoint"),
                   tuple(ValidationPoint.from_json(p) for p in data.get("validation", ())))


@dataclass(frozen=True)
class Sitting:
    """A run of the pipeline on another machine or day that added training seeds to a shipped baseline, or ran
    seeds it held again, reproduced every episode they scored and kept their policies (``ship.add_seeds``)."""

    command: str
    commit: str  # the checkout's (``ship.commit``)
    started: str  # "2026-12-01 14:26 UTC"
    wall_s: float  # [s] the run's wall time
    seeds: tuple[int, ...]  # lerobot-train's seeds it added (or whose policies it kept)

    def named_seeds(self) -> str:
        """"seed 1000", "seeds 1000, 1002"."""
        return f"seed{'s' * (len(self.seeds) > 1)} {', '.join(map(str, self.seeds))}"

    def to_json(self) -> dict:
        return {**asdict(self), "seeds": list(self.seeds)}

    @classmethod
    def from_json(cls, data: dict) -> Sitting:
        return cls(data["command"], data["commit"], data["started"], data["wall_s"], tuple(data["seeds"]))


@dataclass(frozen=True)
class PipelineResults:
    """One run of the pipeline (``results.json``; shipped as ``scores.json``), with the sittings that added
    training seeds to it (``added``: their rows are in ``rows``; the curve stays the first seed's) and those that
    ran held seeds again to keep their policies (``kept``: the rows they reproduced were there already); ``replaced``:
    the earlier sittings, each with the seeds whose rows a later run replaced (their policies were not kept, and run
    again they scored otherwise)."""

    recipe: dict  # Recipe.to_json(), or a shipped baseline's flat recipe of before the sections
    command: str
    started: str  # "2026-11-27 10:00 UTC"
    wall_s: float
    rows: tuple[ScoreRow, ...]
    curve: tuple[CurvePoint, ...] = ()
    commit: str = ""  # the checkout's at shipping (``ship.commit``); "" in results.json
    added: tuple[Sitting, ...] = ()
    kept: tuple[Sitting, ...] = ()
    replaced: tuple[Sitting, ...] = ()

    @property
    def seeds(self) -> tuple[int, ...]:
        """lerobot-train's seeds of the rows, in the order they were run."""
        return tuple(dict.fromkeys(r.seed for r in self.rows))

    def to_json(self) -> dict:
        out = {"recipe": self.recipe, "command": self.command, "started": self.started, "wall_s": self.wall_s,
               "rows": [r.to_json() for r in self.rows], "curve": [p.to_json() for p in self.curve]}
        if self.commit:
            out["commit"] = self.commit
        if self.added:
            out["added"] = [s.to_json() for s in self.added]
        if self.kept:
            out["kept"] = [s.to_json() for s in self.kept]
        if self.replaced:
            out["replaced"] = [s.to_json() for s in self.replaced]
        return out

    @classmethod
    def from_json(cls, data: dict) -> PipelineResults:
        return cls(data["recipe"], data["command"], data["started"], data["wall_s"],
                   tuple(ScoreRow.from_json(r) for r in data["rows"]),
                   tuple(CurvePoint.from_json(p) for p in data.get("curve") or ()), data.get("commit", ""),
                   tuple(Sitting.from_json(s) for s in data.get("added", ())),
                   tuple(Sitting.from_json(s) for s in data.get("kept", ())),
                   tuple(Sitting.from_json(s) for s in data.get("replaced", ())))

    @classmethod
    def load(cls, path: Path) -> PipelineResults:
        return cls.from_json(json.loads(path.read_text()))
