"""Evaluate a policy on benchmark variants: episodes by seed, in jobs spread over an executor.

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``seed + k``), so the same call
gives the same numbers whatever the executor (local processes or Ray), its workers or the job
size. Each job runs at most ``shard_size`` episodes: on one env and one policy (``batch_size`` 1), or on
``batch_size`` cells stepped together with one policy forward a step (``lockstep.py``, ``cpu_cells.py``). Each
finished episode reaches the caller as it finishes (a journal keeps it: Ctrl-C loses none). The metrics are
``metrics.py``'s; the command line is ``colorsort-eval`` (``cli/eval.py``).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from colorsort.benchmark.cpu_cells import CpuCells, cpu_episode_result
from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.filming import EpisodeFilm
from colorsort.benchmark.lockstep import BatchedPolicy, EpisodePlan, run_rolling, run_waves
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.policies import check_policy_spec, checkpoint_cameras, make_policy
from colorsort.benchmark.sweep_journal import Key
from colorsort.cell.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE, parse_cameras
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.envs.rollout import GymEpisode, Observer, rollout
from colorsort.errors import ConfigError, Interrupted, StageError
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
    batch_size: int = 1  # cells a worker steps together, one policy forward over them a step (``lockstep.py``)
    precision: str = "float32"  # a learned policy's forward: float32, or bfloat16 under CPU autocast (batched)


# torch threads of a learned policy in each env's process: with torch's default (one per core) envs
# sharing the cores fight over them, and the count changes a policy's floating-point results
POLICY_THREADS = 1


def set_policy_threads(spec: str) -> int | None:
    """``POLICY_THREADS`` torch threads in this process while a learned policy runs here; the count it had before
    (None for the expert and ``random``, which leave torch alone), for ``restore_threads``."""
    if spec in ("expert", "random"):
        return None
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(POLICY_THREADS)
    return before


def restore_threads(before: int | None) -> None:
    """Give this process back the torch threads it had (it may be the caller's)."""
    if before is not None:
        import torch

        torch.set_num_threads(before)


def renders(settings: EvalConfig) -> bool:
    """Whether an episode's env needs a GL context beyond its policy's cameras: to film, or for the expert's own
    photos (``expert.calibration.sensor_source``)."""
    return settings.film or settings.policy == "expert"


class EpisodeRunner:
    """One env and one policy, built once per process, running episodes by seed (``--batch-size 1``)."""

    def __init__(self, settings: EvalConfig):
        self.threads_before = set_policy_threads(settings.policy)
        self.policy = make_policy(settings.policy)
        self.film = settings.film
        self.env = ColorSortGymEnv(get_variant(settings.variant), cameras=settings.cameras,
                                   image_size=settings.image_size, episode_length=settings.episode_length,
                                   render_mode="rgb_array" if renders(settings) else None, shift=settings.shift)

    def close(self) -> None:
        """Close the env; give this process back the torch threads it had (it may be the caller's)."""
        self.env.close()
        restore_threads(self.threads_before)

    def episode(self, seed: int) -> EpisodeResult:
        """Run the episode of ``seed``: its figures, how it ended, each box's outcome (and its film)."""
        obs, _ = self.env.reset(seed=seed)
        self.policy.reset(self.env, seed)
        film = EpisodeFilm(self.env) if self.film else None
        observers = [PhaseFilming(film, self.policy)] if film is not None else []
        try:
            info = rollout(GymEpisode(self.env), obs, self.policy.act, observers).info
        except BaseException:
            if film is not None:
                film.discard()
            raise
        result = cpu_episode_result(self.env, seed, self.env.steps, info["sim_time"])
        if film is not None:
            result.video = film.finish()
        return result


class PhaseFilming(Observer):
    """Films an episode: its reset, then every step, with the policy's phase where it has one."""

    def __init__(self, film: EpisodeFilm, policy: Any):
        self.film, self.policy = film, policy

    def on_start(self, obs: Any) -> None:
        self.film.add(getattr(self.policy, "phase", None))

    def on_step(self, obs: Any, info: dict) -> None:
        self.film.add(getattr(self.policy, "phase", None))


PRELOAD = ("colorsort.benchmark.evaluate",)  # what worker processes import once, before they fork


@dataclass(frozen=True)
class EvalJob:
    """Episodes of one variant, each its seed and shifts: one task of the executor."""

    settings: EvalConfig
    episodes: tuple[EpisodePlan, ...]

    @property
    def key(self) -> str:
        first = self.episodes[0]
        return f"{self.settings.variant}:{shift_label(parse_shifts(first.shift))}:{first.seed}"


Finished = tuple[str, tuple[str, ...], EpisodeResult]  # a job's message: the variant, the shifts, the result


def run_job(job: EvalJob, ctx: TaskContext) -> int:
    """The task: the job's episodes in order, each sent as it finishes (``Finished``: the caller keeps them as
    they arrive); on a stop (Ctrl-C) it starts no more. Returns how many it finished. ``batch_size`` 1: one env
    and one policy, an episode at a time; more: ``batch_size`` cells stepped together, one policy forward a step
    (``lockstep.py``)."""
    if job.settings.batch_size > 1 and job.settings.policy not in ("expert", "random"):
        return run_lockstep_job(job, ctx)
    runner = EpisodeRunner(job.settings)
    results = []
    try:
        for episode in job.episodes:
            if ctx.stopping():
                break
            if episode.shift != runner.env.shift:
                runner.env.set_shift(episode.shift)
            results.append(runner.episode(episode.seed))
            ctx.send((job.settings.variant, episode.shift, results[-1]))
    finally:
        runner.close()
    return len(results)


def run_lockstep_job(job: EvalJob, ctx: TaskContext) -> int:
    """``run_job`` on ``batch_size`` CPU cells stepped together: rolling where the policy allows, else waves."""
    s = job.settings
    variant = get_variant(s.variant)
    worlds = min(s.batch_size, len(job.episodes))
    threads_before = set_policy_threads(s.policy)
    cells = CpuCells(variant, worlds, s.cameras, s.image_size, s.episode_length, s.film)
    try:
        low, high = cells.envs[0].action_space.low, cells.envs[0].action_space.high
        policy = BatchedPolicy(s.policy, "cpu", low, high, s.precision)

        def sent(k: int, result: EpisodeResult) -> None:
            ctx.send((s.variant, job.episodes[k].shift, result))

        if policy.restart_period is not None:
            found, _ = run_rolling(cells, policy, job.episodes, cells.max_steps, policy.restart_period, cells.task,
                                   progress=False, stop=ctx.stopping, on_result=sent)
        else:
            found, _ = run_waves(cells, policy, job.episodes, cells.max_steps, cells.task, progress=False,
                                 stop=ctx.stopping, on_result=sent)
    finally:
        cells.close()
        restore_threads(threads_before)
    return sum(r is not None for r in found)


def run_jobs(tasks: list[tuple[str, Callable, Any]], episodes: int, executor: ExecutorConfig, progress: bool,
             desc: str, on_message: Callable[[Any], None] | None = None) -> None:
    """Run ``(key, function, job)`` tasks on ``executor`` with a progress bar of ``episodes``: each task sends one
    message an episode, which ``on_message`` is given as it arrives (what a task finished reaches the caller so,
    whether it returns or is stopped).

    Raises:
        StageError: a task failed (its traceback).
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
    failed = [r for r in results if r.error is not None]
    if failed:
        raise StageError("evaluation stopped: " + "; ".join(str(r.error) for r in failed))


def run_episodes(work: list[tuple[EvalConfig, list[EpisodePlan]]], executor: ExecutorConfig, shard_size: int,
                 progress: bool, desc: str, on_episode: Callable[[Finished], None] | None = None) -> list[Finished]:
    """Each ``(settings, episodes)`` pair's episodes in jobs of at most ``shard_size`` (enough jobs to keep every
    worker busy) on ``executor``, all at once; every finished one as ``Finished``, each also given to
    ``on_episode`` as it arrives. The same whatever the executor, its workers, the jobs and ``batch_size``: an
    episode starts from its seed and shifts alone. A stop (Ctrl-C) returns those that finished."""
    per = max(1, executor.workers // max(1, len(work)))  # jobs per pair that keep every worker busy
    jobs = [EvalJob(settings, tuple(block)) for settings, episodes in work if episodes
            for block in chunks(episodes, shard_size, per)]
    found: dict[tuple[str, tuple[str, ...], int], Finished] = {}  # a job run again (its process died) sends again

    def arrived(message: Finished) -> None:
        key = (message[0], message[1], message[2].seed)
        if key not in found and on_episode is not None:
            on_episode(message)
        found[key] = message

    if jobs:
        run_jobs([(job.key, run_job, job) for job in jobs], sum(len(j.episodes) for j in jobs), executor, progress,
                 desc, arrived)
    return list(found.values())


def arm_key(variant: str, shift: tuple[str, ...]) -> str:
    """How a plain evaluation's journal names the arm of an episode: its variant and its shifts' label."""
    return f"{variant}/{shift_label(parse_shifts(shift))}"


@dataclass(frozen=True)
class Evaluation:
    """The reports of an evaluation, one per variant in order, and the films of its episodes."""

    reports: list[EvalReport]
    films: dict[tuple[str, int], bytes]  # (variant, seed) -> H.264 mp4; empty unless filmed


def run_evaluation(policy_spec: str, variant_names: list[str], episodes: int, *, seed: int | None = None,
                   image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE, cameras: tuple[str, ...] = DEFAULT_CAMERAS,
                   progress: bool = True, episode_length: int | None = None,
                   executor: ExecutorConfig = ExecutorConfig(), shard_size: int = DEFAULT_SHARD_SIZE,
                   film: bool = False, shift: tuple[str, ...] = (), batch_size: int = 1, precision: str = "float32",
                   done: Mapping[Key, EpisodeResult] | None = None,
                   on_episode: Callable[[str, EpisodeResult], None] | None = None) -> Evaluation:
    """``episodes`` episodes of a policy on each variant, all spread over ``executor`` in jobs of at most
    ``shard_size`` episodes, each job ``batch_size`` cells stepped together; with ``film``, every episode is filmed
    in the process that runs it; with ``shift`` (``NAME:LEVEL`` texts), under those held-out shifts, on
    ``SHIFT_SEEDS`` unless ``seed`` is given. Episodes in ``done`` (a journal's, keyed ``(arm_key, seed)``) are
    not run again; ``on_episode(arm_key, result)`` is called as each new one finishes.

    Raises:
        Interrupted: the run was stopped (Ctrl-C); the episodes that finished went to ``on_episode``.
    """
    check_policy_spec(policy_spec)
    shift = tuple(str(s) for s in parse_shifts(shift))
    variants = [get_variant(name) for name in variant_names]
    path = policy_spec if policy_spec in ("expert", "random") else str(Path(policy_spec).resolve())  # for any worker
    done = done or {}
    planned = {v.name: episode_seeds(v, episodes, seed, bool(shift)) for v in variants}
    found = {(v, s): done[(arm_key(v, shift), s)] for v, seeds in planned.items() for s in seeds
             if (arm_key(v, shift), s) in done}
    work = [(EvalConfig(path, v, (image_size[0], image_size[1]), tuple(cameras), episode_length, film, shift,
                        batch_size, precision), [EpisodePlan(s, shift) for s in seeds if (v, s) not in found])
            for v, seeds in planned.items()]

    def arrived(message: Finished) -> None:
        if on_episode is not None:
            on_episode(arm_key(message[0], message[1]), message[2])

    for variant, _, result in run_episodes(work, executor, shard_size, progress,
                                           f"{policy_spec} on {', '.join(variant_names)}", arrived):
        found[(variant, result.seed)] = result
    total = sum(len(seeds) for seeds in planned.values())
    if len(found) < total:
        raise Interrupted(len(found), total)
    films = {key: r.video for key, r in found.items() if r.video is not None}
    label = shift_label(parse_shifts(shift))
    reports = [aggregate(str(policy_spec), v, [found[(v, s)] for s in seeds], label) for v, seeds in planned.items()]
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
    trained (its ``config.json``), else none for the expert and ``random`` (the expert takes its own photo
    through the sensor camera when the ray fires, ``expert.calibration.sensor_source``; ``random`` reads nothing).

    Raises:
        ValueError: an unknown policy, or cameras/size other than those the checkpoint takes.
    """
    check_policy_spec(policy_spec)
    given = parse_cameras(cameras) if cameras is not None else None
    size = (image_size, image_size) if image_size is not None else None
    if policy_spec in ("expert", "random"):
        return (given if given is not None else ()), size or DEFAULT_IMAGE_SIZE
    trained, trained_size = checkpoint_cameras(policy_spec)
    if given is not None and set(given) != set(trained):
        raise ConfigError(f"{policy_spec} was trained on cameras {list(trained) or 'none'}; got --cameras {cameras}")
    if size is not None and trained_size is not None and size != trained_size:
        raise ConfigError(f"{policy_spec} was trained on {trained_size[0]}x{trained_size[1]} images; "
                         f"got --image-size {image_size}")
    return trained, trained_size or size or DEFAULT_IMAGE_SIZE
