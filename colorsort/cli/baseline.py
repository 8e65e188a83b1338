"""Rebuild a learned baseline: expert demos -> ``lerobot-train`` -> ``colorsort-eval`` -> table, plots, shipped policy.

Example::

    colorsort-baseline --recipe camera                 # the camera policy: about 1 h 40 min on 2 CPU cores
    colorsort-baseline --recipe camera-tracking --ship baselines/act-camera-tracking  # 3 seeds: about 3 h 30 min
    colorsort-baseline --recipe state --demos.counts=8,40 --training.steps=2500
    colorsort-baseline --recipe camera-snapshot --demos.late_pick=30 --policy.optimizer_lr=1e-4
    colorsort-baseline --list
    colorsort-baseline --recipe camera --help           # every flag, with camera's values

Every field of the recipe is a flag ``--<section>.<field>=<value>`` (sections ``demos``, ``policy``,
``training``, ``dagger``, ``evaluation``): the command's configuration is its command line, parsed by draccus as
LeRobot's are (``colorsort.cli.config_args``, docs/commands.md), ``--config_path FILE`` reads any of them from YAML,
``--policy.type`` picks ACT or diffusion, and ``--help`` shows each with its comment and the chosen recipe's value.
Every stage is a documented command, run as a subprocess with its command line printed: ``colorsort-collect`` for
each training variant (merged with LeRobot's ``aggregate_datasets``; a camera recipe's set then loses
``observation.environment_state`` with ``remove_feature``), ``lerobot-train`` (ACT or diffusion), and
``colorsort-eval`` on the variants' fixed evaluation seeds, with the learning curve from the checkpoints saved
along the way. It prints a Markdown table and writes ``OUT/results.json``, ``OUT/success_vs_demos.png`` and
``OUT/learning_curve.png``.
``--ship DIR`` copies the largest set's ``pretrained_model`` to DIR with ``scores.json``, the plots and a
README of how it was made. ``--add-to DIR`` adds the run's training seeds to the baseline shipped in DIR (the
same recipe and flags but ``--training.seeds``, which names seeds it does not hold): its scores, tables and README
gain their rows, its policy stays, and each added seed's policy is kept in ``DIR/seed<N>/``. So a row's seeds can
be trained in separate sittings, on other machines. A seed DIR holds without its policy (added before DIR kept
them) may be run again: its policy is kept when the run reproduces every episode the seed scored; one that scores
otherwise exits 2 with the variants that differ, nothing changed, or with ``--replace-seeds`` replaces that seed's
rows with its own (the earlier sitting is recorded as replaced).

Finished stages under OUT are reused, each named by a key of the typed settings that feed it and the versions
of the code that made its data (``colorsort.training.cache``, ``colorsort.versions``), so an interrupted run
goes on where it stopped, ``--until`` splits the work into sittings, and a changed setting or a changed expert,
cell or recorder makes the stages it feeds anew; ``--fresh`` starts over.
Exit status 0 done, 1 a stage failed, 2 bad arguments or an OUT holding a stage of other settings.
"""

from __future__ import annotations

import shlex
import shutil
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

import draccus

from colorsort.cli.config_args import Spelling, parse_config
from colorsort.cli.run import guarded
from colorsort.data.perturbations import PERTURBATIONS
from colorsort.errors import ConfigError, DataExistsError
from colorsort.training.dagger_config import DaggerConfig
from colorsort.training.demos_config import DemosConfig
from colorsort.training.pipeline import UNTIL, RunConfig, run_pipeline
from colorsort.training.policy_config import SMALL_ACT, PolicyConfig
from colorsort.training.publishing.ship import addable
from colorsort.training.recipes import RECIPES, SECTIONS, EvaluationConfig, Recipe, TrainingConfig, get_recipe


