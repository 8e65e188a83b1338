"""Evaluate a policy on benchmark variants: episodes by seed, in jobs spread over an executor.

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``seed + k``), so the same call
gives the same numbers whatever the executor (local processes or Ray), its workers or the job
size. Each job builds one env and one policy and runs at most ``shard_size`` episodes. The
metrics are ``metrics.py``'s; the command line is ``colorsort-eval`` (``cli/eval.py``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from colorsort.benchmark.episode_result import EpisodeResult, box_record
from colorsort.benchmark.filming import EpisodeFilm
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.policies import check_policy_spec, checkpoint_cameras, make_policy
from colorsort.cell.cameras import CAMERAS, DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE, parse_cameras
from colorsort.cell.plant import Grip
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.envs.rollout import GymEpisode, Observer, rollout
from colorsort.errors import ConfigError, StageError
from colorsort.executors.base import (
    DEFAULT_SHARD_SIZE,
    ExecutorConfig,
    Task,
    TaskContext,
    chunks,
    forwarded_env,
)
from colorsort.executors.factory import make_executor
from colorsort.shifts import parse_shifts, shift_label
from colorsort.variants import SHIFT_SEEDS, Variant, get_variant


def episode_seeds(variant: Variant, episodes: int, seed: int | None, shifted: bool = False) -> list[int]:
    """Episode k's seed: ``seed + k``, else the variant's k-th evaluation seed, or with ``shifted`` (held-out
    shifts and their control arm) the k-th of ``SHIFT_SEEDS``, which no training, validation or evaluation uses."""
    if seed is not None:
        return [seed + k for k in range(episodes)]
    seeds, kind = (SHIFT_SEEDS, "shift evaluation") if shifted else (variant.seeds, "evaluation")
    if episodes > len(seeds):
        raise ConfigError(f"variant {variant.name!r} has {len(seeds)} {kind} seeds; "
                         f"for {episodes} episodes pass --seed S (seeds S..S+{episodes - 1})")
    return list(seeds[:episodes])


@dataclass(frozen=True)
class EvalConfig:
    """What every evaluation episode shares; each worker process builds its env and policy from it."""

    policy: str
    variant: str
    image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE  # (height, width) [px]
    cameras: tuple[str, ...] = DEFAULT_CAMERAS
    episode_length: int | None = None  # steps before truncation; None: the variant's time limit
    film: bool = False  # film every episode (``filming.py``): its mp4 bytes in its result's ``video``
    shift: tuple[str, ...] = ()  # held-out shifts, ``NAME:LEVEL`` (``colorsort.shifts``); the env applies them


# torch threads of a learned policy in each env's process: with torch's default (one per core) envs
# sharing the cores fight over them, and the count changes a policy's floating-point results
POLICY_THREADS = 1


class EpisodeRunner:
    """One env and one policy, built once per process, running episodes by seed."""

    def __init__(self, settings: EvalConfig):
        self.threads_before: int | None = None
        if settings.policy not in ("expert", "random"):
            import torch

            self.threads_before = torch.get_num_threads()
            torch.set_num_threads(POLICY_THREADS)
        self.policy = make_policy(settings.policy)
        self.film = settings.film
        self.env = ColorSortGymEnv(get_variant(settings.variant), cameras=settings.cameras,
                                   image_size=settings.image_size, episode_length=settings.episode_length,
                                   render_mode="rgb_array" if settings.film else None,  # a GL context to film with
                                   shift=settings.shift)

    def close(self) -> None:
        """Close the env; give this process back the torch threads it had (it may be the caller's)."""
        self.env.close()
        if self.threads_before is not None:
            import torch

            torch.set_num_threads(self.threads_before)

    def episode(self, seed: int) -> EpisodeResult:
        """Run the episode of ``seed``: its figures, how it ended, each box's outcome (and its film)."""
        obs, _ = self.env.reset(seed=seed)
        self.policy.reset(self.env, seed)
        film = EpisodeFilm(self.env) if self.film else None
        observers = [Filming(film, self.policy)] if film is not None else []
        try:
            info = rollout(GymEpisode(self.env), obs, self.policy.act, observers).info
        except BaseException:
            if film is not None:
                film.discard()
            raise
        env = self.env.env
        placed = {p.serial: p for p in env.placements}
        gripped = {g.serial: g for g in env.grips}  # a box sealed twice: the last seal
        boxes = [box_record(e, placed[e.serial].offset, placed[e.serial].yaw, *grip_fields(gripped.get(e.serial)))
                 for e in env.events[: self.env.variant.boxes]]
        result = EpisodeResult.judged(seed, self.env.steps, info["sim_time"], env.events, self.env.variant.boxes,
                                      boxes, env.shifts.record)  # each shift's level and its draws this episode
        if film is not None:
            result.video = film.finish()
        return result


class Filming(Observer):
    """Films an episode: its reset, then every step, with the policy's phase where it has one."""

    def __init__(self, film: EpisodeFilm, policy: Any):
        self.film, self.policy = film, policy

    def on_start(self, obs: Any) -> None:
        self.film.add(getattr(self.policy, "phase", None))

    def on_step(self, obs: Any, info: dict) -> None:
        self.film.add(getattr(self.policy, "phase", None))


def grip_fields(grip: Grip | None) -> tuple[float | None, float | None]:
    """How the cup held a box: ``grip.offset`` [m] off the cup's axis and ``grip.yaw`` [deg] against the cup
    (None, None for a box never sealed)."""
    return (None, None) if grip is None else (grip.offset, grip.yaw)


PRELOAD = ("colorsort.benchmark.evaluate",)  # what worker processes import once, before they fork


@dataclass(frozen=True)
class EvalJob:
    """Episodes of one variant, by seed: one task of the executor."""

    settings: EvalConfig
    seeds: tuple[int, ...]


class _Stopped(Exception):
    """The evaluation was asked to stop."""


def run_job(job: EvalJob, ctx: TaskContext) -> list[EpisodeResult]:
    """The task: one env and one policy, the job's episodes in seed order; one message per episode."""
    runner = EpisodeRunner(job.settings)
    results = []
    try:
        for seed in job.seeds:
            if ctx.stopping():
                raise _Stopped(f"stopped before seed {seed}")
            results.append(runner.episode(seed))
            ctx.send(job.settings.variant)
    finally:
        runner.close()
    return results


def run_episodes(jobs: list[EvalJob], executor: ExecutorConfig = ExecutorConfig(), progress: bool = True,
                 desc: str = "evaluating") -> tuple[list[list[EpisodeResult]], int]:
    """Run every job on ``executor``; returns each job's episode results (in seed order) and how many
    jobs ran again because their process died.

    Episodes are independent (each starts from its seed), so the results are the same whatever the
    executor, its workers or the way seeds are split into jobs.

    Raises:
        RuntimeError: a job failed (its traceback), or the run was interrupted.
    """
    tasks = [(f"{j.settings.variant}:{shift_label(parse_shifts(j.settings.shift))}:{j.seeds[0]}", run_job, j)
             for j in jobs]
    results = run_jobs(tasks, sum(len(j.seeds) for j in jobs), executor, progress, desc, with_attempts=True)
    return [r.value for r in results], sum(r.attempts > 1 for r in results)


def run_jobs(tasks: list[tuple[str, Callable, Any]], episodes: int, executor: ExecutorConfig, progress: bool,
             desc: str, with_attempts: bool = False, on_message: Callable[[Any], None] | None = None) -> list:
    """Run ``(key, function, job)`` tasks on ``executor`` with a progress bar of ``episodes`` (each task sends one
    message an episode, which ``on_message`` is also given as it arrives); each task's value in order (its
    ``TaskResult`` with ``with_attempts``).

    Raises:
        RuntimeError: a task failed (its traceback), or the run was interrupted.
    """
    bar = tqdm(total=episodes, desc=desc, unit="episode", disable=not progress)
    try:
        def message(m: Any) -> None:
            bar.update()
            if on_message is not None:
                on_message(m)

        results = make_executor(executor, PRELOAD, forwarded_env()).run([Task(*t) for t in tasks], message)
    finally:
        bar.close()
    failed = [r for r in results if not r.ok]
    if failed:
        raise StageError("evaluation stopped: " + "; ".join(r.error or f"{r.key} was stopped" for r in failed))
    return results if with_attempts else [r.value for r in results]


@dataclass(frozen=True)
class Evaluation:
    """The reports of an evaluation, one per variant in order, and the films of its episodes."""

    reports: list[EvalReport]
    films: dict[tuple[str, int], bytes]  # (variant, seed) -> H.264 mp4; empty unless filmed


def run_evaluation(policy_spec: str, variant_names: list[str], episodes: int, *, seed: int | None = None,
                   image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE, cameras: tuple[str, ...] = DEFAULT_CAMERAS,
                   progress: bool = True, episode_length: int | None = None,
                   executor: ExecutorConfig = ExecutorConfig(), shard_size: int = DEFAULT_SHARD_SIZE,
                   film: bool = False, shift: tuple[str, ...] = ()) -> Evaluation:
    """``episodes`` episodes of a policy on each variant, all spread over ``executor`` in jobs of at most
    ``shard_size`` episodes; with ``film``, every episode is filmed in the process that runs it; with ``shift``
    (``NAME:LEVEL`` texts), under those held-out shifts, on ``SHIFT_SEEDS`` unless ``seed`` is given."""
    check_policy_spec(policy_spec)
    shift = tuple(str(s) for s in parse_shifts(shift))
    variants = [get_variant(name) for name in variant_names]
    path = policy_spec if policy_spec in ("expert", "random") else str(Path(policy_spec).resolve())  # for any worker
    jobs, owner = [], []
    per_variant = max(1, executor.workers // len(variants))  # jobs per variant that keep every worker busy
    for k, variant in enumerate(variants):
        settings = EvalConfig(path, variant.name, (image_size[0], image_size[1]), tuple(cameras), episode_length,
                                film, shift)
        for block in chunks(episode_seeds(variant, episodes, seed, bool(shift)), shard_size, per_variant):
            jobs.append(EvalJob(settings, tuple(block)))
            owner.append(k)
    results, _ = run_episodes(jobs, executor, progress, desc=f"{policy_spec} on {', '.join(variant_names)}")
    films = {(job.settings.variant, r.seed): r.video for job, rs in zip(jobs, results, strict=True)
             for r in rs if r.video is not None}
    per = [[r for job, rs in zip(owner, results, strict=True) if job == k for r in rs] for k in range(len(variants))]
    label = shift_label(parse_shifts(shift))
    reports = [aggregate(str(policy_spec), v.name, rs, label) for v, rs in zip(variants, per, strict=True)]
    return Evaluation(reports, films)


def evaluate_variants(policy_spec: str, variant_names: list[str], episodes: int, *, seed: int | None = None,
                      image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE, cameras: tuple[str, ...] = DEFAULT_CAMERAS,
                      progress: bool = True, episode_length: int | None = None,
                      executor: ExecutorConfig = ExecutorConfig(),
                      shard_size: int = DEFAULT_SHARD_SIZE) -> list[EvalReport]:
    """``run_evaluation``'s reports, one per variant, in order (no films)."""
    return run_evaluation(policy_spec, variant_names, episodes, seed=seed, image_size=image_size, cameras=cameras,
                          progress=progress, episode_length=episode_length, executor=executor,
                          shard_size=shard_size).reports


def evaluate(policy_spec: str, variant_name: str, episodes: int, *, seed: int | None = None,
             image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE, cameras: tuple[str, ...] = DEFAULT_CAMERAS,
             progress: bool = True, episode_length: int | None = None, envs: int = 1,
             executor: ExecutorConfig | None = None, shard_size: int = DEFAULT_SHARD_SIZE) -> EvalReport:
    """``episodes`` episodes of a policy on one variant, on ``envs`` local processes (or ``executor``)."""
    if envs < 1:
        raise ConfigError(f"envs={envs}: give at least 1")
    return evaluate_variants(policy_spec, [variant_name], episodes, seed=seed, image_size=image_size, cameras=cameras,
                             progress=progress, episode_length=episode_length,
                             executor=executor or ExecutorConfig(workers=envs), shard_size=shard_size)[0]


def observation_settings(policy_spec: str, cameras: str | None,
                         image_size: int | None) -> tuple[tuple[str, ...], tuple[int, int]]:
    """The cameras and (height, width) [px] to render for a policy: as given, else as a checkpoint was
    trained (its ``config.json``), else scene and wrist at 128 px.

    Raises:
        ValueError: an unknown policy, or cameras/size other than those the checkpoint takes.
    """
    check_policy_spec(policy_spec)
    given = parse_cameras(cameras) if cameras is not None else None
    size = (image_size, image_size) if image_size is not None else None
    if policy_spec == "expert" and given == ():
        raise ConfigError("the expert reads the sensor camera, which --cameras none leaves unrendered: give "
                          f"cameras (any of {list(CAMERAS)}), or leave --cameras out")
    if policy_spec in ("expert", "random"):
        return (given if given is not None else DEFAULT_CAMERAS), size or DEFAULT_IMAGE_SIZE
    trained, trained_size = checkpoint_cameras(policy_spec)
    if given is not None and set(given) != set(trained):
        raise ConfigError(f"{policy_spec} was trained on cameras {list(trained) or 'none'}; got --cameras {cameras}")
    if size is not None and trained_size is not None and size != trained_size:
        raise ConfigError(f"{policy_spec} was trained on {trained_size[0]}x{trained_size[1]} images; "
                         f"got --image-size {image_size}")
    return trained, trained_size or size or DEFAULT_IMAGE_SIZE
