"""Record the scripted expert's episodes as a LeRobot v3.0 dataset.

Example::

    colorsort-collect --episodes 100 --boxes-per-episode 1 --preset default --robot IRB140 \\
        --seed 0 --out datasets/colorsort --repo-id local/colorsort --cameras scene,wrist \\
        --image-size 128 --fps 20 --workers 2 --vcodec libsvtav1

Episode ``i`` (0 <= i < episodes) runs with env seed ``seed + i``, so a dataset is the same
whatever the number of workers; only episodes in which every box ended where it belongs are
kept (the summary says how many were tried and why the others were not). ``--workers N``
records N shards side by side and merges them with lerobot's ``aggregate_datasets``.

The output directory only ever holds a complete dataset: shards are recorded in a hidden
staging folder beside it (``.<name>.staging``) and the merged result replaces the output in one
rename. Ctrl-C stops recording, keeps every finished episode and says so; ``--resume`` then
records the episodes still missing; ``--overwrite`` replaces an existing dataset.
``meta/colorsort.json`` keeps the settings, the episode number (seed - base seed) of each
dataset episode in order (``episodes``), every episode number tried and why failed ones failed.

Exit status: 0 done, 1 nothing kept or a worker failed, 2 bad arguments, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import queue
import shutil
import signal
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from tqdm import tqdm

from colorsort.config import PRESETS, ROBOTS, TaskConfig, make_config, sorting_time_limit
from colorsort.logs import quiet_robosuite_info
from colorsort.variants import VARIANTS, get_variant

os.environ.setdefault("SVT_LOG", "1")  # the AV1 encoder's banner and info lines: errors only
os.environ.setdefault("HF_DATASETS_DISABLE_PROGRESS_BARS", "1")  # one bar per episode saved, otherwise
# Mesa's CPU renderer draws in the calling thread, with no helper threads competing with the
# video encoder and with other workers for the cores.
os.environ.setdefault("LP_NUM_THREADS", "0")
from colorsort.env import CAMERAS, parse_cameras  # noqa: E402

FPS_CHOICES = (10, 20, 25, 50)  # control rates whose period is a whole number of 10 ms servo periods
VCODECS = ("h264", "libsvtav1", "hevc")
MARKER = "meta/colorsort.json"  # the collector's record: settings and the episodes tried


@dataclass(frozen=True)
class CollectConfig:
    """What to record and where."""

    episodes: int = 10  # episodes to try; episode i runs with env seed `seed + i`
    boxes_per_episode: int = 1  # an episode ends when this many boxes have left the belt
    preset: str = "default"  # task preset (config.PRESETS)
    robot: str = "IRB140"  # "IRB140", "Panda" or "UR5e"
    variant: str | None = None  # record a benchmark variant's task (its preset, overrides, robot and lights)
    seed: int = 0  # base seed
    out: str = "datasets/colorsort"  # dataset directory (LeRobot's `root`)
    repo_id: str = "local/colorsort"  # LeRobot repo id, for loading: LeRobotDataset(repo_id, root=out)
    cameras: tuple[str, ...] = ("scene", "wrist")  # stored as observation.images.<camera>; () records state only
    image_size: tuple[int, int] = (128, 128)  # (height, width) of every camera [px]
    fps: int = 20  # frames per second = the env's control rate [Hz]
    workers: int = 1  # processes recording shards side by side
    vcodec: str = "h264"  # video codec of the camera streams (bench_collect.py --vcodec compares them)
    resume: bool = False  # add the episodes still missing to an existing dataset
    overwrite: bool = False  # replace an existing dataset

    def __post_init__(self) -> None:
        if self.variant is not None:
            v = get_variant(self.variant)
            if (self.preset, self.robot) != (v.preset, v.robot):
                raise ValueError(f"variant {self.variant!r} sets the preset ({v.preset!r}) and robot ({v.robot!r}); "
                                 f"got preset={self.preset!r}, robot={self.robot!r}: give the variant alone")
        if self.preset not in PRESETS:
            raise ValueError(f"Unknown preset {self.preset!r}. Valid presets: {sorted(PRESETS)}")
        if self.robot not in ROBOTS:
            raise ValueError(f"Unknown robot {self.robot!r}. Valid robots: {list(ROBOTS)}")
        bad = [c for c in self.cameras if c not in CAMERAS]
        if bad or len(set(self.cameras)) != len(self.cameras):
            raise ValueError(f"cameras={self.cameras}: give distinct names from {list(CAMERAS)}, or none")
        if self.fps not in FPS_CHOICES:
            raise ValueError(f"fps={self.fps} not supported. Valid values: {list(FPS_CHOICES)}")
        if self.vcodec not in VCODECS:
            raise ValueError(f"Unknown vcodec {self.vcodec!r}. Valid codecs: {list(VCODECS)}")
        if not 1 <= self.episodes <= 1_000_000:
            raise ValueError(f"episodes={self.episodes} out of range; valid values lie in [1, 1000000]")
        if not 1 <= self.boxes_per_episode <= 100:
            raise ValueError(f"boxes_per_episode={self.boxes_per_episode}; valid values lie in [1, 100]")
        if not 1 <= self.workers <= 64:
            raise ValueError(f"workers={self.workers}; valid values lie in [1, 64]")
        if not all(16 <= s <= 1024 and s % 2 == 0 for s in self.image_size):
            raise ValueError(f"image_size={self.image_size}: height and width must be even, in [16, 1024] px")
        if self.seed < 0:
            raise ValueError(f"seed={self.seed} must be >= 0")
        if self.resume and self.overwrite:
            raise ValueError("Pass --resume or --overwrite, not both")

    def settings(self) -> dict:
        """The settings every episode of one dataset must share (checked on --resume)."""
        keys = ("boxes_per_episode", "preset", "robot", "variant", "seed", "repo_id", "cameras", "image_size", "fps", "vcodec")
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items() if k in keys}

    @property
    def task_config(self) -> TaskConfig:
        """The task the episodes run: the variant's, or the preset's."""
        return get_variant(self.variant).task_config if self.variant else make_config(self.preset)


@dataclass(frozen=True)
class EpisodeResult:
    index: int  # episode number i: seed = base seed + i
    seed: int
    kept: bool
    reason: str  # "ok", or why it was not kept: "misplaced", "dropped", "timeout"
    frames: int
    sim_time_s: float  # [s]


@dataclass
class ShardReport:
    """What one recorder did, and where its wall time went [s]."""

    root: str
    kept: list[int] = field(default_factory=list)  # episode numbers saved, in order
    interrupted: bool = False
    error: str | None = None
    seconds: dict[str, float] = field(default_factory=lambda: dict.fromkeys(
        ("setup", "expert", "physics and control", "rendering", "frames to lerobot", "episode saving"), 0.0))


@dataclass
class CollectSummary:
    root: str
    repo_id: str
    tried: int = 0  # episodes tried by this run
    kept: int = 0
    not_kept: dict[str, int] = field(default_factory=dict)  # reason -> episodes
    frames: int = 0  # frames recorded by this run (kept episodes)
    sim_time_s: float = 0.0  # [s] sim time recorded by this run (kept episodes)
    dataset_episodes: int = 0  # in the dataset at the end, earlier runs included
    dataset_frames: int = 0
    wall_s: float = 0.0
    size_mb: float = 0.0
    interrupted: bool = False
    errors: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)  # summed over workers, plus "merging"

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds recorded per wall-clock second."""
        return self.sim_time_s / self.wall_s if self.wall_s > 0 else 0.0


