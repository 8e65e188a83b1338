"""A held-out sweep's cost: the local executor against a local Ray cluster, side by side, and the full protocol's time.

    python benchmarks/bench_sweep.py [--policy baselines/act-camera-snapshot] [--variant default] [--episodes 2]
                                     [--levels 2] [--envs 2] [--repeats 2]

Runs ``colorsort-eval --sweep``'s arms (the control and every shift at ``--levels``, ``--episodes`` an arm, on the
shift seeds) with ``--executor local`` and ``--executor ray``, ``--envs`` at once each, alternating, ``--repeats``
times; prints each run's wall time and episodes per minute, Ray's time over local's (median and range), whether both
gave the same episodes, and what the protocol's whole sweep (50 episodes at level 2 and for the control, 20 at levels
1 and 3) would take at each executor's measured rate. Wall time includes starting the workers (and Ray's cluster)
and building their envs and policies, as a user sees. The projection is an upper bound where the sample is small:
a sweep pays its start-up once (workers, Ray's cluster, each worker's env and policy), so a longer one runs more
episodes a minute. It assumes the sample's mix of episodes: a stalled episode (one that runs to the time limit)
costs the most, so a policy that stalls more on the other levels takes longer.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import observation_settings  # noqa: E402
from colorsort.benchmark.shift_sweep import run_sweep, sweep_arms  # noqa: E402
from colorsort.executors.base import ExecutorConfig  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded  # noqa: E402

PROTOCOL = sweep_arms(50, 20)  # docs/shifts.md: 50 episodes at level 2 and for the control, 20 at levels 1 and 3


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", default="baselines/act-camera-snapshot", help="expert, random or a checkpoint folder")
    p.add_argument("--variant", default="default")
    p.add_argument("--episodes", type=int, default=2, help="episodes an arm")
    p.add_argument("--levels", default="2", help="comma-separated levels to sweep (the control always runs)")
    p.add_argument("--envs", type=int, default=2, help="episodes at once, each executor")
    p.add_argument("--repeats", type=int, default=2)
    args = p.parse_args()
    quiet_robosuite_info()
    cameras, size = observation_settings(args.policy, None, None)
    arms = sweep_arms(args.episodes, args.episodes, tuple(int(x) for x in args.levels.split(",")))
    n = sum(a.episodes for a in arms)
    print(f"{args.policy} on '{args.variant}': {len(arms)} arms (the control and every shift at level {args.levels}), "
          f"{args.episodes} episodes each, {n} episodes a run, {args.envs} envs, {os.cpu_count()} CPU cores")
    seconds: dict[str, list[float]] = {"local": [], "ray": []}
    episodes: dict[str, list] = {}
    for repeat in range(args.repeats):
        for name in seconds:
            start = time.perf_counter()
            reports = run_sweep(args.policy, args.variant, arms, image_size=size, cameras=cameras,
                                executor=ExecutorConfig(name, args.envs), progress=False)
            seconds[name].append(time.perf_counter() - start)
            episodes[name] = [r.per_episode for r in reports]
            print(f"  {name:<6} (repeat {repeat + 1}): {seconds[name][-1]:6.1f} s, "
                  f"{60 * n / seconds[name][-1]:5.1f} episodes/min")
    print(f"\n{'executor':<10}{'wall [s] (median)':>19}{'episodes/min':>14}{'range':>13}"
          f"{'the protocol':>15}")
    full = sum(a.episodes for a in PROTOCOL)
    for name, times in seconds.items():
        rates = [60 * n / t for t in times]
        print(f"{name:<10}{statistics.median(times):>19.1f}{statistics.median(rates):>14.1f}"
              f"{f'{min(rates):.1f}-{max(rates):.1f}':>13}{f'{full / statistics.median(rates):.0f} min':>15}")
    ratios = [r / loc for r, loc in zip(seconds["ray"], seconds["local"], strict=True)]
    print(f"ray / local wall time: {statistics.median(ratios):.2f}x (range {min(ratios):.2f}-{max(ratios):.2f}x)")
    print(f"the protocol's sweep: {len(PROTOCOL)} arms, {full} episodes; projected at each executor's median rate")
    print(f"same episodes with both executors: {episodes['local'] == episodes['ray']}")


if __name__ == "__main__":
    with recorded(__file__):
        main()
