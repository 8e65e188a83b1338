"""Scaling collection and evaluation: local processes against a local Ray cluster, the merge's cost,
and the speed-up projected from them.

    python benchmarks/bench_scale.py [--episodes 8] [--repeats 2] [--eval-episodes 6]

1. Recording: the same episodes (seeds 0..N-1, the expert, one box each, scene and wrist at
   128 px) with 1 and 2 workers, on local processes and on a Ray cluster that each run starts
   on this machine (its start-up included: the engine's overhead), alternated, ``--repeats``
   times; the real-time factor of each (simulated seconds recorded per wall-clock second).
2. The merge: one-episode and many-episode shards recorded once, then merged in several
   combinations with LeRobot's ``aggregate_datasets``; a least-squares fit of the merge's wall
   time to ``a + b * shards + c * episodes``.
3. Projection: recording 20,000 episodes in shards of 32 on 8, 64 and 512 workers, from the
   one-worker recording speed, the per-shard start-up and the merge fit (the merge runs once, on
   one process: what stays serial). Measured on this machine; a cluster's nodes differ.
4. Evaluation: expert episodes per minute on the default variant with 1 and 2 workers, local and Ray.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

import numpy as np  # noqa: E402

from colorsort.benchmark.evaluate import evaluate  # noqa: E402
from colorsort.data.collect import CollectSummary, collect  # noqa: E402
from colorsort.data.config import CollectConfig  # noqa: E402
from colorsort.data.shards import merge_in_child  # noqa: E402
from colorsort.executors.base import ExecutorConfig  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded

SETUPS = (("local", 1), ("local", 2), ("ray", 1), ("ray", 2))


def record(config: CollectConfig) -> CollectSummary:
    summary = collect(config, progress=False, log=lambda _: None)
    if summary.errors or summary.kept != config.episodes:
        raise SystemExit(f"recording failed: kept {summary.kept}/{config.episodes}, errors {summary.errors}")
    return summary


def recording(base: CollectConfig, repeats: int, tmp: Path) -> dict[tuple[str, int], list[CollectSummary]]:
    runs: dict[tuple[str, int], list[CollectSummary]] = {s: [] for s in SETUPS}
    for r in range(repeats):
        for executor, workers in SETUPS:
            out = tmp / f"{executor}-{workers}-{r}"
            config = replace(base, executor=ExecutorConfig(executor, workers), out=str(out))
            runs[executor, workers].append(record(config))
            print(f"  {executor} x{workers} (repeat {r + 1}): {runs[executor, workers][-1].real_time_factor:.2f}x")
    return runs


def staged_shards(base: CollectConfig, tmp: Path, episodes: int, shard_size: int) -> list[Path]:
    """Finished shards of ``shard_size`` episodes, kept: recorded with collect's own shard task."""
    from colorsort.data.shards import ShardJob
    from colorsort.data.shards import record as record_shard
    from colorsort.executors.base import chunks

    class Ctx:
        def send(self, m):
            pass

        def stopping(self):
            return False

    roots = []
    for block in chunks(list(range(episodes)), shard_size):
        root = tmp / f"shards-{shard_size}" / f"shard-{block[0]:06d}"
        root.parent.mkdir(parents=True, exist_ok=True)
        record_shard(ShardJob(base, tuple(block), str(root), "bench"), Ctx())
        roots.append(root)
    return roots


def merge_fit(base: CollectConfig, tmp: Path) -> tuple[np.ndarray, list[tuple[int, int, float]]]:
    """[a, b, c] of merge seconds = a + b * shards + c * episodes, and the points it was fitted to."""
    ones = staged_shards(base, tmp, 16, 1)
    eights = staged_shards(base, tmp, 16, 8)
    points = []
    for k, sources in enumerate([ones[:2], ones[:4], ones[:8], ones, eights[:1] + ones[8:10], eights]):
        t = time.perf_counter()
        merge_in_child(sources, tmp / f"merged-{k}", base.repo_id)
        episodes = sum(8 if s in eights else 1 for s in sources)
        points.append((len(sources), episodes, time.perf_counter() - t))
    a = np.array([[1.0, s, e] for s, e, _ in points])
    coef, *_ = np.linalg.lstsq(a, np.array([t for *_, t in points]), rcond=None)
    return coef, points


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--eval-episodes", type=int, default=6)
    args = p.parse_args()
    quiet_robosuite_info()
    base = CollectConfig(episodes=args.episodes)
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        print(f"1. recording {args.episodes} one-box episodes, scene and wrist at 128 px, {os.cpu_count()} CPU cores")
        runs = recording(base, args.repeats, tmp)
        print("2. merging")
        coef, points = merge_fit(base, tmp)

    print(f"\nrecording {args.episodes} episodes, real-time factor (median of {args.repeats}, range):")
    one = statistics.median(s.real_time_factor for s in runs["local", 1])
    for (executor, workers), summaries in runs.items():
        f = [s.real_time_factor for s in summaries]
        print(f"  {executor:<6} {workers} worker{'s' * (workers > 1)}: {statistics.median(f):5.2f}x "
              f"({min(f):.2f}-{max(f):.2f})   {statistics.median(f) / one:4.2f} of local x1   "
              f"wall {statistics.median(s.wall_s for s in summaries):5.1f} s")
    print("\nmerge (aggregate_datasets, in a child process): shards, episodes, seconds")
    for s, e, t in points:
        print(f"  {s:>3} {e:>3} {t:6.2f}")
    print(f"  fit: {coef[0]:.2f} s + {coef[1]:.3f} s per shard + {coef[2]:.3f} s per episode")

    # Projection from the one-worker local runs: per-episode recording time and per-shard start-up.
    local1 = runs["local", 1]
    setup = statistics.median(s.seconds["setup"] for s in local1)
    per_episode = statistics.median((s.wall_s - s.seconds["merging"] - s.seconds["setup"]) / s.kept for s in local1)
    n, k = 20_000, 32
    shards = -(-n // k)
    merge_s = coef[0] + coef[1] * shards + coef[2] * n
    ray_start = statistics.median(s.wall_s for s in runs["ray", 1]) - statistics.median(s.wall_s for s in local1)
    serial = max(ray_start, 0.0) + merge_s
    t1 = shards * (setup + k * per_episode) + merge_s
    print(f"\nprojection: {n} episodes in shards of {k}: {per_episode:.2f} s per episode, {setup:.2f} s start-up "
          f"per shard, merge {merge_s / 60:.1f} min and Ray's start-up {max(ray_start, 0):.0f} s stay serial")
    print(f"  {'workers':>7} {'hours':>7} {'speed-up':>9}")
    for w in (1, 8, 64, 512):
        t = -(-shards // w) * (setup + k * per_episode) + serial
        print(f"  {w:>7} {t / 3600:7.2f} {t1 / t:9.1f}")

    print(f"\nevaluation: the expert on default, {args.eval_episodes} episodes")
    for executor, workers in SETUPS:
        t = time.perf_counter()
        evaluate("expert", "default", args.eval_episodes, image_size=(128, 128), progress=False,
                 executor=ExecutorConfig(executor, workers))
        minutes = (time.perf_counter() - t) / 60
        rate = args.eval_episodes / minutes
        print(f"  {executor:<6} {workers} worker{'s' * (workers > 1)}: {rate:5.1f} episodes/min")


if __name__ == "__main__":
    with recorded(__file__):
        main()
