"""Evaluation speed: episodes per minute of ``colorsort-eval`` with 1 and 2 environments at once, per policy.

    python benchmarks/bench_eval.py [--policies expert,baselines/act-state,baselines/act-camera] [--variant default]
                               [--episodes 8] [--repeats 2]

For each policy, runs ``colorsort.benchmark.evaluate.evaluate`` with ``envs=1`` and ``envs=2`` side by
side, alternating, ``--repeats`` times each, on the same seeds, and prints wall time, episodes per
minute, the speed-up of 2 over 1 (median and range over the repeats), and checks that both give the
same numbers. A checkpoint renders the cameras it was trained on (none for a state policy); the
expert renders scene and wrist at ``--image-size``. Wall time includes starting the worker processes
and building their envs and policies, as a user sees.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import evaluate, observation_settings  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded


def bench(policy: str, variant: str, episodes: int, repeats: int, image_size: int | None) -> None:
    cameras, size = observation_settings(policy, None, image_size)
    seconds: dict[int, list[float]] = {1: [], 2: []}
    reports = {}
    for _ in range(repeats):
        for envs in (1, 2):
            start = time.perf_counter()
            reports[envs] = evaluate(policy, variant, episodes, image_size=size, cameras=cameras, progress=False,
                                     envs=envs)
            seconds[envs].append(time.perf_counter() - start)
    same = reports[1].per_episode == reports[2].per_episode
    seen = f"cameras {'+'.join(cameras)} at {size[0]} px" if cameras else "no cameras"
    print(f"\n{policy} on '{variant}', {episodes} episodes, {seen}, {os.cpu_count()} CPU cores, {repeats} repeats")
    print(f"{'envs':<6}{'wall [s] (median)':>20}{'episodes/min':>15}{'range':>18}")
    for envs, times in seconds.items():
        rates = [60 * episodes / t for t in times]
        print(f"{envs:<6}{statistics.median(times):>20.1f}{statistics.median(rates):>15.1f}"
              f"{f'{min(rates):.1f}-{max(rates):.1f}':>18}")
    ratios = [a / b for a, b in zip(seconds[1], seconds[2], strict=True)]
    print(f"2 envs / 1 env: {statistics.median(ratios):.2f}x (range {min(ratios):.2f}-{max(ratios):.2f}x)")
    print(f"same per-episode results with 1 and 2 envs: {same}; success {reports[1].success_rate:.0%}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policies", default="expert", help="comma-separated: expert, random or checkpoint folders")
    p.add_argument("--variant", default="default")
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--image-size", type=int, default=None, help="the expert's cameras [px] (default 128)")
    args = p.parse_args()
    quiet_robosuite_info()
    for policy in args.policies.split(","):
        bench(policy, args.variant, args.episodes, args.repeats, args.image_size)


if __name__ == "__main__":
    with recorded(__file__):
        main()
