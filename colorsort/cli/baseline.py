"""Rebuild a learned baseline: expert demos -> ``lerobot-train`` -> ``colorsort-eval`` -> table, plots, shipped policy.

Example::

    colorsort-baseline --recipe camera                 # the camera policy: about 1 h 40 min on 2 CPU cores
    colorsort-baseline --recipe camera-tracking --ship baselines/act-camera-tracking  # 3 seeds: about 3 h 30 min
    colorsort-baseline --recipe state --demos 8,40 --steps 2500
    colorsort-baseline --list

Every stage is a documented command, run as a subprocess with its command line printed:
``colorsort-collect`` for each training variant (merged with LeRobot's ``aggregate_datasets``; a
camera recipe's set then loses ``observation.environment_state`` with ``remove_feature``),
``lerobot-train`` (ACT or diffusion), and ``colorsort-eval`` on the variants' fixed evaluation seeds,
with the learning curve from the checkpoints saved along the way. It prints a Markdown table and
writes ``OUT/results.json``, ``OUT/success_vs_demos.png`` and ``OUT/learning_curve.png``.
``--ship DIR`` copies the largest set's ``pretrained_model`` to DIR with ``scores.json``, the plots
and a README of how it was made.

Finished stages under OUT (a dataset with its marker, a training run with its last checkpoint,
an evaluation's JSON) are reused, so an interrupted run goes on where it stopped and ``--until``
splits the work into sittings; ``--fresh`` starts over. A merged demo set from another ``--train-variants``
mix is refused (exit 2), never trained on.
Exit status 0 done, 1 a stage failed, 2 bad arguments or an OUT holding another mix's demos.
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import sys
from dataclasses import replace
from pathlib import Path

from colorsort.cli.args import parse_range
from colorsort.cli.run import guarded
from colorsort.errors import ConfigError, DataExistsError
from colorsort.training.pipeline import UNTIL, RunSettings, run_pipeline
from colorsort.training.policy_settings import LR_SCHEDULES, ActSettings
from colorsort.training.recipes import RECIPES, get_recipe


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="colorsort-baseline", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--recipe", default="state", help=f"the preset to start from, one of {list(RECIPES)}")
    p.add_argument("--list", action="store_true", help="print the recipes and exit")
    p.add_argument("--demos", help="increasing demo counts, comma-separated")
    p.add_argument("--train-variants", help="variants the demos come from, comma-separated, each optionally "
                                            "VARIANT:WEIGHT (default: the recipe's mix)")
    p.add_argument("--boxes-per-episode", type=int)
    p.add_argument("--late-pass", type=int, help="colorsort-collect's --late-pass for the demos [control steps]")
    p.add_argument("--late-pick", type=int, help="colorsort-collect's --late-pick for the demos [control steps]")
    p.add_argument("--no-turn", action="store_true",
                   help="demos in which the expert keeps the cup's home yaw over a turned box (colorsort-collect's)")
    p.add_argument("--steps", type=int, help="training updates for the largest set")
    p.add_argument("--small-steps", type=int, help="training updates for the smaller sets")
    p.add_argument("--passes", type=float, help="train every set for this many passes over its frames instead")
    p.add_argument("--seeds", help="lerobot-train seeds, comma-separated: every set is trained once per seed")
    p.add_argument("--batch-size", type=int)
    p.add_argument("--lr-schedule", help=f"the learning rate over training, one of {list(LR_SCHEDULES)}")
    p.add_argument("--lr", type=float,
                   help="ACT's learning rate, its backbone's too (the recipe's: 1e-4, camera-snapshot's 3e-4)")
    p.add_argument("--save-every", type=int, help="updates between learning-curve checkpoints (0: none)")
    p.add_argument("--select-episodes", type=int,
                   help="score the checkpoint that does best on this many validation episodes of each training "
                        "variant (0: the last)")
    p.add_argument("--eval-variants", help="variants the largest set's policy is scored on, comma-separated")
    p.add_argument("--eval-episodes", type=int, help="evaluation episodes on the main variant")
    p.add_argument("--other-episodes", type=int, help="evaluation episodes on the other variants")
    p.add_argument("--curve-episodes", type=int, help="evaluation episodes per learning-curve checkpoint")
    p.add_argument("--episode-length", type=int, help="evaluation steps before truncation")
    p.add_argument("--cameras", help="'none' (a state policy) or comma-separated cameras")
    p.add_argument("--image-size", type=int, help="camera images [px], square")
    p.add_argument("--image-shift", type=float, help="random shifts of training images, up to this fraction "
                                                     "of their size (0: off)")
    p.add_argument("--relight", action="store_true", default=None,
                   help="relight every training image at random as the lighting variant does "
                        "(brightness, warm to cold)")
    p.add_argument("--demo-brightness",
                   help="LO,HI: the lighting demos collected under lights of this brightness [x the cell's] "
                        "instead of the variant's 0.5-1.6, e.g. 0.5,0.9 (dim)")
    p.add_argument("--device", help="lerobot-train's device: cpu, cuda or mps")
    p.add_argument("--workers", type=int, default=2, help="collection processes")
    p.add_argument("--envs", type=int, default=2, help="evaluation processes")
    p.add_argument("--out", help="working folder (default outputs/baselines/<recipe>)")
    p.add_argument("--until", default="eval", choices=UNTIL, help="the last stage to run")
    p.add_argument("--ship", help="copy the largest set's policy here with its scores and a README")
    p.add_argument("--fresh", action="store_true", help="delete OUT first instead of reusing its finished stages")
    return p.parse_args(argv)


def overrides(args: argparse.Namespace) -> dict:
    """The Recipe fields the command line sets."""
    found: dict = {}
    if args.demos:
        found["demos"] = tuple(int(x) for x in args.demos.split(","))
    if args.train_variants:
        pairs = [item.partition(":") for item in args.train_variants.split(",")]
        found["train_mix"] = tuple((v, float(w) if w else 1.0) for v, _, w in pairs)
    if args.seeds:
        found["seeds"] = tuple(int(x) for x in args.seeds.split(","))
    if args.eval_variants:
        found["eval_variants"] = tuple(args.eval_variants.split(","))
    if args.cameras:
        found["cameras"] = () if args.cameras == "none" else tuple(args.cameras.split(","))
    if args.no_turn:
        found["turn_to_box"] = False
    if args.lr_schedule or args.lr is not None:
        policy = get_recipe(args.recipe).policy
        if not isinstance(policy, ActSettings):
            raise ConfigError(f"--lr and --lr-schedule set ACT's learning rate; recipe {args.recipe!r} trains "
                             f"{policy.name}, which keeps LeRobot's")
        if args.lr_schedule:
            policy = replace(policy, lr_schedule=args.lr_schedule)
        if args.lr is not None:
            policy = replace(policy, optimizer_lr=args.lr, optimizer_lr_backbone=args.lr)
        found["policy"] = policy
    for key in ("boxes_per_episode", "late_pass", "late_pick", "steps", "small_steps", "passes", "batch_size",
                "save_every", "select_episodes", "eval_episodes", "other_episodes", "curve_episodes", "episode_length",
                "image_size", "image_shift", "device"):
        if getattr(args, key) is not None:
            found[key] = getattr(args, key)
    if args.relight:
        found["image_relight"] = True
    if args.demo_brightness:
        found["demo_brightness"] = parse_range(args.demo_brightness)
    return found


@guarded("colorsort-baseline")
def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.list:
        width, label_width = max(map(len, RECIPES)), max(len(r.label) for r in RECIPES.values())
        for r in RECIPES.values():
            length = f"{r.passes:g} passes" if r.passes else f"{r.steps} updates"
            seeds = f"{len(r.seeds)} seed" + ("s" if len(r.seeds) > 1 else "")
            print(f"{r.name:<{width}}  {r.label:<{label_width}} demos {','.join(map(str, r.demos))} from "
                  f"{'+'.join(r.train_variants)}, {length} x {seeds} on {r.device}")
        return 0
    recipe = get_recipe(args.recipe, **overrides(args))  # a bad number in --demos or a weight is a ValueError too
    settings = RunSettings(Path(args.out or f"outputs/baselines/{recipe.name}"), args.workers, args.envs, args.until)
    ship_to = Path(args.ship) if args.ship else None
    if ship_to and ship_to.exists() and any(ship_to.iterdir()):
        raise DataExistsError(f"{ship_to} exists: remove it first, or ship elsewhere")
    if args.fresh:
        shutil.rmtree(settings.out, ignore_errors=True)
    run_pipeline(recipe, settings, shlex.join(["colorsort-baseline", *argv]), ship_to)  # DataConflictError: OUT
    # holds a stage of other settings, nothing overwritten
    return 0


if __name__ == "__main__":
    sys.exit(main())