@dataclass(frozen=True)
class BaselineCommandConfig:
    """``colorsort-baseline``'s settings: the run's, then the recipe's sections, each field a flag whose default is
    the chosen recipe's value (``--recipe camera --help`` shows camera's)."""

    recipe: str = "state"  # the preset to start from (--list)
    list: bool = False  # print the recipes and exit
    workers: int = RunConfig.workers  # collection processes
    envs: int = RunConfig.envs  # evaluation processes
    out: str | None = None  # working folder (default outputs/baselines/<recipe>)
    until: str = RunConfig.until  # the last stage to run: data, train or eval
    ship: str | None = None  # copy the largest set's policy here with its scores and a README
    # add this run's training seeds to the baseline shipped in this folder (the same recipe and flags but
    # --training.seeds); its policy stays
    add_to: str | None = None
    # with --add-to: a seed the baseline holds without its policy, run again and scored otherwise, has its rows
    # replaced by this run's (refused without it: the rows held scored weights that are gone)
    replace_seeds: bool = False
    fresh: bool = False  # delete OUT first instead of reusing its finished stages
    demos: DemosConfig = field(default_factory=DemosConfig)
    policy: PolicyConfig = SMALL_ACT
    training: TrainingConfig = field(default_factory=TrainingConfig)
    dagger: DaggerConfig = field(default_factory=DaggerConfig)
    evaluation: EvaluationConfig = field(default_factory=EvaluationConfig)

    def __post_init__(self) -> None:
        if self.until not in UNTIL:
            raise ConfigError(f"--until {self.until!r}: valid stages are {list(UNTIL)}")
        if self.ship and self.add_to:
            raise ConfigError("--ship makes a new baseline, --add-to adds seeds to a shipped one: give one of them")
        if self.replace_seeds and not self.add_to:
            raise ConfigError("--replace-seeds replaces the rows of seeds a baseline holds: give --add-to DIR too")

    def chosen(self) -> Recipe:
        """The recipe to run: the preset named ``recipe`` with these sections (its checks run again)."""
        return replace(get_recipe(self.recipe), **{s: getattr(self, s) for s in SECTIONS})

    @staticmethod
    def of(recipe: Recipe) -> BaselineCommandConfig:
        """The settings whose defaults are ``recipe``'s own."""
        return BaselineCommandConfig(recipe=recipe.name, **{s: getattr(recipe, s) for s in SECTIONS})


# a perturbation is also a flag of its own, as before the command was its configuration (--demos.late_pick=10)
SPELLING = Spelling(members={f"demos.{name}": ("demos.perturbations", kind.parse)
                             for name, kind in PERTURBATIONS.items()})


def recipe_named(argv: list[str]) -> str:
    """The ``--recipe`` that ``argv`` names (its last), else the one its ``--config_path`` file names, else the
    default's."""
    name = BaselineCommandConfig.recipe
    for k, token in enumerate(argv):
        path = token.partition("=")[2] if token.startswith("--config_path=") else (
            argv[k + 1] if token == "--config_path" and k + 1 < len(argv) else None)
        if path:
            with open(path, encoding="utf-8") as f:
                name = str((draccus.cfgparsing.load_config(f, file=path) or {}).get("recipe", name))
    for k, token in enumerate(argv):
        if token.startswith("--recipe="):
            name = token.partition("=")[2]
        elif token == "--recipe" and k + 1 < len(argv):
            name = argv[k + 1]
    return name


def parse_args(argv: list[str]) -> BaselineCommandConfig:
    """The run's settings, the chosen recipe's values the defaults of its sections' flags."""
    defaults = BaselineCommandConfig.of(get_recipe(recipe_named(argv)))  # ConfigError naming the recipes
    perturbations = "\n".join(f"  --demos.{name}={kind.metavar}  {kind.help}" for name, kind in PERTURBATIONS.items())
    return parse_config(BaselineCommandConfig, argv, prog="colorsort-baseline", description=__doc__,
                        defaults=defaults, spelling=SPELLING,
                        epilog="the demonstrator's perturbations, one flag each (or "
                               f"--demos.perturbations=[NAME:VALUE,...]):\n{perturbations}")


def chosen_recipe(argv: list[str]) -> Recipe:
    """The recipe ``argv`` asks for: the preset ``--recipe`` names with its sections' flags."""
    return parse_args(argv).chosen()


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
    args = parse_args(argv)
    recipe = args.chosen()
    if args.list:
        width, label_width = max(map(len, RECIPES)), max(len(r.label) for r in RECIPES.values())
        for r in RECIPES.values():
            print(f"{r.name:<{width}}  {r.label:<{label_width}} {describe(r)}")
        return 0
    settings = RunConfig(Path(args.out or f"outputs/baselines/{recipe.name}"), args.workers, args.envs, args.until)
    ship_to = Path(args.ship) if args.ship else None
    add_to = Path(args.add_to) if args.add_to else None
    if ship_to and ship_to.exists() and any(ship_to.iterdir()):
        raise DataExistsError(f"{ship_to} exists: remove it first, ship elsewhere, or add seeds with --add-to")
    if add_to:
        addable(recipe, add_to)  # ConfigError before any work: another recipe, or seeds it holds with policies
    if args.fresh:
        shutil.rmtree(settings.out, ignore_errors=True)
    # DataConflictError: OUT holds a stage of other settings, or a held seed scored otherwise; nothing overwritten
    run_pipeline(recipe, settings, shlex.join(["colorsort-baseline", *argv]), ship_to, add_to, args.replace_seeds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
