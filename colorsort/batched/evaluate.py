"""Evaluate a policy on the batched cell: ``envs`` episodes at once, the policy on the cell's device.

A world's episode ends as the CPU cell's does (``ColorSortGymEnv``: the variant's boxes have left play,
or one was misplaced or dropped, or the step limit). The evaluator is the one the CPU cells use
(``benchmark/lockstep.py``: rolling or waves, one ``BatchedPolicy``); ``WarpCells`` is the batched cell as its
``Cells``, ``WaveFilms`` the films of its waves.

Each episode's result is the ``EpisodeResult`` the CPU cell's evaluator writes, so reports and JSON are the same as
the CPU cell's. A seed's episode is the same whichever world runs it, and when, up to the last bits of float32: a
policy's batch of another size rounds differently, so a box may settle a few steps apart.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from colorsort.batched.cell import BatchedCell, Record, StepResult, check_device
from colorsort.batched.films import Filming, FilmViewer, WaveRecording
from colorsort.batched.kernels import OUTCOMES
from colorsort.batched.schedule import COLOR_NAMES
from colorsort.batched.spec import CellSpec, spec_for_variant
from colorsort.benchmark.episode_result import EpisodeResult, box_record
from colorsort.benchmark.lockstep import BatchedPolicy, EpisodePlan, WaveTiming, run_rolling, run_waves
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.report_page import choose_films
from colorsort.cell.referee import BoxEvent, Outcome, episode_rule
from colorsort.config import BIN_COLORS
from colorsort.errors import ConfigError
from colorsort.variants import Variant, get_variant


def tally(n_events: np.ndarray, outcome: np.ndarray, boxes: int) -> dict[str, np.ndarray]:
    """Each world's counts over the first ``boxes`` boxes that left play (``referee.judge`` and
    ``ColorSortGymEnv``'s ``info``): done, success, failed, and a count per ``Outcome``, a row per world."""
    counted = np.arange(boxes)[None] < np.minimum(n_events, boxes)[:, None]
    count = {o: ((outcome[:, :boxes] == OUTCOMES.index(o)) & counted).sum(1) for o in Outcome}
    failed = count[Outcome.MISPLACED] + count[Outcome.DROPPED] > 0
    done = n_events >= boxes
    success, terminated = episode_rule(done, failed)
    return {"done": done, "success": success, "failed": failed, "terminated": terminated,
            **{o.value: c for o, c in count.items()}}


def episode_result(record: Record, world: int, variant: Variant, steps: int, sim_time: float) -> EpisodeResult:
    """World ``world``'s episode, judged as the CPU cell's (``EpisodeResult.judged``)."""
    grips, offsets, yaws = record.grips[world], record.offset[world], record.yaw[world]
    events, boxes = [], []
    for t, serial, color, outcome, b in record.events(world):
        event = BoxEvent(t, serial, COLOR_NAMES[color], OUTCOMES[outcome], BIN_COLORS[b] if b >= 0 else None)
        grip = grips[serial] if serial < len(grips) else (math.nan, math.nan)
        events.append(event)
        boxes.append(box_record(event, float(offsets[serial]), float(np.rad2deg(yaws[serial])),
                                None if math.isnan(grip[0]) else float(grip[0]),
                                None if math.isnan(grip[1]) else float(grip[1])))
    return EpisodeResult.judged(int(record.seeds[world]), steps, sim_time, events, variant.boxes, boxes)


class WarpCells:
    """The batched cell as ``lockstep.Cells``: every world stepped each step, the ended ones uncounted."""

    def __init__(self, cell: BatchedCell, variant: Variant):
        self.cell, self.variant, self.worlds = cell, variant, cell.worlds

    def reset(self, episodes: Sequence[EpisodePlan], worlds: np.ndarray) -> StepResult:
        if any(e.shift for e in episodes):
            raise ConfigError("the batched cell (MuJoCo Warp) applies no held-out shift yet")
        seeds = [e.seed for e in episodes]
        whole = len(worlds) == self.worlds and bool((np.asarray(worlds) == np.arange(self.worlds)).all())
        return self.cell.reset(seeds) if whole else self.cell.reset(seeds, worlds=np.asarray(worlds))

    def step(self, actions: Any, active: np.ndarray) -> StepResult:
        return self.cell.step(actions)

    def ended(self) -> np.ndarray:
        return tally(self.cell.n_events.numpy(), self.cell.ev_outcome.numpy(), self.variant.boxes)["terminated"]

    def results(self, worlds: np.ndarray, steps: np.ndarray) -> list[EpisodeResult]:
        if not len(worlds):
            return []
        record = self.cell.record()  # one copy to the host for every world that ended now
        return [episode_result(record, int(w), self.variant, int(n), float(n) * self.cell.control_dt)
                for w, n in zip(worlds, steps, strict=True)]


