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
import sys

from tqdm import tqdm

from colorsort.cell.cameras import CAMERAS, parse_cameras
from colorsort.cli.args import parse_image_size
from colorsort.cli.run import guarded
from colorsort.config import PRESETS
from colorsort.data.collect import CollectSummary, collect
from colorsort.data.config import FPS_CHOICES, VCODECS, CollectConfig
from colorsort.data.perturbations import PERTURBATIONS, parse
from colorsort.errors import FAILED, INTERRUPTED
from colorsort.executors.base import EXECUTORS
from colorsort.expert.config import parse_changes
from colorsort.logs import quiet_robosuite_info
from colorsort.robots import ROBOTS
from colorsort.variants import VARIANTS, get_variant


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
    parser.add_argument("--workers", type=int, default=d.workers,
                        help="shards recorded at once (processes, or Ray tasks of 1 CPU)")
    parser.add_argument("--executor", default=d.executor, choices=EXECUTORS,
                        help="local: processes on this machine; ray: a Ray cluster (see --address)")
    parser.add_argument("--address", default=None,
                        help="ray: the cluster to join, e.g. auto (default: start one on this machine)")
    parser.add_argument("--shard-size", type=int, default=d.shard_size,
                        help="episodes per shard, at most (fewer where that keeps every worker busy)")
    parser.add_argument("--retries", type=int, default=d.retries,
                        help="times a shard is recorded again after its worker process died")
    parser.add_argument("--vcodec", default=d.vcodec, help=f"video codec, one of {VCODECS}")
    for name, kind in PERTURBATIONS.items():  # the demonstrator's perturbations, one flag each
        parser.add_argument(f"--{name.replace('_', '-')}", dest=name, metavar=kind.metavar, default=None,
                            help=f"{kind.help} (colorsort.data.perturbations.{kind.__module__.rsplit('.', 1)[-1]})")
    parser.add_argument("--no-turn", action="store_true",
                        help="the expert keeps the cup at its home yaw over a turned box instead of turning to it")
    parser.add_argument("--expert", default=None, metavar="NAME:VALUE,...",
                        help="the expert's settings changed from its belt's preset (colorsort.expert.config), e.g. "
                             "press:0.01,track_hold_time:0.15")
    parser.add_argument("--shift", default=d.shift, metavar="NAME:train,...",
                        help="record with shifts' training ranges drawn per episode (colorsort.shifts; all:train for "
                             "every one that has a range); held-out levels 1-3 are refused")
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
    return CollectConfig(
        episodes=args.episodes, boxes_per_episode=args.boxes_per_episode, preset=preset, robot=robot,
        variant=args.variant, seed=args.seed, out=args.out, repo_id=args.repo_id,
        cameras=parse_cameras(args.cameras),
        image_size=parse_image_size(args.image_size), fps=args.fps, workers=args.workers, vcodec=args.vcodec,
        executor=args.executor, shard_size=args.shard_size, retries=args.retries, address=args.address,
        turn_to_box=not args.no_turn, expert=parse_changes(args.expert) if args.expert else (), shift=args.shift,
        resume=args.resume, overwrite=args.overwrite,
        perturbations=tuple(parse(name, getattr(args, name)) for name in PERTURBATIONS
                            if getattr(args, name) is not None))


def print_summary(config: CollectConfig, s: CollectSummary) -> None:
    reasons = ", ".join(f"{k}: {v}" for k, v in sorted(s.not_kept.items())) or "none"
    print(f"episodes this run: tried {s.tried}, kept {s.kept}, not kept {s.tried - s.kept} ({reasons})")
    print(f"recorded {s.sim_time_s:.1f} s of sim time in {s.wall_s:.1f} s: {s.real_time_factor:.2f}x real time")
    kept = f", {s.shards_kept} kept from the killed run" if s.shards_kept else ""
    print(f"shards: {s.shards} of at most {config.shard_size} episodes on {config.workers} {s.executor} "
          f"worker{'s' * (config.workers > 1)}{kept}; retried {s.retried}")
    if s.dataset_episodes:
        print(f"dataset: {s.root}  ({s.dataset_episodes} episodes, {s.dataset_frames} frames at {config.fps} fps, "
              f"{s.size_mb:.1f} MB on disk)")
        print("load it:  HF_HUB_OFFLINE=1 python -c \"from lerobot.datasets.lerobot_dataset import LeRobotDataset; "
              f"print(LeRobotDataset('{config.repo_id}', root='{s.root}', video_backend='pyav'))\"")
    if s.interrupted:
        print("interrupted: every finished episode is saved; run again with --resume to record the rest")


@guarded("colorsort-collect")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(argv)
    summary = collect(config, progress=True, log=tqdm.write)
    print_summary(config, summary)
    for error in summary.errors:
        print(f"a worker failed:\n{error}", file=sys.stderr)
    if summary.interrupted:
        return INTERRUPTED
    if summary.errors or summary.dataset_episodes == 0:
        return FAILED
    return 0


if __name__ == "__main__":
    sys.exit(main())
