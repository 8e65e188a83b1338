"""A policy on the batched cell (MuJoCo Warp) against the CPU cell, episode by episode on the same seeds.

    python benchmarks/bench_warp_agreement.py --policy baselines/act-state --episodes 50 --episode-length 600

Both backends run the variant's evaluation seeds (``--seed`` for others); the table gives each backend's
success rate with its 95% interval and boxes, then how many episodes ended the same way (success, failed,
time limit) and how many sorted the same boxes into the same bins. The batched cell runs on Warp's
``--device`` (its CPU device by default: every world at once, slowly), the CPU cell on ``--envs``
processes.
"""

from __future__ import annotations

import argparse
import sys
import time

from colorsort.results import recorded


def main() -> int:
    with recorded(__file__):
        return run()


def run() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", default="baselines/act-state")
    parser.add_argument("--variant", default="default")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--seed", type=int, default=None, help="first seed (default: the variant's evaluation seeds)")
    parser.add_argument("--episode-length", type=int, default=None, help="steps before an episode is truncated")
    parser.add_argument("--device", default="cpu", help="Warp's device for the batched cell")
    parser.add_argument("--envs", type=int, default=2, help="CPU cell processes")
    args = parser.parse_args()

    from colorsort.batched.evaluate import evaluate_batched
    from colorsort.benchmark.evaluate import evaluate, observation_settings

    cameras, size = observation_settings(args.policy, None, None)
    start = time.perf_counter()
    cpu = evaluate(args.policy, args.variant, args.episodes, seed=args.seed, cameras=cameras, image_size=size,
                   episode_length=args.episode_length, envs=args.envs, progress=False)
    cpu_s = time.perf_counter() - start
    batched = evaluate_batched(args.policy, args.variant, args.episodes, seed=args.seed, envs=args.episodes,
                               device=args.device, episode_length=args.episode_length, progress=False)
    warp, timing = batched.report, batched.timing

    def boxes(episode: dict) -> list[tuple]:
        return [(b["color"], b["outcome"], b["bin"]) for b in episode["boxes"]]

    pairs = list(zip(cpu.per_episode, warp.per_episode, strict=True))
    same_end = sum(a["ended"] == b["ended"] for a, b in pairs)
    same_boxes = sum(boxes(a) == boxes(b) for a, b in pairs)
    limit = f", episodes cut at {args.episode_length} steps" if args.episode_length else ""
    print(f"`{args.policy}` on `{args.variant}`, {args.episodes} episodes (seeds {pairs[0][0]['seed']}.."
          f"{pairs[-1][0]['seed']}){limit}; the batched cell on Warp's `{args.device}` device.\n")
    print("| backend | success (95% CI) | correct | misplaced | dropped | wall [s] |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, r, seconds in (("CPU cell", cpu, cpu_s), (f"batched cell ({args.device})", warp, timing.seconds)):
        lo, hi = r.success_ci95
        print(f"| {name} | {100 * r.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%) | {r.correct} | "
              f"{r.misplaced} | {r.dropped} | {seconds:.0f} |")
    print(f"\nEpisodes that ended the same way: {same_end} of {len(pairs)}; with the same boxes in the same bins, "
          f"in order: {same_boxes} of {len(pairs)}.")
    differ = [(a["seed"], a["ended"], b["ended"]) for a, b in pairs if a["ended"] != b["ended"]]
    if differ:
        print("Ended differently (seed: CPU, batched): " + ", ".join(f"{s}: {a}, {b}" for s, a, b in differ))
    return 0


if __name__ == "__main__":
    sys.exit(main())