# ---------------------------------------------------------------------------------------- recording
def episode_time_limit(config: CollectConfig) -> float:
    """[s] sim time after which an episode counts as failed."""
    return sorting_time_limit(config.boxes_per_episode, config.task_config)


def make_recording_env(config: CollectConfig):
    """The env the collector records from: the dataset's cameras, every step (none for a state-only dataset;
    the expert still renders its own sensor photo)."""
    from colorsort.env import ColorSort

    h, w = config.image_size
    return ColorSort(robots=config.robot, config=config.task_config, use_camera_obs=bool(config.cameras),
                     camera_names=list(config.cameras) or "scene",
                     camera_heights=h, camera_widths=w, control_freq=config.fps, ignore_done=True, seed=config.seed)


class _Stopped(Exception):
    """Recording was asked to stop."""


def record_shard(config: CollectConfig, indices: list[int], root: Path,
                 report: Callable[[EpisodeResult], None], stop: Callable[[], bool] = lambda: False) -> ShardReport:
    """Record episodes ``indices`` into a new dataset at ``root``; always finalizes what it saved.

    Ctrl-C (KeyboardInterrupt) or ``stop()`` turning true abandons the episode under way and
    returns with ``interrupted`` set; any other error is returned in ``error``.
    """
    import av
    from lerobot.configs.video import RGBEncoderConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.dataset import features, frame, task_text

    av.logging.set_libav_level(av.logging.ERROR)  # FFmpeg's notes on every file it writes (lerobot restores
    # FFmpeg's own log callback, which prints at this level)
    from colorsort.expert import SortingExpert
    from colorsort.lighting import LightRig

    out = ShardReport(str(root))
    sec = out.seconds
    t0 = time.perf_counter()
    env = make_recording_env(config)
    expert = SortingExpert(env)
    variant = get_variant(config.variant) if config.variant else None
    lights = LightRig(env.mj_model) if variant else None
    dataset = LeRobotDataset.create(
        config.repo_id, config.fps, features(env, config.cameras, config.image_size), root=root,
        robot_type=config.robot, use_videos=True, video_backend="pyav", rgb_encoder=RGBEncoderConfig(vcodec=config.vcodec),
        streaming_encoding=True, encoder_queue_maxsize=10_000, encoder_threads=1 if config.workers > 1 else None,
    )
    sec["setup"] += time.perf_counter() - t0
    limit = episode_time_limit(config)
    k = config.boxes_per_episode
    try:
        for index in indices:
            seed = config.seed + index
            obs = env.reset(seed=seed)
            if variant is not None:  # as the benchmark's gym env does: the same seed gives the same episode
                lights.apply(variant.lighting(env.rng))
                if variant.random_lights and config.cameras:
                    obs = env.observe()
            expert.reset(obs)
            first = min(env.boxes_in_play(), key=lambda b: b.serial)
            task = task_text(first.color, k)
            frames = 0
            while len(env.events) < k and env.cur_time < limit:
                if stop():
                    raise _Stopped
                t = time.perf_counter()
                action = expert.act(obs).astype(np.float32)  # stored as float32: the env consumes exactly that
                t_act = time.perf_counter()
                dataset.add_frame(frame(env, obs, action, config.cameras, task))
                t_add = time.perf_counter()
                render_before = env.render_seconds
                obs, _, _, _ = env.step(action)
                t_step = time.perf_counter()
                rendered = env.render_seconds - render_before
                sec["expert"] += t_act - t
                sec["frames to lerobot"] += t_add - t_act
                sec["rendering"] += rendered
                sec["physics and control"] += t_step - t_add - rendered
                frames += 1
            outcomes = [e.outcome for e in env.events[:k]]
            if len(outcomes) < k:
                reason = "timeout"
            else:
                reason = next((o for o in outcomes if o not in ("placed", "rejected")), "ok")
            t = time.perf_counter()
            if reason == "ok":
                dataset.save_episode()
                out.kept.append(index)
            else:
                dataset.clear_episode_buffer()
            sec["episode saving"] += time.perf_counter() - t
            report(EpisodeResult(index, seed, reason == "ok", reason, frames, frames / config.fps))
    except (KeyboardInterrupt, _Stopped):
        out.interrupted = True
    except Exception:  # noqa: BLE001 - reported to the caller, finished episodes are still saved
        out.error = traceback.format_exc()
    finally:
        if dataset.has_pending_frames():
            dataset.clear_episode_buffer()  # the episode under way is not saved
        dataset.finalize()
        env.close()
    return out


