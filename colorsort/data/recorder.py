"""The recording loop: the expert runs episodes by seed and each kept one is saved as a LeRobot episode.

``record_shard`` records a list of episode numbers into one new dataset and always finalizes it,
so every episode it saved is loadable whatever stops it. Where its wall time goes is timed per
stage (``ShardSummary.seconds``) for ``benchmarks/bench_collect.py``.
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from colorsort.cell.referee import judge
from colorsort.config import sorting_time_limit
from colorsort.data.config import CollectConfig
from colorsort.data.perturbations import perturbed
from colorsort.envs.robosuite_task import ColorSort
from colorsort.envs.rollout import CellEpisode, Observer, Step, Stopped, rollout
from colorsort.envs.schema import features, frame, task_text
from colorsort.executors.base import held_interrupts
from colorsort.expert.base import Expert
from colorsort.expert.factory import make_expert
from colorsort.variants import get_variant

STAGES = ("setup", "expert", "physics and control", "rendering", "frames to lerobot", "episode saving")


@dataclass(frozen=True)
class TriedEpisode:
    """One demo the recorder tried: kept in the dataset, or why not (not an evaluated episode: that is
    ``benchmark.episode_result.EpisodeResult``)."""

    index: int  # episode number i: seed = base seed + i
    seed: int
    kept: bool
    reason: str  # "ok", or why it was not kept: "misplaced", "dropped", "timeout" (``referee.judge``)
    frames: int
    sim_time_s: float  # [s]


@dataclass
class ShardSummary:
    """What one recorder did, and where its wall time went [s]."""

    root: str
    tried: list[int] = field(default_factory=list)  # episode numbers run to the end, in order
    kept: list[int] = field(default_factory=list)  # episode numbers saved, in order
    failed: dict[str, str] = field(default_factory=dict)  # episode number -> why it was not kept
    interrupted: bool = False
    incomplete: bool = False  # the interrupt cut an episode's save short: the shard's files cannot be trusted
    error: str | None = None
    seconds: dict[str, float] = field(default_factory=lambda: dict.fromkeys(STAGES, 0.0))
    sim_state: dict | None = None  # the sim-state layout of its env (``SimStateLayout.describe``)
    draws: dict[str, dict] = field(default_factory=dict)  # kept episode number -> its shifts' draws (``--shift``)


def episode_time_limit(config: CollectConfig) -> float:
    """[s] sim time after which an episode counts as failed."""
    return sorting_time_limit(config.boxes_per_episode, config.task_config)


def make_recording_env(config: CollectConfig) -> ColorSort:
    """The env the collector records from: the dataset's cameras, every step (none for a state-only dataset;
    the expert still renders its own sensor photo)."""
    h, w = config.image_size
    return ColorSort(robots=config.robot, config=config.task_config, use_camera_obs=bool(config.cameras),
                     camera_names=list(config.cameras) or "scene",
                     camera_heights=h, camera_widths=w, control_freq=config.fps, ignore_done=True, seed=config.seed,
                     shift=config.shift or None)


def expert_step(expert: Expert, obs: dict) -> Step:
    """The expert's action for ``obs``, stored and executed as it is (float32: the env consumes exactly that)."""
    action = expert.act(obs).astype(np.float32)
    return Step(action, action)


def perturbed_step(hooks: list, expert: Expert, obs: dict) -> Step:
    """This step's actions: the expert's for ``obs`` through the perturbations' ``hooks``."""
    return perturbed(hooks, partial(expert_step, expert, obs))


class FrameWriter(Observer):
    """Adds each step's frame (the observation acted on, the stored action) to the dataset being recorded, and
    times where the step's wall time went (``ShardSummary.seconds``)."""

    def __init__(self, env: ColorSort, dataset: Any, cameras: tuple[str, ...], task: str, seconds: dict[str, float]):
        self.env, self.dataset, self.cameras, self.task, self.sec = env, dataset, cameras, task, seconds
        self.frames = 0
        self._t = self._t_add = 0.0
        self._rendered_before = 0.0

    def on_observe(self, obs: Any) -> None:
        self._t = time.perf_counter()

    def on_action(self, obs: Any, step: Step) -> None:
        t_act = time.perf_counter()
        self.dataset.add_frame(frame(self.env, obs, step.stored, self.cameras, self.task))
        self._t_add = time.perf_counter()
        self.sec["expert"] += t_act - self._t
        self.sec["frames to lerobot"] += self._t_add - t_act
        self._rendered_before = self.env.render_seconds

    def on_step(self, obs: Any, info: dict) -> None:
        rendered = self.env.render_seconds - self._rendered_before
        self.sec["rendering"] += rendered
        self.sec["physics and control"] += time.perf_counter() - self._t_add - rendered
        self.frames += 1


