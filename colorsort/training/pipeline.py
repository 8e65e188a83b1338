"""A learned baseline end to end: demos -> ``lerobot-train`` -> ``colorsort-eval`` -> table, plots, shipped policy.

For each demo count of the recipe: collect (``stages.collect_demos``); for each training seed, train
(``stages.train``) and score the largest set's policies on every evaluation variant and the smaller
sets' on the main variant; then the learning curve (each earlier checkpoint of the largest set's
first seed on the main variant's first ``curve_episodes`` seeds; the scored checkpoint's point is the
first episodes of its full score). The scored checkpoint is the last, or where the recipe says so
(``select_episodes``) the one that did best on validation seeds (``selection``). With DAgger rounds
(``recipe.dagger``) the largest set's policy of each seed is the last round's (``dagger``).
Finished stages are reused, so the pipeline can be rebuilt over several sittings.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from colorsort.benchmark.metrics import EvalReport
from colorsort.errors import ConfigError
from colorsort.training import pipeline_stages as stages
from colorsort.training import selection
from colorsort.training.publishing.run_summary import first_episodes, plot_curve, plot_demos, summary_table, table
from colorsort.training.publishing.ship import add_seeds, ship, training_machine
from colorsort.training.recipes import Recipe
from colorsort.training.results_file import CurvePoint, PipelineResults, ScoreRow, ValidationPoint, report_from_json

UNTIL = ("data", "train", "eval")


@dataclass(frozen=True)
class RunConfig:
    """How one run of the pipeline runs (not what it makes: that is the recipe).

    Attributes:
        out: working folder (datasets, training runs, evaluations, logs, results).
        workers: collection processes.
        envs: evaluation processes.
        until: the last stage to run: "data", "train" or "eval" (everything).
    """

    out: Path
    workers: int = 2
    envs: int = 2
    until: str = "eval"

    def __post_init__(self) -> None:
        if self.until not in UNTIL:
            raise ConfigError(f"until={self.until!r}: valid stages are {list(UNTIL)}")
        for key in ("workers", "envs"):
            if getattr(self, key) < 1:
                raise ConfigError(f"{key}={getattr(self, key)}: give at least 1")


def run_pipeline(recipe: Recipe, settings: RunConfig, command: str, ship_to: Path | None = None,
                 add_to: Path | None = None, replace_seeds: bool = False) -> PipelineResults | None:
    """Every stage of ``recipe`` under ``settings.out``; the results (also written to ``out/results.json``), or None
    when ``settings.until`` stops before the evaluations. ``ship_to``: ship the first seed's policy there;
    ``add_to``: add this run's training seeds and their policies to the baseline shipped there (``ship.add_seeds``:
    its learning curve is its own first seed's, so this run makes none; ``replace_seeds``: a seed it holds without
    its policy that scores otherwise replaces its rows)."""
    out = settings.out
    out.mkdir(parents=True, exist_ok=True)
    started, t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), time.perf_counter()
    rows: list[ScoreRow] = []
    curve: list[CurvePoint] = []
    shipped: Path | None = None
    models: dict[int, Path] = {}  # the largest set's policy of each training seed
    demos, training = recipe.demos, recipe.training
    for n in demos.counts:
        largest = n == demos.counts[-1]
        data = stages.collect_demos(recipe, n, out, settings.workers)
        if settings.until == "data":
            continue
        kept, frames = stages.size(data)
        steps = training.updates(largest, frames)
        for seed in training.seeds:
            run_dir, timing = stages.train(recipe, data, steps, seed, out)
            trained_frames = frames
            if largest and recipe.dagger.rounds:
                run_dir, timing, trained_on, steps = dagger(recipe, settings, n, data, run_dir, timing, steps, seed)
                trained_frames = stages.size(trained_on)[1]  # the demos' and the expert's labels
            if settings.until == "train":
                continue
            model, chosen, validation = choose(recipe, settings, run_dir, timing, steps)
            passes = round(steps * training.batch_size / trained_frames, 1)
            scored = []
            for report in score(recipe, settings, model, run_dir.name + ("" if chosen == steps else f"-at{chosen}"),
                                largest):
                scored.append(ScoreRow(n, kept, trained_frames, seed, steps, passes, timing["wall_s"] / 60, report,
                                       chosen if validation else None, tuple(validation)))
                print(table(scored[-1:], recipe.label).splitlines()[-1], flush=True)
            rows += scored
            if largest:
                models[seed] = model
            if largest and seed == training.seeds[0]:
                shipped = model
                if training.save_every and add_to is None:
                    curve = learning_curve(recipe, settings, run_dir, timing, scored, chosen)
    if settings.until != "eval":
        print(f"stopped after the {settings.until!r} stage: {out}")
        return None
    assert shipped is not None
    results = PipelineResults(recipe.to_json(), command, started, round(time.perf_counter() - t0, 1), tuple(rows),
                              tuple(curve))
    plots = write_results(recipe, results, out)
    if ship_to is not None:
        ship(recipe, shipped, results, plots, ship_to, command)
    if add_to is not None:
        add_seeds(recipe, results, add_to, command, models, replace_seeds)
    return results


def score(recipe: Recipe, settings: RunConfig, model: Path, name: str, largest: bool) -> Iterator[EvalReport]:
    """``model`` (the checkpoint ``name`` of a run) on the evaluation seeds of every variant of the recipe's
    evaluation (the largest set) or its main variant alone; one report per variant, as each is made."""
    evaluation, out = recipe.evaluation, settings.out
    for variant in evaluation.variants if largest else (evaluation.main_variant,):
        stem = out / "eval" / f"{name}-{recipe.policy.execution}-{variant}"
        yield report_from_json(stages.score_policy(recipe, model, variant, evaluation.episodes_on(variant), stem,
                                               settings.envs, out / "logs"))


def write_results(recipe: Recipe, results: PipelineResults, out: Path) -> list[Path]:
    """``results.json`` and the plots (success against demos; the learning curve, where there is one) under ``out``,
    and the summary table printed; the plots' paths."""
    main = recipe.evaluation.main_variant
    plots = [out / "success_vs_demos.png"]
    plot_demos([r for r in results.rows if r.variant == main], recipe.label, main, plots[0])
    if results.curve:
        plots.append(out / "learning_curve.png")
        plot_curve(list(results.curve), recipe.label, main, training_machine(recipe.training.device), plots[1])
    (out / "results.json").write_text(json.dumps(results.to_json(), indent=1))
    print(f"\n{summary_table(list(results.rows), recipe.label)}\n\nplots: {', '.join(map(str, plots))}\n"
          f"results: {out / 'results.json'}\nwall time: {results.wall_s / 60:.1f} min (stages reused from earlier "
          "runs excluded)")
    return plots