def _worker(config: CollectConfig, indices: list[int], root: str, messages, stop_event) -> None:
    """A recording process: Ctrl-C goes to the parent, which asks it to stop through ``stop_event``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    quiet_robosuite_info()
    try:
        shard = record_shard(config, indices, Path(root), lambda r: messages.put(("episode", r)), stop_event.is_set)
    except BaseException:  # noqa: BLE001 - e.g. the env could not be built
        shard = ShardReport(root, error=traceback.format_exc())
    messages.put(("shard", shard))


def split(indices: list[int], parts: int) -> list[list[int]]:
    """``indices`` in ``parts`` contiguous blocks, sizes differing by at most one."""
    sizes = [len(indices) // parts + (k < len(indices) % parts) for k in range(parts)]
    starts = np.cumsum([0] + sizes)
    return [indices[starts[k] : starts[k + 1]] for k in range(parts) if sizes[k] > 0]


# ---------------------------------------------------------------------------------------- the whole job
def read_marker(root: Path) -> dict | None:
    path = root / MARKER
    return json.loads(path.read_text()) if path.is_file() else None


def _check_output(config: CollectConfig, root: Path) -> dict | None:
    """Validate what is at ``root`` against --resume / --overwrite; returns the marker to resume from."""
    if not root.exists():
        return None
    if root.is_dir() and not any(root.iterdir()):
        return None
    is_dataset = (root / "meta" / "info.json").is_file()
    if config.overwrite:
        if not is_dataset:
            raise FileExistsError(f"{root} exists and is not a LeRobot dataset: not overwriting it")
        return None
    if not config.resume:
        raise FileExistsError(f"{root} already exists. Pass --resume to add the missing episodes to it, "
                              "--overwrite to replace it, or choose another --out")
    marker = read_marker(root)
    if marker is None:
        raise ValueError(f"Cannot resume {root}: it has no {MARKER}, so it was not recorded by colorsort-collect")
    if marker["settings"] != config.settings():
        diff = {k: (marker["settings"].get(k), v) for k, v in config.settings().items() if marker["settings"].get(k) != v}
        raise ValueError(f"Cannot resume {root} with other settings (recorded, requested): {diff}")
    return marker


def _merge(sources: list[Path], dest: Path, repo_id: str) -> None:
    """One dataset at ``dest`` from ``sources`` (complete datasets), episodes in order."""
    if len(sources) == 1:
        shutil.move(sources[0], dest)
        return
    import warnings

    from lerobot.datasets.aggregate import aggregate_datasets

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Cannot enable progress bars")
        aggregate_datasets([repo_id] * len(sources), repo_id, roots=sources, aggr_root=dest)


def dir_size_mb(root: Path) -> float:
    return sum(f.stat().st_size for f in root.rglob("*") if f.is_file()) / 1e6


def collect(config: CollectConfig, progress: bool = True, log: Callable[[str], None] = print) -> CollectSummary:
    """Record, merge and report, as the module docstring says.

    Raises:
        FileExistsError: the output exists and neither --resume nor --overwrite was given.
        ValueError: --resume on a dataset recorded with other settings.
    """
    start = time.perf_counter()
    root = Path(config.out).resolve()
    marker = _check_output(config, root)
    tried = set(marker["tried"]) if marker else set()
    failed = dict(marker.get("failed", {})) if marker else {}
    todo = [i for i in range(config.episodes) if i not in tried]
    summary = CollectSummary(str(root), config.repo_id)
    if marker and not todo:
        log(f"{root} already holds all {config.episodes} episodes tried; nothing to do")
        return summary
    staging = root.parent / f".{root.name}.staging"
    if staging.exists():
        log(f"removing {staging}, left by a run that was killed")
        shutil.rmtree(staging)
    staging.mkdir(parents=True)
    blocks = split(todo, min(config.workers, len(todo)))
    shards: list[ShardReport] = []
    bar = tqdm(total=len(todo), unit="episode", desc="recording", disable=not progress, smoothing=0.1)

    def on_episode(r: EpisodeResult) -> None:
        tried.add(r.index)
        summary.tried += 1
        if r.kept:
            summary.kept += 1
            summary.frames += r.frames
            summary.sim_time_s += r.sim_time_s
        else:
            failed[str(r.index)] = r.reason
            summary.not_kept[r.reason] = summary.not_kept.get(r.reason, 0) + 1
        bar.update(1)
        bar.set_postfix(kept=summary.kept, not_kept=summary.tried - summary.kept)

    try:
        if len(blocks) == 1:
            shards.append(record_shard(config, blocks[0], staging / "shard-00", on_episode))
        else:
            shards = _run_workers(config, blocks, staging, on_episode, log)
    finally:
        bar.close()
    summary.interrupted = any(s.interrupted for s in shards)
    summary.errors = [s.error for s in shards if s.error]
    for s in shards:
        for key, value in s.seconds.items():
            summary.seconds[key] = summary.seconds.get(key, 0.0) + value

    t = time.perf_counter()
    sources = ([root] if marker else []) + [Path(s.root) for s in shards if s.kept]
    if any(s.kept for s in shards):
        merged = staging / "merged"
        (_merge_in_child if len(shards) > 1 else _merge)(sources, merged, config.repo_id)
        kept = (marker["episodes"] if marker else []) + [i for s in shards for i in s.kept]
        record = {"settings": config.settings(), "episodes": kept, "tried": sorted(tried), "failed": failed}
        (merged / MARKER).write_text(json.dumps(record))
        old = staging / "previous"
        if root.exists():
            root.rename(old)
        merged.rename(root)
    elif marker:  # nothing new kept: still remember what was tried
        marker.update(tried=sorted(tried), failed=failed)
        (root / MARKER).write_text(json.dumps(marker))
    shutil.rmtree(staging, ignore_errors=True)
    summary.seconds["merging"] = time.perf_counter() - t
    summary.wall_s = time.perf_counter() - start
    if root.exists() and (root / "meta" / "info.json").is_file():
        info = json.loads((root / "meta" / "info.json").read_text())
        summary.dataset_frames, summary.dataset_episodes = info["total_frames"], info["total_episodes"]
        summary.size_mb = dir_size_mb(root)
    return summary


def _context():
    """Worker processes forked from a server that imported lerobot (seconds of torch) once and has
    never opened a GL context; each worker opens its own."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["colorsort.collect", "lerobot.datasets.lerobot_dataset", "lerobot.datasets.aggregate"])
    return ctx


