"""Record DAgger's labels: a learned policy drives each episode, the expert takes over and finishes it.

Example::

    colorsort-takeover --policy baselines/act-state --variant default --episodes 2 --handover 30,60 \\
        --out datasets/labels

Episode ``i`` runs with env seed ``seed + i`` (from 40,000 by default, apart from the demos', evaluation's and
validation's seeds). The policy acts for a number of steps drawn from ``--handover`` (from the episode's seed),
with the cameras and image size it was trained on; then the expert plans from whatever state the cell is in
(``Expert.take_over``) and finishes the episode. Every frame from the handover on is stored with the expert's
action, and an episode is kept when every box ended where it belongs. The frames carry their own task text and
``meta/takeover.json`` says which policy, seeds and handovers made them, so they stay told apart after a merge
with demos (``colorsort-baseline --dagger.rounds=N`` runs rounds of this). An existing dataset is never
overwritten.

Exit status: 0 done, 1 no episode kept, 2 bad arguments, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from colorsort.cli.run import guarded
from colorsort.data.config import VCODECS
from colorsort.errors import FAILED, ConfigError
from colorsort.expert.config import parse_changes
from colorsort.logs import quiet_robosuite_info
from colorsort.training.takeover import TAKEOVER_SEED, TakeoverConfig, record_takeovers


def parse_handover(text: str) -> tuple[int, int]:
    """``"20,200"`` -> (20, 200); ``"50"`` -> (50, 50)."""
    try:
        steps = [int(t) for t in text.split(",")]
    except ValueError:
        raise ConfigError(f"--handover {text!r}: give FIRST,LAST steps (or one number)") from None
    if len(steps) not in (1, 2):
        raise ConfigError(f"--handover {text!r}: give FIRST,LAST steps (or one number)")
    return steps[0], steps[-1]


def parse_args(argv: list[str]) -> TakeoverConfig:
    """``argv`` as ``colorsort-takeover``'s configuration; ``--help`` prints every flag and exits."""
    parser = argparse.ArgumentParser(prog="colorsort-takeover", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", required=True, help="a LeRobot checkpoint (pretrained_model folder)")
    parser.add_argument("--out", required=True, help="a new dataset folder")
    parser.add_argument("--variant", default="default", help="the benchmark variant played (colorsort-eval --list)")
    parser.add_argument("--episodes", type=int, default=10, help="episodes played")
    parser.add_argument("--handover", default="20,200", help="FIRST,LAST: the policy's steps before the expert's")
    parser.add_argument("--seed", type=int, default=TAKEOVER_SEED, help="env seed of the first episode")
    parser.add_argument("--repo-id", default="local/colorsort-takeover", help="the dataset's LeRobot repo id")
    parser.add_argument("--vcodec", default=TakeoverConfig.vcodec,
                        help=f"video codec, one of {VCODECS}: the demos' (colorsort-collect --vcodec)")
    parser.add_argument("--expert", default=None, metavar="NAME:VALUE,...",
                        help="the expert's settings changed from its belt's preset, as colorsort-collect's --expert "
                             "(give the demos' own)")
    parser.add_argument("--no-turn", action="store_true",
                        help="the expert keeps the cup at its home yaw over a turned box, as colorsort-collect's "
                             "--no-turn (give it where the demos had it)")
    args = parser.parse_args(argv)
    return TakeoverConfig(policy=args.policy, out=args.out, variant=args.variant, episodes=args.episodes,
                          handover=parse_handover(args.handover), seed=args.seed, repo_id=args.repo_id,
                          vcodec=args.vcodec, expert=parse_changes(args.expert) if args.expert else (),
                          turn_to_box=not args.no_turn)


@guarded("colorsort-takeover")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(sys.argv[1:] if argv is None else argv)
    summary = record_takeovers(config)
    print(f"kept {len(summary.kept)} of {config.episodes} episodes, {summary.frames} expert-labelled frames "
          f"-> {summary.root}")
    for seed, why in summary.failed.items():
        print(f"  seed {seed} (handed over at step {summary.handed_over_at[seed]}): {why}")
    return 0 if summary.kept else FAILED
