"""Evaluate a policy on a benchmark variant: success rate with a confidence interval and sorting metrics.

Example::

    colorsort-eval --policy expert --variant default --episodes 50 --envs 2 --json outputs/eval.json
    colorsort-eval --policy outputs/train/act/checkpoints/last/pretrained_model --variant jitter --episodes 20
    colorsort-eval --list

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``--seed S`` + k), so the same
command gives the same numbers, whatever ``--envs`` (episodes run at once, one process each).
Metrics: success rate (every box of the episode where it belongs, none misplaced or dropped) with a 95% Wilson interval; boxes placed correctly, misplaced, dropped;
distractors (boxes with no bin) let through; boxes per minute (boxes handled right, placed in
their bin or let through, per minute of sim time); mean cycle time (sim time between consecutive
boxes handled right).
Exit status 0 when it ran, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

from colorsort.benchmark.evaluate import evaluate, observation_settings
from colorsort.benchmark.metrics import format_report
from colorsort.logs import quiet_robosuite_info
from colorsort.variants import VARIANTS, get_variant


def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    parser = argparse.ArgumentParser(prog="colorsort-eval", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", default="expert", help="expert, random, or a LeRobot checkpoint folder")
    parser.add_argument("--variant", default="default", help="a variant name (see --list)")
    parser.add_argument("--episodes", type=int, default=10, help="episodes to run")
    parser.add_argument("--seed", type=int, default=None, help="first seed (default: the variant's seeds)")
    parser.add_argument("--image-size", type=int, default=None,
                        help="square camera images [px] (default: a checkpoint's own, else 128)")
    parser.add_argument("--cameras", default=None,
                        help="comma-separated cameras or 'none' (default: those a checkpoint was trained on, "
                             "else scene,wrist)")
    parser.add_argument("--episode-length", type=int, default=None,
                        help="steps before an episode is truncated (default: the variant's time limit)")
    parser.add_argument("--envs", type=int, default=1,
                        help="episodes run at once, each in its own process (same numbers whatever N)")
    parser.add_argument("--json", default=None, help="write the metrics as JSON here")
    parser.add_argument("--list", action="store_true", help="print the variants, one per line, and exit")
    args = parser.parse_args(argv)
    if args.list:
        for v in VARIANTS.values():
            print(f"{v.name:<14} {v.gym_id:<34} {v.description}")
        return 0
    if args.episodes < 1:
        parser.error(f"--episodes {args.episodes}: give at least 1")
    if args.envs < 1:
        parser.error(f"--envs {args.envs}: give at least 1")
    try:
        get_variant(args.variant)
        cameras, image_size = observation_settings(args.policy, args.cameras, args.image_size)
        report = evaluate(args.policy, args.variant, args.episodes, args.seed, image_size, cameras,
                          episode_length=args.episode_length, envs=args.envs)
    except ValueError as err:
        print(f"colorsort-eval: error: {err}", file=sys.stderr)
        return 2
    print(format_report(report))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(asdict(report), indent=1))
        print(f"metrics: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
