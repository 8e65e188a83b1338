"""Baselines: the scripted expert and a random policy on every benchmark variant.

    python benchmarks/bench_suite.py [--episodes 10] [--workers 2] [--image-size 64] [--variants tracking,tracking-fast]

Runs ``colorsort.benchmark.evaluate.evaluate`` for each (policy, variant) pair on the variant's fixed
evaluation seeds, the pairs spread over worker processes, and prints one Markdown table row per
pair (what README's baseline table shows). Camera size does not change what these two policies
do (the expert takes its own 128 px sensor photo), so small images keep it fast.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import evaluate  # noqa: E402
from colorsort.benchmark.metrics import EvalReport  # noqa: E402
from colorsort.results import recorded
from colorsort.variants import VARIANTS  # noqa: E402


def run(job: tuple[str, str, int, int]) -> EvalReport:
    policy, variant, episodes, size = job
    return evaluate(policy, variant, episodes, image_size=(size, size), progress=False)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--image-size", type=int, default=64)
    p.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated variant names (default: all)")
    args = p.parse_args()
    variants = args.variants.split(",")
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        p.error(f"unknown variant(s) {unknown}; valid variants: {list(VARIANTS)}")
    jobs = [(policy, v, args.episodes, args.image_size) for v in variants for policy in ("expert", "random")]
    with mp.get_context("spawn").Pool(args.workers) as pool:
        reports = pool.map(run, jobs, chunksize=1)
    print(f"{args.episodes} episodes per row, seeds {reports[0].seeds[0]}..{reports[0].seeds[-1]}\n")
    print("| variant | policy | success rate (95% CI) | correct | misplaced | dropped | distractors let through "
          "| boxes/min | mean cycle [s] |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in reports:
        lo, hi = r.success_ci95
        cycle = f"{r.mean_cycle_time_s:.2f}" if r.mean_cycle_time_s is not None else "-"
        rate = f"{100 * r.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%)"
        print(f"| {r.variant} | {r.policy} | {rate} | {r.correct} "
              f"| {r.misplaced} | {r.dropped} | {r.distractors_let_through}/{r.distractors} | {r.boxes_per_minute:.1f} "
              f"| {cycle} |")


if __name__ == "__main__":
    with recorded(__file__):
        main()