def _merge_in_child(sources: list[Path], dest: Path, repo_id: str) -> None:
    """``_merge`` in a worker process: the parent never has to import lerobot."""
    p = _context().Process(target=_merge, args=(sources, dest, repo_id))
    p.start()
    p.join()
    if p.exitcode != 0:
        raise RuntimeError(f"merging {len(sources)} datasets into {dest} failed (exit code {p.exitcode}); "
                           f"the recorded shards are kept in {dest.parent}")


def _run_workers(config: CollectConfig, blocks: list[list[int]], staging: Path,
                 on_episode: Callable[[EpisodeResult], None], log: Callable[[str], None]) -> list[ShardReport]:
    ctx = _context()
    messages, stop_event = ctx.Queue(), ctx.Event()
    procs = [ctx.Process(target=_worker, args=(config, b, str(staging / f"shard-{k:02d}"), messages, stop_event),
                        daemon=False) for k, b in enumerate(blocks)]
    for p in procs:
        p.start()
    shards: dict[str, ShardReport] = {}
    while len(shards) < len(procs):
        try:
            kind, payload = messages.get(timeout=0.5)
        except queue.Empty:
            dead = [p for p in procs if not p.is_alive() and p.exitcode not in (0, None)]
            if dead and messages.empty():
                for k, p in enumerate(procs):
                    root = str(staging / f"shard-{k:02d}")
                    if not p.is_alive() and root not in shards and p.exitcode != 0:
                        shards[root] = ShardReport(root, error=f"worker {k} died with exit code {p.exitcode}")
            continue
        except KeyboardInterrupt:
            log("stopping: the workers finish saving what they recorded ...")
            stop_event.set()
            continue
        if kind == "episode":
            on_episode(payload)
        else:
            shards[payload.root] = payload
    for p in procs:
        p.join()
    return [shards[str(staging / f"shard-{k:02d}")] for k in range(len(procs))]