def dagger(recipe: Recipe, settings: RunConfig, n: int, data: Path, run_dir: Path, timing: dict, steps: int,
           seed: int) -> tuple[Path, dict, Path, int]:
    """DAgger's rounds after the first training (``recipe.dagger``): each round's policy (its last checkpoint, or
    with ``rollout="chosen"`` the one validation seeds choose) plays every training variant, the expert labels the
    states it reached, the labels join the training set and a policy is trained on it for the round's updates:
    a new one from scratch, or with ``retrain="finetune"`` the one that played, further. The last round's run, its
    timing, its training set and its updates.

    The timing counts every round's training: its wall time is their sum, and its start is moved back by the earlier
    rounds' training, so that a checkpoint's minutes (``stages.checkpoints``) are all the training behind it."""
    out, rounds = settings.out, recipe.dagger
    round_steps = rounds.updates or steps
    earlier_s = 0.0
    for round_ in range(1, rounds.rounds + 1):
        earlier_s += timing["wall_s"]
        model = run_dir / "checkpoints" / "last" / "pretrained_model"
        if rounds.rollout == "chosen":
            model = choose(recipe, settings, run_dir, timing, steps)[0]
        labels = [stages.label(recipe, model, variant, k, round_, out)
                  for k, variant in enumerate(recipe.demos.train_variants)
                  if not rounds.variants or variant in rounds.variants]
        data = stages.add_labels(recipe, data, labels, f"demos-{n}-dagger{round_}", out)
        run_dir, timing = stages.train(recipe, data, round_steps, seed, out,
                                       init=model if rounds.retrain == "finetune" else None)
        steps = round_steps
    return run_dir, {**timing, "started": timing["started"] - earlier_s,
                     "wall_s": round(earlier_s + timing["wall_s"], 1)}, data, steps


def choose(recipe: Recipe, settings: RunConfig, run_dir: Path, timing: dict,
           steps: int) -> tuple[Path, int, list[ValidationPoint]]:
    """The checkpoint to score: (its pretrained_model, its update, the validation points it was chosen on).

    The last, with no validation, unless the recipe selects (``select_episodes``) among two checkpoints or more."""
    last = run_dir / "checkpoints" / "last" / "pretrained_model"
    found = stages.checkpoints(run_dir, timing)
    if not recipe.evaluation.select_episodes or len(found) < 2:
        return last, steps, []
    points = selection.validate(recipe, run_dir.name, found, settings.out, settings.envs)
    chosen = selection.best(points).step
    print(f"{run_dir.name}: validation chose update {chosen} ("
          + ", ".join(f"{p.step}: {p.successes}/{p.episodes}" for p in points) + ")", flush=True)
    return (last if chosen == steps else next(m for step, _, m in found if step == chosen)), chosen, points


def learning_curve(recipe: Recipe, settings: RunConfig, run_dir: Path, timing: dict,
                   scored: list[ScoreRow], chosen: int) -> list[CurvePoint]:
    """Success on the main variant's first ``curve_episodes`` seeds at every checkpoint, with its training time.

    The ``chosen`` checkpoint's point is the first episodes of its full score."""
    main = recipe.evaluation.main_variant
    final = next(r.report for r in scored if r.variant == main)
    episodes = min(recipe.evaluation.curve_episodes, final.episodes)
    points = []
    for step, minutes, model in stages.checkpoints(run_dir, timing):
        if step == chosen:
            report = final
        else:
            stem = settings.out / "curve" / f"{run_dir.name}-{recipe.policy.execution}-{step}"
            report = report_from_json(stages.score_policy(recipe, model, main, episodes, stem, settings.envs,
                                                      settings.out / "logs"))
        points.append(first_episodes(report, episodes, step, round(minutes, 1)))
    return points
