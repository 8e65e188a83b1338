"""Speed of recording: the real-time factor of colorsort-collect with 1 and with 2 workers, side by side.

    python benchmarks/bench_collect.py [--episodes 24] [--cameras scene,wrist] [--image-size 128] [--fps 20]

Records the same episodes (seeds 0..N-1, one box each, the expert) twice into temporary
folders: once with one worker, once with two. Prints for each the simulated seconds recorded
per wall-clock second (start-up, merging and everything else included), the ratio of the two,
and where the workers' time went: the expert, physics and control, rendering, handing frames to
LeRobot (its streaming encoder compresses them in a thread meanwhile), saving episodes (finishing
the videos, parquet, statistics), start-up and merging.
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.cli.args import parse_image_size  # noqa
from colorsort.data.collect import CollectSummary, collect  # noqa
from colorsort.data.config import CollectConfig  # noqa: E402
from colorsort.executors.base import ExecutorConfig  # noqa: E402
from colorsort.results import recorded


def run(config: CollectConfig) -> CollectSummary:
    summary = collect(config, progress=True, log=lambda _: None)
    if summary.errors or summary.kept != config.episodes:
        raise SystemExit(f"recording failed: kept {summary.kept}/{config.episodes}, errors {summary.errors}")
    return summary


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--episodes", type=int, default=24)
    p.add_argument("--cameras", default="scene,wrist")
    p.add_argument("--image-size", default="128")
    p.add_argument("--fps", type=int, default=20)
    p.add_argument("--vcodec", default="h264")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = CollectConfig(episodes=args.episodes, cameras=tuple(args.cameras.split(",")),
                             image_size=parse_image_size(args.image_size), fps=args.fps, vcodec=args.vcodec,
                             out=str(Path(tmp) / "w1"))
        before = resource.getrusage(resource.RUSAGE_SELF)
        one = run(base)
        after = resource.getrusage(resource.RUSAGE_SELF)
        cores = (after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime) / one.wall_s
        two = run(replace(base, executor=ExecutorConfig(workers=2), out=str(Path(tmp) / "w2")))
        size = one.size_mb

    h, w = base.image_size
    print(f"\n{args.episodes} one-box episodes, {len(base.cameras)} cameras ({','.join(base.cameras)}) at {h}x{w}, "
          f"{base.fps} fps, {base.vcodec}, {os.cpu_count()} CPU cores")
    print(f"{'workers':>8} {'sim s':>8} {'wall s':>8} {'real-time factor':>17}")
    for n, s in ((1, one), (2, two)):
        print(f"{n:>8} {s.sim_time_s:8.1f} {s.wall_s:8.1f} {s.real_time_factor:16.2f}x")
    print(f"2 workers / 1 worker: {two.real_time_factor / one.real_time_factor:.2f}x")
    print(f"1 worker kept {cores:.2f} cores busy on average (CPU time / wall time: its video encoder runs in "
          f"threads), so {os.cpu_count()} cores allow at most {os.cpu_count() / cores:.2f}x with more workers")
    print(f"dataset: {one.dataset_frames} frames, {size:.1f} MB ({1e3 * size / one.dataset_frames:.1f} kB per frame)")

    print("\nwhere the time goes [s, summed over workers]")
    print(f"{'stage':<22} {'1 worker':>10} {'2 workers':>10}")
    for key in one.seconds:
        print(f"{key:<22} {one.seconds[key]:10.2f} {two.seconds.get(key, 0.0):10.2f}")
    for label, s, n in (("1 worker", one, 1), ("2 workers", two, 2)):
        staged = sum(v for k, v in s.seconds.items() if k != "merging") / n + s.seconds.get("merging", 0.0)
        print(f"{label}: {s.wall_s - staged:.1f} s of the wall time is outside those stages "
              f"(importing lerobot and torch, starting processes)")


if __name__ == "__main__":
    with recorded(__file__):
        main()