# ---------------------------------------------------------------------------------------- command line
def parse_image_size(text: str) -> tuple[int, int]:
    """"128" -> (128, 128); "96x128" -> (96, 128) (height x width)."""
    parts = text.lower().split("x")
    try:
        size = tuple(int(p) for p in parts)
    except ValueError:
        raise ValueError(f"image size {text!r}: give one number (square) or HxW, e.g. 128 or 96x128") from None
    if len(size) == 1:
        return size[0], size[0]
    if len(size) == 2:
        return size  # type: ignore[return-value]
    raise ValueError(f"image size {text!r}: give one number (square) or HxW, e.g. 128 or 96x128")


def parse_args(argv: list[str] | None) -> CollectConfig:
    d = CollectConfig()
    parser = argparse.ArgumentParser(prog="colorsort-collect", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--episodes", type=int, default=d.episodes, help="episodes to try (seeds seed..seed+N-1)")
    parser.add_argument("--boxes-per-episode", type=int, default=d.boxes_per_episode,
                        help="boxes that leave the belt per episode")
    parser.add_argument("--preset", default=None, choices=sorted(PRESETS), help=f"task preset (default {d.preset})")
    parser.add_argument("--robot", default=None, choices=list(ROBOTS), help=f"robot arm (default {d.robot})")
    parser.add_argument("--variant", default=None, choices=list(VARIANTS),
                        help="record a benchmark variant's task (preset, overrides, robot, lights); "
                             "not with --preset or --robot")
    parser.add_argument("--seed", type=int, default=d.seed, help="base seed: episode i uses seed + i")
    parser.add_argument("--out", default=d.out, help="dataset directory")
    parser.add_argument("--repo-id", default=d.repo_id, help="LeRobot repo id of the dataset")
    parser.add_argument("--cameras", default=",".join(d.cameras),
                        help=f"comma-separated, any of {','.join(CAMERAS)}; 'none' records state only (no videos)")
    parser.add_argument("--image-size", default=str(d.image_size[0]), help="square size or HxW [px]")
    parser.add_argument("--fps", type=int, default=d.fps, help=f"frames per second, one of {FPS_CHOICES}")
    parser.add_argument("--workers", type=int, default=d.workers, help="recording processes")
    parser.add_argument("--vcodec", default=d.vcodec, help=f"video codec, one of {VCODECS}")
    parser.add_argument("--resume", action="store_true", help="add the missing episodes to an existing dataset")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing dataset")
    args = parser.parse_args(argv)
    if args.variant and (args.preset or args.robot):
        parser.error("--variant sets the preset and robot: give --variant alone, or --preset/--robot")
    if args.variant:
        v = get_variant(args.variant)
        preset, robot = v.preset, v.robot
    else:
        preset, robot = args.preset or d.preset, args.robot or d.robot
    try:
        return CollectConfig(
            episodes=args.episodes, boxes_per_episode=args.boxes_per_episode, preset=preset, robot=robot,
            variant=args.variant, seed=args.seed, out=args.out, repo_id=args.repo_id,
            cameras=parse_cameras(args.cameras),
            image_size=parse_image_size(args.image_size), fps=args.fps, workers=args.workers, vcodec=args.vcodec,
            resume=args.resume, overwrite=args.overwrite)
    except ValueError as err:
        parser.error(str(err))  # exits with status 2
        raise


def print_summary(config: CollectConfig, s: CollectSummary) -> None:
    reasons = ", ".join(f"{k}: {v}" for k, v in sorted(s.not_kept.items())) or "none"
    print(f"episodes this run: tried {s.tried}, kept {s.kept}, not kept {s.tried - s.kept} ({reasons})")
    print(f"recorded {s.sim_time_s:.1f} s of sim time in {s.wall_s:.1f} s: {s.real_time_factor:.2f}x real time")
    if s.dataset_episodes:
        print(f"dataset: {s.root}  ({s.dataset_episodes} episodes, {s.dataset_frames} frames at {config.fps} fps, "
              f"{s.size_mb:.1f} MB on disk)")
        print("load it:  HF_HUB_OFFLINE=1 python -c \"from lerobot.datasets.lerobot_dataset import LeRobotDataset; "
              f"print(LeRobotDataset('{config.repo_id}', root='{s.root}', video_backend='pyav'))\"")
    if s.interrupted:
        print("interrupted: every finished episode is saved; run again with --resume to record the rest")


def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(argv)
    try:
        summary = collect(config, progress=True, log=tqdm.write)
    except (FileExistsError, ValueError) as err:
        print(f"colorsort-collect: error: {err}", file=sys.stderr)
        return 2
    print_summary(config, summary)
    for error in summary.errors:
        print(f"a worker failed:\n{error}", file=sys.stderr)
    if summary.interrupted:
        return 130
    if summary.errors or summary.dataset_episodes == 0:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