def record_shard(config: CollectConfig, indices: list[int], root: Path,
                 report: Callable[[TriedEpisode], None], stop: Callable[[], bool] = lambda: False) -> ShardSummary:
    """Record episodes ``indices`` into a new dataset at ``root``; always finalizes what it saved.

    Ctrl-C (KeyboardInterrupt) or ``stop()`` turning true abandons the episode under way and
    returns with ``interrupted`` set; any other error is returned in ``error``.
    """
    out = ShardSummary(str(root))
    t0 = time.perf_counter()
    env = make_recording_env(config)
    expert = make_expert(env, config.expert_config)
    out.sim_state = env.sim_state_layout.describe()
    dataset = open_dataset(config, env, root)
    demonstrator = Demonstrator(config, env, expert)
    out.seconds["setup"] += time.perf_counter() - t0
    try:
        for index in indices:
            report(demonstrator.record(index, dataset, out, stop))
    except (KeyboardInterrupt, Stopped):
        out.interrupted = True
    except Exception:  # noqa: BLE001 - reported to the caller, finished episodes are still saved
        out.error = traceback.format_exc()
    finally:
        finalize(dataset, out)
        env.close()
    return out


def open_dataset(config: CollectConfig, env: ColorSort, root: Path) -> Any:
    """A new LeRobot dataset at ``root`` for ``env``'s frames at ``config``'s cameras, encoding as it records."""
    import av
    from lerobot.configs.video import RGBEncoderConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    av.logging.set_libav_level(av.logging.ERROR)  # FFmpeg's notes on every file it writes (lerobot restores
    # FFmpeg's own log callback, which prints at this level)
    return LeRobotDataset.create(
        config.repo_id, config.fps, features(env, config.cameras, config.image_size), root=root,
        robot_type=config.robot, use_videos=True, video_backend="pyav",
        rgb_encoder=RGBEncoderConfig(vcodec=config.vcodec), streaming_encoding=True, encoder_queue_maxsize=10_000,
        encoder_threads=1 if config.executor.workers > 1 or config.executor.name != "local" else None,
    )


class Demonstrator:
    """The expert of a collection with its perturbations and lights, recording episodes by number.

    Args:
        config: the collection.
        env: the recording env (``make_recording_env``).
        expert: the expert acting in it.
    """

    def __init__(self, config: CollectConfig, env: ColorSort, expert: Expert):
        self.config, self.env, self.expert = config, env, expert
        self.lighting = None
        if config.variant:
            variant = get_variant(config.variant)
            self.lighting = next((draw for p in config.perturbations if (draw := p.lighting(variant))),
                                 variant.lighting)
        self.around_expert = sorted(config.perturbations, key=lambda p: (p.order, p.name))  # innermost first

    def record(self, index: int, dataset: Any, out: ShardSummary, stop: Callable[[], bool]) -> TriedEpisode:
        """Episode ``index`` (seed ``config.seed + index``), saved in ``dataset`` when it sorted its boxes right (its
        draws in ``out.draws`` under shifts), cleared otherwise."""
        config, env, expert = self.config, self.env, self.expert
        seed, k, sec = config.seed + index, config.boxes_per_episode, out.seconds
        obs = env.reset(seed=seed, lighting=self.lighting)  # as the benchmark's gym env: same seed, same episode
        expert.reset(obs)
        hooks = [p.episode(seed, expert) for p in self.around_expert]
        first = min(env.boxes_in_play(), key=lambda b: b.serial)
        writer = FrameWriter(env, dataset, config.cameras, task_text(first.color, k), sec)
        # stored as float32: the env consumes exactly that; the executed action is the stored one unless a
        # perturbation holds something back
        rollout(CellEpisode(env, k, episode_time_limit(config)), obs, partial(perturbed_step, hooks, expert),
                [writer], stop=stop)
        reason = judge(env.events, k).reason
        t = time.perf_counter()
        with held_interrupts():  # a save cut short would cost every episode of the shard
            if reason == "ok":
                dataset.save_episode()
                out.kept.append(index)
                if config.shift:
                    out.draws[str(index)] = env.shifts.record
            else:
                dataset.clear_episode_buffer()
                out.failed[str(index)] = reason
            out.tried.append(index)
        sec["episode saving"] += time.perf_counter() - t
        return TriedEpisode(index, seed, reason == "ok", reason, writer.frames, writer.frames / config.fps)


def finalize(dataset: Any, out: ShardSummary) -> None:
    """Finish ``dataset``'s files with every episode saved; the one under way, if any, is dropped. After an
    interrupt that cut a save short (``out.incomplete``) the files are not to be trusted and are dropped anyway."""
    try:
        pending = dataset.has_pending_frames()
    except KeyError:  # save_episode takes "size" out of the buffer first: the interrupt came while it saved
        out.incomplete = pending = True
    if pending:
        dataset.clear_episode_buffer()  # the episode under way is not saved
    try:
        dataset.finalize()
    except Exception:  # noqa: BLE001 - after a cut-short save the files are dropped anyway
        if not out.incomplete:
            raise