class WaveFilms:
    """``lockstep.WaveFilm`` over ``films.Filming``: each wave recorded on the device, its kept episodes drawn."""

    def __init__(self, filming: Filming, cell: BatchedCell):
        self.filming, self.cell = filming, cell
        self.recording: WaveRecording | None = None

    def start(self) -> None:
        self.recording = WaveRecording(self.cell)

    def add(self) -> None:
        assert self.recording is not None
        self.recording.add()

    def end(self, results: list[EpisodeResult]) -> None:
        assert self.recording is not None
        self.filming.wave_ended(self.recording, results)


@dataclass(frozen=True)
class BatchedEvaluation:
    """A batched evaluation's report (``metrics.aggregate``'s, as the CPU cell's), its timing, and the films of
    the episodes its report keeps (seed -> mp4 bytes; empty unless filmed)."""

    report: EvalReport
    timing: WaveTiming
    films: dict[int, bytes]


def evaluate_batched(policy_spec: str, variant_name: str, episodes: int, *, seed: int | None = None,
                     envs: int = 1024, device: str = "cuda:0", episode_length: int | None = None,
                     progress: bool = True, spec: CellSpec | None = None, film: bool = False,
                     videos: int | None = None) -> BatchedEvaluation:
    """``episodes`` episodes of a policy on one variant, ``envs`` worlds at once on Warp's ``device``
    ("cpu" or "cuda:0"); the report is ``metrics.aggregate``'s, as for the CPU cell. ``spec`` saves
    building the variant's cell with robosuite (``CellSpec.load``). With ``film``, the episodes a report keeps
    (``report_page.choose_films`` with ``videos``) are filmed as the CPU cell films them."""
    from colorsort.benchmark.evaluate import episode_seeds

    if envs < 1:
        raise ConfigError(f"envs={envs}: give at least 1")
    check_device(device)  # before the policy is moved there
    variant = get_variant(variant_name)
    seeds = episode_seeds(variant, episodes, seed)
    spec = spec or spec_for_variant(variant.name)
    policy = BatchedPolicy(policy_spec if policy_spec in ("expert", "random") else str(Path(policy_spec).resolve()),
                           device, spec.action_low, spec.action_high)
    max_steps = episode_length or int(np.ceil(variant.time_limit * spec.control_freq))
    spawns = int(np.ceil(max_steps / spec.control_freq / variant.task_config.spawn_period)) + 2
    cell = BatchedCell(spec, variant, min(envs, len(seeds)), device=device, max_boxes=max(variant.boxes + 2, spawns),
                       cameras=policy.cameras, image_size=policy.image_size or (64, 64))
    cells, runs = WarpCells(cell, variant), [EpisodePlan(s) for s in seeds]
    filming = Filming(FilmViewer(spec, variant), videos) if film else None
    task, desc = f"Sort the next {variant.boxes} boxes from the conveyor into the bins of their colours.", \
        f"{policy.name} on {variant.name} (warp)"
    if filming is None and policy.restart_period is not None:
        found, timing = run_rolling(cells, policy, runs, max_steps, policy.restart_period, task, progress,
                                    desc=desc)
    else:  # films keep whole waves of states; a policy with other state runs whole waves
        found, timing = run_waves(cells, policy, runs, max_steps, task, progress,
                                  WaveFilms(filming, cell) if filming is not None else None, desc=desc)
    results = [r for r in found if r is not None]
    report = aggregate(str(policy_spec), variant.name, results)
    films: dict[int, bytes] = {}
    if filming is not None:
        kept = choose_films([report], {(variant.name, s): s for s in filming.tracks}, videos)
        films = filming.films([s for _, s in kept])
        filming.viewer.close()
    return BatchedEvaluation(report, timing, films)
