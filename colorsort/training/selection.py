"""Choosing a training run's checkpoint on validation seeds, never on the seeds it is scored on.

A small policy trained on a CPU can learn a task and lose it in its last updates (``camera-tracking``'s
seed 1002 sorted every box of 20 tracking episodes at 2,400 updates and 12% at 3,600). Scoring every
checkpoint on the evaluation seeds and keeping the best would report the best of several draws as one;
so each checkpoint plays ``select_episodes`` episodes of every training variant on
``colorsort.variants.VALIDATION_SEEDS`` instead, the one that does best there is scored on the
evaluation seeds and shipped, and the evaluation seeds decide nothing.

Layout under the pipeline's working folder::

    select/<run>-<exec>-<update>-<variant>-<key>.json   colorsort-eval's report of one checkpoint on validation seeds
"""

from __future__ import annotations

from pathlib import Path

from colorsort.errors import ConfigError
from colorsort.training import pipeline_stages as stages
from colorsort.training.recipes import Recipe
from colorsort.training.results_file import ValidationPoint
from colorsort.variants import VALIDATION_SEEDS

COUNTS = ("episodes", "successes", "correct", "misplaced", "dropped")


def validate(recipe: Recipe, run: str, checkpoints: list[tuple[int, float, Path]], out: Path,
             envs: int) -> list[ValidationPoint]:
    """Every checkpoint of the training run ``run`` (``stages.checkpoints``: update, minutes, pretrained_model) on
    ``recipe.evaluation.select_episodes`` validation episodes of each training variant (and as many again under
    ``recipe.evaluation.select_shift``'s training ranges, where it names some); one point per checkpoint, counts summed
    over the variants. Each evaluation is reused when its report is there."""
    points = []
    for step, minutes, model in checkpoints:
        counts = dict.fromkeys(COUNTS, 0)
        by_variant = {}
        shifts = ("", recipe.evaluation.select_shift) if recipe.evaluation.select_shift else ("",)
        for variant in recipe.demos.train_variants:
            for shift in shifts:
                name = f"{run}-{recipe.policy.execution}-{step}-{variant}" + ("-shifted" if shift else "")
                shifted = {"shift": shift} if shift else {}
                report = stages.score_policy(recipe, model, variant, recipe.evaluation.select_episodes,
                                         out / "select" / name, envs, out / "logs", first_seed=VALIDATION_SEEDS[0],
                                         **shifted)
                for key in COUNTS:
                    counts[key] += report[key]
                by_variant[variant + (" shifted" if shift else "")] = report["success_rate"]
        points.append(ValidationPoint(step, round(minutes, 1), success_by_variant=by_variant, **counts))
    return points


def best(points: list[ValidationPoint]) -> ValidationPoint:
    """The point with the most successful episodes; ties go to the most boxes sorted right, then the later update."""
    if not points:
        raise ConfigError("no checkpoints to choose from")
    return max(points, key=lambda p: (p.successes, p.correct, p.step))
