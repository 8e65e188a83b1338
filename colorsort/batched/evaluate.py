"""Evaluate a policy on the batched cell: ``envs`` episodes at once, the policy on the cell's device.

A world's episode ends as the CPU cell's does (``ColorSortGymEnv``: the variant's boxes have left play,
or one was misplaced or dropped, or the step limit). Two ways to fill the worlds:

- rolling (``run_rolling``), for policies whose only state is a queue of actions refilled for every world
  at once (LeRobot's ACT, and Diffusion Policy on one observation): a world whose episode ended starts the
  next seed at the queue's next refill, while the others run on, so a slow episode holds up no other;
- waves (``run_waves``), as LeRobot's ``lerobot-eval`` runs a vector env, for any other policy and for
  filmed evaluations: ``envs`` worlds start together, the policy is reset once per wave, and a world whose
  episode ended runs on until its wave ends, nothing after its end counting.

Each episode's result is the dict ``benchmark.evaluate.EpisodeRunner.episode`` writes, so reports and JSON
are the same as the CPU cell's. A seed's episode is the same whichever world runs it, and when, up to the last
bits of float32: a policy's batch of another size rounds differently, so a box may settle a few steps apart.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from colorsort.batched.cell import BatchedCell, Record, check_device
from colorsort.batched.films import Filming, FilmViewer, WaveRecording
from colorsort.batched.kernels import OUTCOMES
from colorsort.batched.schedule import COLOR_NAMES
from colorsort.batched.spec import CellSpec, spec_for_variant
from colorsort.benchmark.episode_result import EpisodeResult, box_record
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.policies import check_policy_spec, checkpoint_cameras
from colorsort.benchmark.report_page import choose_films
from colorsort.cell.referee import BoxEvent, Outcome
from colorsort.config import BIN_COLORS
from colorsort.errors import ConfigError
from colorsort.variants import Variant, get_variant


@dataclass(frozen=True)
class WaveTiming:
    """How long a batched evaluation took [s], and how many control steps of all worlds it ran."""

    seconds: float
    control_steps: int
    worlds: int


class BatchedPolicy:
    """A LeRobot checkpoint acting on every world at once, on a torch device; or ``random``."""

    def __init__(self, spec: str, device: str, low: np.ndarray, high: np.ndarray):
        import torch

        check_policy_spec(spec)
        self.name = spec
        self.device = torch.device(device)
        self.low = torch.as_tensor(low, dtype=torch.float32, device=self.device)
        self.high = torch.as_tensor(high, dtype=torch.float32, device=self.device)
        self.policy = None
        if spec == "expert":
            raise ConfigError("the expert reads the sensor camera and plans on the host: evaluate it with "
                              "--backend cpu; the warp backend runs 'random' and LeRobot checkpoints")
        self.cameras: tuple[str, ...] = ()
        self.image_size: tuple[int, int] | None = None
        self.restart_period: int | None = 1
        if spec != "random":
            self.cameras, self.image_size = checkpoint_cameras(spec)
            from colorsort.benchmark.policies import LeRobotPolicy

            loaded = LeRobotPolicy(spec, device=str(self.device))
            self.policy = loaded.policy
            self.preprocessor, self.postprocessor = loaded.preprocessor, loaded.postprocessor
            self.restart_period = restart_period(self.policy.config)

    def reset(self, seed: int) -> None:
        import torch

        self.generator = torch.Generator(device=self.device).manual_seed(seed)
        torch.manual_seed(seed)
        if self.policy is not None:
            self.policy.reset()

    def act(self, step, task: str):
        """Actions (N, action size) for a ``BatchedCell`` step's observations."""
        import torch

        n = step.state.shape[0]
        if self.policy is None:
            u = torch.rand((n, len(self.low)), generator=self.generator, device=self.device)
            return self.low + u * (self.high - self.low)
        batch = {"observation.state": step.state.to(self.device),
                 "observation.environment_state": step.env_state.to(self.device), "task": [task] * n}
        for camera, image in step.images.items():  # as LeRobot's preprocess_observation: (N, 3, H, W) in [0, 1]
            batch[f"observation.images.{camera}"] = image.to(self.device).permute(0, 3, 1, 2).float() / 255.0
        with torch.no_grad():
            return self.postprocessor(self.policy.select_action(self.preprocessor(batch)))


def restart_period(config) -> int | None:
    """Control steps between the points where a LeRobot policy holds no state of any world, or None.

    ACT without temporal ensembling, and Diffusion Policy on one observation, keep nothing between
    steps but their queue of actions, filled for every world at once and emptied every ``n_action_steps``
    steps. At each such point a world may start a new episode and the policy acts on it as on a fresh
    episode (``run_rolling``). Any other state (an ensemble of chunks, a queue of observations) gives None.
    """
    steps = getattr(config, "n_action_steps", None)
    if steps is None or getattr(config, "temporal_ensemble_coeff", None) is not None:
        return None
    return int(steps) if getattr(config, "n_obs_steps", 1) == 1 else None


def tally(n_events: np.ndarray, outcome: np.ndarray, boxes: int) -> dict[str, np.ndarray]:
    """Each world's counts over the first ``boxes`` boxes that left play (``referee.judge`` and
    ``ColorSortGymEnv``'s ``info``): done, success, failed, and a count per ``Outcome``, a row per world."""
    counted = np.arange(boxes)[None] < np.minimum(n_events, boxes)[:, None]
    count = {o: ((outcome[:, :boxes] == OUTCOMES.index(o)) & counted).sum(1) for o in Outcome}
    failed = count[Outcome.MISPLACED] + count[Outcome.DROPPED] > 0
    done = n_events >= boxes
    return {"done": done, "success": done & ~failed, "failed": failed, **{o.value: c for o, c in count.items()}}


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


