"""Evaluation speed: episodes per minute of ``colorsort-eval`` at batch size 1 and N, per policy, side by side.

    python benchmarks/bench_eval.py [--policies expert,baselines/act-state,baselines/act-camera-tracking@tracking]
                                    [--variant default] [--episodes 16] [--envs 2] [--batch-sizes 1,8]
                                    [--repeats 2] [--lerobot 0]

For each policy (``POLICY@VARIANT`` runs it on another variant than ``--variant``), runs
``colorsort.benchmark.evaluate.run_evaluation`` on ``--envs`` local workers at each of ``--batch-sizes`` (cells a
worker steps together, one batched policy forward a control step), alternating, ``--repeats`` times each, on the
same seeds, and prints the wall time, episodes per minute and the speed-up over the first batch size (median and
range over the repeats), how many episodes end the same (outcome, boxes right, steps) as at the first batch size,
and each batch size's success rate with its 95% interval. Wall time includes starting the workers and building
their envs and policies, as a user sees. With ``--lerobot E``, LeRobot's own ``lerobot-eval`` runs ``E`` episodes
of each checkpoint at ``--eval.batch_size`` 1 and the largest of ``--batch-sizes`` (its asynchronous vector env,
as it defaults to), timed the same way.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import observation_settings, run_evaluation  # noqa: E402
from colorsort.benchmark.metrics import EvalReport  # noqa: E402
from colorsort.benchmark.policies import checkpoint_cameras  # noqa: E402
from colorsort.executors.base import ExecutorConfig  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded  # noqa: E402
from colorsort.variants import get_variant  # noqa: E402


def outcome(episode: dict) -> tuple:
    """What an episode's outcome is compared on: how it ended, boxes right, misplaced, dropped, and its steps."""
    return episode["ended"], episode["correct"], episode["misplaced"], episode["dropped"], episode["steps"]


def rate_range(times: list[float], episodes: int) -> str:
    rates = [60 * episodes / t for t in times]
    return f"{statistics.median(rates):>14.1f}{f'{min(rates):.1f}-{max(rates):.1f}':>14}"


def bench(policy: str, variant: str, episodes: int, envs: int, sizes: list[int], repeats: int) -> None:
    cameras, size = observation_settings(policy, None, None)
    seconds: dict[int, list[float]] = {n: [] for n in sizes}
    reports: dict[int, EvalReport] = {}
    for _ in range(repeats):
        for n in sizes:
            start = time.perf_counter()
            reports[n] = run_evaluation(policy, [variant], episodes, image_size=size, cameras=cameras, progress=False,
                                        executor=ExecutorConfig(workers=envs), batch_size=n).reports[0]
            seconds[n].append(time.perf_counter() - start)
    seen = f"cameras {'+'.join(cameras)} at {size[0]} px" if cameras else "no cameras"
    print(f"\n{policy} on '{variant}', {episodes} episodes, {seen}, {envs} workers, {os.cpu_count()} CPU cores, "
          f"{repeats} repeats")
    print(f"{'batch':<7}{'wall [s] (median)':>18}{'episodes/min':>14}{'range':>14}{'speed-up':>10}{'range':>13}"
          f"{'same outcome':>14}{'success (95% CI)':>24}")
    ref = sizes[0]
    for n in sizes:
        ratios = [a / b for a, b in zip(seconds[ref], seconds[n], strict=True)]
        same = sum(outcome(a) == outcome(b) for a, b in zip(reports[ref].per_episode, reports[n].per_episode,
                                                             strict=True))
        lo, hi = reports[n].success_ci95
        print(f"{n:<7}{statistics.median(seconds[n]):>18.1f}{rate_range(seconds[n], episodes)}"
              f"{statistics.median(ratios):>9.2f}x{f'{min(ratios):.2f}-{max(ratios):.2f}x':>13}"
              f"{f'{same}/{episodes}':>14}{f'{reports[n].success_rate:.0%} ({lo:.0%}-{hi:.0%})':>24}")


def bench_lerobot(policy: str, variant: str, episodes: int, sizes: list[int], repeats: int) -> None:
    """``lerobot-eval`` on the same variant at ``--eval.batch_size`` 1 and the largest of ``sizes``."""
    cameras, size = checkpoint_cameras(policy)
    task = get_variant(variant).gym_id.partition("/")[2]
    exe = Path(sys.executable).with_name("lerobot-eval")
    seconds: dict[int, list[float]] = {n: [] for n in (1, max(sizes))}
    for _ in range(repeats):
        for n in seconds:
            with tempfile.TemporaryDirectory() as out:
                argv = [str(exe), "--env.type=colorsort", f"--env.task={task}",
                        f"--env.cameras={','.join(cameras) or 'none'}", f"--policy.path={policy}",
                        "--policy.device=cpu", f"--eval.n_episodes={episodes}", f"--eval.batch_size={n}",
                        f"--output_dir={out}/eval"]
                if size is not None:
                    argv.append(f"--env.image_size={size[0]}")
                start = time.perf_counter()
                done = subprocess.run(argv, capture_output=True, text=True)
                seconds[n].append(time.perf_counter() - start)
                if done.returncode != 0:
                    raise RuntimeError(f"{' '.join(argv)} exited {done.returncode}:\n{done.stderr[-3000:]}")
    print(f"lerobot-eval, the same policy and variant, {episodes} episodes (its asynchronous vector env):")
    for n, times in seconds.items():
        ratios = [a / b for a, b in zip(seconds[1], times, strict=True)]
        print(f"  --eval.batch_size={n:<3} wall {statistics.median(times):6.1f} s, episodes/min"
              f"{rate_range(times, episodes)}, speed-up {statistics.median(ratios):.2f}x")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policies", default="expert", help="comma-separated: expert, random or checkpoint folders, "
                                                        "each optionally @VARIANT")
    p.add_argument("--variant", default="default")
    p.add_argument("--episodes", type=int, default=16)
    p.add_argument("--envs", type=int, default=2, help="local worker processes")
    p.add_argument("--batch-sizes", default="1,8", help="comma-separated; the first is the reference")
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--lerobot", type=int, default=0, help="episodes of lerobot-eval per checkpoint (0: none)")
    args = p.parse_args()
    quiet_robosuite_info()
    sizes = [int(n) for n in args.batch_sizes.split(",")]
    for item in args.policies.split(","):
        policy, _, variant = item.partition("@")
        bench(policy, variant or args.variant, args.episodes, args.envs, sizes, args.repeats)
        if args.lerobot and policy not in ("expert", "random"):
            bench_lerobot(policy, variant or args.variant, args.lerobot, sizes, args.repeats)


if __name__ == "__main__":
    with recorded(__file__):
        main()
