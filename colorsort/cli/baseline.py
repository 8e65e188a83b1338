"""Rebuild a learned baseline: expert demos -> ``lerobot-train`` -> ``colorsort-eval`` -> table, plots, shipped policy.

Example::

    colorsort-baseline --recipe camera                 # the camera policy: about 1 h 40 min on 2 CPU cores
    colorsort-baseline --recipe camera-tracking --ship baselines/act-camera-tracking  # 3 seeds: about 3 h 30 min
    colorsort-baseline --recipe state --demos.counts=8,40 --training.steps=2500
    colorsort-baseline --recipe camera-snapshot --demos.late_pick=30 --policy.optimizer_lr=1e-4
    colorsort-baseline --list
    colorsort-baseline --recipe camera --help           # every flag, with camera's values

Every field of the recipe is a flag ``--<section>.<field>=<value>`` (sections ``demos``, ``policy``,
``training``, ``evaluation``; ``colorsort.training.flags``), generated from the recipe's dataclasses, and
``--help`` shows each with the chosen recipe's value. Every stage is a documented command, run as a
subprocess with its command line printed: ``colorsort-collect`` for each training variant (merged with
LeRobot's ``aggregate_datasets``; a camera recipe's set then loses ``observation.environment_state`` with
``remove_feature``), ``lerobot-train`` (ACT or diffusion), and ``colorsort-eval`` on the variants' fixed
evaluation seeds, with the learning curve from the checkpoints saved along the way. It prints a Markdown
table and writes ``OUT/results.json``, ``OUT/success_vs_demos.png`` and ``OUT/learning_curve.png``.
``--ship DIR`` copies the largest set's ``pretrained_model`` to DIR with ``scores.json``, the plots and a
README of how it was made. ``--add-to DIR`` adds the run's training seeds to the baseline shipped in DIR (the
same recipe and flags but ``--training.seeds``, which names seeds it does not hold): its scores, tables and README
gain their rows, its policy stays. So a row's seeds can be trained in separate sittings, on other machines.

Finished stages under OUT are reused, each named by a key of the typed settings that feed it and the versions
of the code that made its data (``colorsort.training.cache``, ``colorsort.versions``), so an interrupted run
goes on where it stopped, ``--until`` splits the work into sittings, and a changed setting or a changed expert,
cell or recorder makes the stages it feeds anew; ``--fresh`` starts over.
Exit status 0 done, 1 a stage failed, 2 bad arguments or an OUT holding a stage of other settings.
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import sys
from pathlib import Path

from colorsort.cli.run import guarded
from colorsort.errors import ConfigError, DataExistsError
from colorsort.training.flags import add_recipe_flags, recipe_changes
from colorsort.training.pipeline import UNTIL, RunConfig, run_pipeline
from colorsort.training.publishing.ship import addable
from colorsort.training.recipes import RECIPES, Recipe, get_recipe


def parse_args(argv: list[str]) -> tuple[argparse.Namespace, Recipe]:
    """The run's arguments and the recipe they ask for: ``--recipe`` first, then that recipe's flags."""
    first = argparse.ArgumentParser(add_help=False)
    first.add_argument("--recipe", default="state")
    chosen = get_recipe(first.parse_known_args(argv)[0].recipe)
    p = argparse.ArgumentParser(prog="colorsort-baseline", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--recipe", default="state", help=f"the preset to start from, one of {list(RECIPES)}")
    p.add_argument("--list", action="store_true", help="print the recipes and exit")
    p.add_argument("--workers", type=int, default=2, help="collection processes")
    p.add_argument("--envs", type=int, default=2, help="evaluation processes")
    p.add_argument("--out", help="working folder (default outputs/baselines/<recipe>)")
    p.add_argument("--until", default="eval", choices=UNTIL, help="the last stage to run")
    p.add_argument("--ship", help="copy the largest set's policy here with its scores and a README")
    p.add_argument("--add-to", help="add this run's training seeds to the baseline shipped in this folder (the "
                   "same recipe and flags but --training.seeds); its policy stays")
    p.add_argument("--fresh", action="store_true", help="delete OUT first instead of reusing its finished stages")
    add_recipe_flags(p, chosen)
    args = p.parse_args(argv)
    return args, chosen.override(recipe_changes(args, chosen))


def describe(recipe: Recipe) -> str:
    """One line of ``--list``."""
    training, demos = recipe.training, recipe.demos
    length = f"{training.passes:g} passes" if training.passes else f"{training.steps} updates"
    seeds = f"{len(training.seeds)} seed" + ("s" if len(training.seeds) > 1 else "")
    return (f"demos {','.join(map(str, demos.counts))} from {'+'.join(demos.train_variants)}, {length} x {seeds} "
            f"on {training.device}")


@guarded("colorsort-baseline")
def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args, recipe = parse_args(argv)
    if args.list:
        width, label_width = max(map(len, RECIPES)), max(len(r.label) for r in RECIPES.values())
        for r in RECIPES.values():
            print(f"{r.name:<{width}}  {r.label:<{label_width}} {describe(r)}")
        return 0
    settings = RunConfig(Path(args.out or f"outputs/baselines/{recipe.name}"), args.workers, args.envs, args.until)
    ship_to = Path(args.ship) if args.ship else None
    add_to = Path(args.add_to) if args.add_to else None
    if ship_to and add_to:
        raise ConfigError("--ship makes a new baseline, --add-to adds seeds to a shipped one: give one of them")
    if ship_to and ship_to.exists() and any(ship_to.iterdir()):
        raise DataExistsError(f"{ship_to} exists: remove it first, ship elsewhere, or add seeds with --add-to")
    if add_to:
        addable(recipe, add_to)  # ConfigError before any work: another recipe, or seeds it holds
    if args.fresh:
        shutil.rmtree(settings.out, ignore_errors=True)
    run_pipeline(recipe, settings, shlex.join(["colorsort-baseline", *argv]), ship_to, add_to)  # DataConflictError:
    # OUT holds a stage of other settings, nothing overwritten
    return 0


if __name__ == "__main__":
    sys.exit(main())