def run_waves(cell: BatchedCell, policy: BatchedPolicy, variant: Variant, seeds: list[int], max_steps: int,
              progress: bool = True, filming: Filming | None = None) -> tuple[list[EpisodeResult], WaveTiming]:
    """Every seed's episode, in waves of ``cell.worlds``; results in seed order. With ``filming``, each wave is
    recorded and the episodes its report may film kept (``films.py``)."""
    n = cell.worlds
    task = f"Sort the next {variant.boxes} boxes from the conveyor into the bins of their colours."
    results: list[EpisodeResult] = []
    bar = tqdm(total=len(seeds), desc=f"{policy.name} on {variant.name} (warp)", unit="episode", disable=not progress)
    start, control_steps = time.perf_counter(), 0
    for first in range(0, len(seeds), n):
        wave = seeds[first : first + n]
        padded = wave + [wave[-1]] * (n - len(wave))  # idle worlds repeat a seed; their results are dropped
        out = cell.reset(padded)
        recording = WaveRecording(cell) if filming is not None else None
        if recording is not None:
            recording.add()
        policy.reset(int(wave[0]))
        ended = np.zeros(n, bool)
        ended[len(wave):] = True
        finished: dict[int, EpisodeResult] = {}
        for step in range(1, max_steps + 1):
            out = cell.step(policy.act(out, task))
            control_steps += 1
            if recording is not None:
                recording.add()
            counts = tally(cell.n_events.numpy(), cell.ev_outcome.numpy(), variant.boxes)
            stop = counts["done"] | counts["failed"] | (step >= max_steps)
            new = np.flatnonzero(stop & ~ended)
            if len(new):
                record = cell.record()  # one copy to the host for every world that ended now
                for w in new:
                    finished[int(w)] = episode_result(record, int(w), variant, step, step * cell.control_dt)
                bar.update(len(new))
            ended |= stop
            if ended.all():
                break
        wave_results = [finished[w] for w in range(len(wave))]
        if filming is not None and recording is not None:
            filming.wave_ended(recording, wave_results)
        results += wave_results
    bar.close()
    return results, WaveTiming(time.perf_counter() - start, control_steps, n)


def run_rolling(cell: BatchedCell, policy: BatchedPolicy, variant: Variant, seeds: list[int], max_steps: int,
                period: int, progress: bool = True) -> tuple[list[EpisodeResult], WaveTiming]:
    """Every seed's episode, ``cell.worlds`` at a time; a world whose episode ended starts the next seed at the
    policy's next restart point (every ``period`` control steps, ``restart_period``) while the others run on.
    Results in seed order, each as the episode would be on its own: it starts at a restart point, where the
    policy holds nothing of that world."""
    n = cell.worlds
    task = f"Sort the next {variant.boxes} boxes from the conveyor into the bins of their colours."
    first = seeds[:n]
    out = cell.reset(first + [first[-1]] * (n - len(first)))  # idle worlds repeat a seed; never counted
    policy.reset(int(seeds[0]))
    episode = np.arange(n)  # each world's index into seeds
    start = np.zeros(n, int)  # the control step its episode began at
    active = episode < len(first)
    upcoming = len(first)
    results: dict[int, EpisodeResult] = {}
    bar = tqdm(total=len(seeds), desc=f"{policy.name} on {variant.name} (warp)", unit="episode", disable=not progress)
    begin, t = time.perf_counter(), 0
    while active.any() or upcoming < len(seeds):
        if t % period == 0 and upcoming < len(seeds) and not active.all():
            free = np.flatnonzero(~active)[: len(seeds) - upcoming]
            out = cell.reset(seeds[upcoming : upcoming + len(free)], worlds=free)
            episode[free] = np.arange(upcoming, upcoming + len(free))
            start[free], active[free] = t, True
            upcoming += len(free)
        out = cell.step(policy.act(out, task))
        t += 1
        steps = t - start
        counts = tally(cell.n_events.numpy(), cell.ev_outcome.numpy(), variant.boxes)
        ended = np.flatnonzero(active & (counts["done"] | counts["failed"] | (steps >= max_steps)))
        if len(ended):
            record = cell.record()  # one copy to the host for every world that ended now
            for w in ended:
                results[int(episode[w])] = episode_result(record, int(w), variant, int(steps[w]),
                                                          steps[w] * cell.control_dt)
            active[ended] = False
            bar.update(len(ended))
    bar.close()
    return [results[k] for k in range(len(seeds))], WaveTiming(time.perf_counter() - begin, t, n)


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
    filming = Filming(FilmViewer(spec, variant), videos) if film else None
    if filming is None and policy.restart_period is not None:
        results, timing = run_rolling(cell, policy, variant, seeds, max_steps, policy.restart_period, progress)
    else:  # films keep whole waves of states; a policy with other state runs whole waves
        results, timing = run_waves(cell, policy, variant, seeds, max_steps, progress, filming)
    report = aggregate(str(policy_spec), variant.name, results)
    films: dict[int, bytes] = {}
    if filming is not None:
        kept = choose_films([report], {(variant.name, s): s for s in filming.tracks}, videos)
        films = filming.films([s for _, s in kept])
        filming.viewer.close()
    return BatchedEvaluation(report, timing, films)
