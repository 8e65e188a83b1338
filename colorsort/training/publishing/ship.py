"""Shipping a trained policy: LeRobot's ``pretrained_model`` files, its scores as JSON, plots and a README.

``ship`` makes a baseline's folder; ``add_seeds`` adds the rows of training seeds run later (another sitting,
another machine: the same recipe but its seeds, so the same demos) to a folder shipped before, leaving its
policy, the first seed's, as it was, and keeps each added seed's policy beside it in ``seed<N>/``: a later
sitting's run folder is on another machine, and a seed's held-out sweep needs its weights. A seed held without its
policy there (added before the folders kept them) may be run again: its policy is kept when the run reproduces
every episode the seed scored; a run that scores otherwise is refused, or with ``replace_rows``
(``--replace-seeds``) replaces the seed's rows (the sitting that made them is recorded as replaced)."""

from __future__ import annotations

import json
import os
import shutil
import string
import subprocess
from dataclasses import asdict, replace
from functools import partial
from pathlib import Path

from colorsort.errors import ConfigError, DataConflictError
from colorsort.paths import asset_path
from colorsort.training.dagger_config import DaggerConfig
from colorsort.training.publishing.run_summary import curve_table, plot_demos, summary_table, table, validation_table
from colorsort.training.publishing.tables import parameters
from colorsort.training.recipes import RELIGHT_TEMPERATURE, Recipe
from colorsort.training.results_file import PipelineResults, ScoreRow, Sitting
from colorsort.variants import LIGHT_BRIGHTNESS, VALIDATION_SEEDS, get_variant


def commit(shipped: Path | None = None) -> str:
    """The checkout's commit (marked when it has uncommitted changes outside ``shipped``, the folder being
    shipped, whose tracked files a reship replaces), or why there is none."""
    inside = shipped is not None and shipped.resolve().is_relative_to(Path.cwd().resolve())
    exclude = [f":(exclude){shipped.resolve()}"] if inside and shipped is not None else []
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ":/", *exclude],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return sha + (" (with uncommitted changes)" if dirty else "")


def training_machine(device: str) -> str:
    """One line: this machine's CPU cores and the training device."""
    return f"a {os.cpu_count()}-core machine, training on {'the CPU' if device == 'cpu' else device}"


def demo_line(recipe: Recipe) -> str:
    """How the largest set's demos were made: "8 on default, 8 on lighting under lights of brightness x0.45-0.75,
    ...; 3 boxes each; every belt pass held back 0-100 steps". A perturbation on every training variant is named
    once at the end, one on some of them after each of those."""
    demos = recipe.demos
    everywhere = [p for p in demos.perturbations if demos.applying(p) == demos.train_variants]
    mix = ", ".join(f"{c} on {v}" + "".join(f" {p.describe()}" for p in demos.perturbations_on(v)
                                            if p not in everywhere)
                    for v, c in demos.split(demos.counts[-1]).items())
    boxes = f"{demos.boxes_per_episode} boxes each" + "".join(f", {v}'s {n}" for v, n in demos.boxes_by_variant)
    expert = ([f"the expert's {', '.join(f'{n} {v:g}' for n, v in demos.expert)} (`ExpertConfig`, changed from its "
               "preset)"] if demos.expert else [])
    shifts = ([f"each recorded with held-out shifts' training ranges drawn per episode, up to level 1 exclusive "
               f"(`{demos.shift}`)"] if demos.shift else [])
    return "; ".join([mix, boxes, *(p.describe() for p in everywhere), *expert, *shifts])


def dagger_line(recipe: Recipe, frames: int) -> str:
    """The README's sentence on DAgger's rounds, or nothing for behaviour cloning alone."""
    d = recipe.dagger
    if not d.rounds:
        return ""
    played = ", ".join(f"`{v}`" for v in d.variants) if d.variants else "every training variant"
    driver = "the last policy" if d.rollout == "last" else "the last policy's checkpoint chosen on validation seeds"
    trained = ("a new policy was trained from scratch" if d.retrain == "scratch"
               else "the policy that played was trained further")
    return (f" Then {d.rounds} DAgger round{'s' * (d.rounds > 1)}: each time {driver} played {d.episodes} "
            f"episodes of {played}, the expert took over after {d.handover[0]}-{d.handover[1]} steps "
            f"and labelled the states it reached (`colorsort-takeover`), and {trained} "
            f"on the demos and every round's labels ({frames} frames in all); the minutes count every round's "
            f"training.")


def seed_folder(dest: Path, seed: int) -> Path:
    """Where a baseline keeps the policy of a training seed other than its own first: ``dest/seed<N>``."""
    return dest / f"seed{seed}"


def policy_bytes(folder: Path) -> int:
    """The bytes of the policy in ``folder``: its own files, not its seed folders' nor its README."""
    return sum(f.stat().st_size for f in folder.iterdir() if f.is_file() and f.name != "README.md")


def ship(recipe: Recipe, model: Path, results: PipelineResults, plots: list[Path], dest: Path, command: str) -> None:
    """Copy ``model`` to ``dest`` with ``scores.json`` (``results``), the plots and a README of how it was made."""
    dest.mkdir(parents=True, exist_ok=True)
    for f in model.iterdir():
        shutil.copy2(f, dest / f.name)
    for p in plots:
        shutil.copy2(p, dest / p.name)
    results = replace(results, command=command, commit=commit(dest))
    (dest / "scores.json").write_text(json.dumps(results.to_json(), indent=1))
    write_readme(recipe, results, dest)
    print(f"shipped {dest} ({policy_bytes(dest) / 1e6:.1f} MB)")


def differences(stored: object, recipe: object, prefix: str = "") -> list[str]:
    """The ``section.field`` keys where two recipes' JSON differ."""
    if not (isinstance(stored, dict) and isinstance(recipe, dict)):
        return [] if stored == recipe else [prefix.rstrip(".")]
    return [k for key in sorted(set(stored) | set(recipe))
            for k in differences(stored.get(key), recipe.get(key), f"{prefix}{key}.")]


def seedless(recipe: dict) -> dict:
    """A stored recipe without its training seeds."""
    training = recipe.get("training")
    if not isinstance(training, dict):  # stored flat, before the sections
        return recipe
    return {**recipe, "training": {k: v for k, v in training.items() if k != "seeds"}}


def with_defaults(recipe: dict) -> dict:
    """A stored recipe with the fields it predates at their defaults: a setting added since ran as its default
    does (``dagger.rollout``, for one). The policy section is the method's own and is left as stored."""
    defaults = {**Recipe("defaults").to_json(), "dagger": json.loads(json.dumps(asdict(DaggerConfig())))}
    return {**recipe, **{section: {**defaults[section], **stored} for section, stored in recipe.items()
                         if section in ("demos", "training", "dagger", "evaluation") and isinstance(stored, dict)}}


def addable(recipe: Recipe, dest: Path) -> PipelineResults:
    """The scores shipped in ``dest``, when ``recipe`` differs from theirs only in training seeds: seeds it does not
    hold, or holds without their policy (neither its own first seed nor a ``seed<N>`` folder); ConfigError saying
    what differs otherwise."""
    path = dest / "scores.json"
    if not path.is_file():
        raise ConfigError(f"{dest} holds no shipped baseline (no scores.json): ship one there first with --ship")
    shipped = PipelineResults.load(path)
    differ = differences(seedless(with_defaults(shipped.recipe)), seedless(with_defaults(recipe.to_json())))
    if differ:
        raise ConfigError(f"{dest}'s recipe differs from this run's in {differ}: seeds can be added only to a "
                          "baseline of the same recipe (give those settings as it was made, see its README)")
    held = [s for s in sorted(set(recipe.training.seeds) & set(shipped.seeds))
            if s == shipped.seeds[0] or seed_folder(dest, s).is_dir()]
    if held:
        raise ConfigError(f"{dest} already holds training seeds {held} with their policies: give --training.seeds "
                          f"other than {list(shipped.seeds)}")
    return shipped


def episodes(row: ScoreRow) -> tuple:
    """What a run of a row's seed again must reproduce: the checkpoint chosen, each validation point's counts and
    every scored episode (not the minutes, nor the run's folder)."""
    points = [(p.step, p.episodes, p.successes, p.correct, p.misplaced, p.dropped, p.success_by_variant)
              for p in row.validation]
    return row.demos_tried, row.demos, row.frames, row.steps, row.checkpoint, points, row.report.per_episode


def unreproduced(held: PipelineResults, run: PipelineResults, seed: int) -> list[str]:
    """The variants where ``run``'s rows of ``seed`` differ from the ones ``held`` has (or are missing)."""
    def rows(results: PipelineResults) -> dict[tuple[int, str], tuple]:
        return {(r.demos_tried, r.variant): episodes(r) for r in results.rows if r.seed == seed}

    theirs, ours = rows(held), rows(run)
    return sorted({key[1] for key in theirs.keys() | ours.keys() if theirs.get(key) != ours.get(key)})


def add_seeds(recipe: Recipe, results: PipelineResults, dest: Path, command: str, models: dict[int, Path],
              replace_rows: bool = False) -> PipelineResults:
    """Add ``results``' rows (training seeds run in a later sitting of ``recipe``) to the baseline shipped in
    ``dest``: its scores, its plot against demos and its README, and each seed's policy (``models``, by seed) in
    ``seed<N>/``; its policy, curve and first command stay. A seed it held already keeps its rows when the run
    reproduced every one of them; one that scored otherwise is refused (DataConflictError, nothing changed), or with
    ``replace_rows`` has its rows replaced by the run's, in place. The merged scores."""
    shipped = addable(recipe, dest)
    held = tuple(s for s in recipe.training.seeds if s in shipped.seeds)
    differ = {seed: v for seed in held if (v := unreproduced(shipped, results, seed))}
    if differ and not replace_rows:
        raise DataConflictError(
            f"training seeds {list(differ)} scored otherwise than {dest} holds ({differ}): this run's policies are not "
            "the ones scored there, so nothing was kept or changed; --replace-seeds replaces their rows with this "
            "run's, keeping its policies")
    for seed in recipe.training.seeds:
        shutil.copytree(models[seed], seed_folder(dest, seed))
    sitting = partial(Sitting, command, commit(dest), results.started, results.wall_s)
    new = tuple(s for s in recipe.training.seeds if s not in shipped.seeds or s in differ)
    again = tuple(s for s in held if s not in differ)
    rows = tuple(r for r in shipped.rows if r.seed not in differ) + tuple(r for r in results.rows if r.seed in new)
    seeds = tuple(dict.fromkeys(r.seed for r in rows))
    later = {x for a in shipped.added for x in a.seeds}
    first = Sitting(shipped.command, shipped.commit, shipped.started, shipped.wall_s,
                    tuple(x for x in shipped.seeds if x not in later))
    made = [(s, tuple(x for x in s.seeds if x in differ)) for s in (first, *shipped.added)]
    merged_recipe = recipe.override({"training.seeds": seeds})

    def without_replaced(sittings: tuple[Sitting, ...]) -> tuple[Sitting, ...]:
        return tuple(replace(s, seeds=tuple(x for x in s.seeds if x not in differ)) for s in sittings
                     if set(s.seeds) - set(differ))

    merged = replace(shipped, recipe=merged_recipe.to_json(), rows=rows,
                     added=without_replaced(shipped.added) + ((sitting(new),) if new else ()),
                     kept=without_replaced(shipped.kept) + ((sitting(again),) if again else ()),
                     replaced=shipped.replaced + tuple(replace(s, seeds=gone) for s, gone in made if gone))
    (dest / "scores.json").write_text(json.dumps(merged.to_json(), indent=1))
    main = recipe.evaluation.main_variant
    plot_demos([r for r in merged.rows if r.variant == main], recipe.label, main, dest / "success_vs_demos.png")
    write_readme(merged_recipe, merged, dest)
    if new:
        print(f"added training seeds {list(new)} to {dest} (now {list(seeds)})"
              + (f"; the rows of {list(differ)} replaced" if differ else ""))
    if again:
        print(f"training seeds {list(again)} reproduced every episode {dest} holds of them: their policies kept in "
              f"{', '.join(str(seed_folder(dest, s)) for s in again)}")
    return merged


def took(sitting: Sitting) -> str:
    """How long a sitting ran: "77 min", or that it reused every stage (of an earlier run of the same flags)."""
    return f"{sitting.wall_s / 60:.0f} min" if sitting.wall_s >= 30 else "every stage reused from an earlier run"


# what a README says of running its command again (tests/test_pipeline.py holds the first clause)
REPRODUCES = ("The same command on the same machine trains the same weights, bit for bit: the data order and the "
              "image augmentation are drawn from the training seed, the recipe fixes `--num_workers`, and torch's "
              "threads are fixed (`OMP_NUM_THREADS`, 2 unless the environment sets it). Another thread count, CPU or "
              "version of torch or LeRobot sums in another order and trains other weights.")


MODEL_CARD = "templates/model_card.md"  # under colorsort.assets: the README's template (``string.Template``)


def write_readme(recipe: Recipe, results: PipelineResults, dest: Path) -> None:
    """``dest/README.md``: how the policy in ``dest`` was made and scored, from ``results`` (its rows' first
    training seed is the policy's), rendered from the model card template (``MODEL_CARD``)."""
    demos, training, evaluation = recipe.demos, recipe.training, recipe.evaluation
    every_seed = [r for r in results.rows if r.demos_tried == demos.counts[-1]]
    largest = [r for r in every_seed if r.seed == training.seeds[0]]
    first = largest[0]
    values = {
        "name": dest.name, "label": recipe.label, "description": recipe.policy.describe(parameters(dest) or 0)
        + backbone_line(recipe), "inputs": inputs_line(recipe), "size_mb": f"{policy_bytes(dest) / 1e6:.1f}",
        "stored": stored_line(recipe), "command": results.command, "recipe": recipe.name,
        "commit": results.commit or "unknown", "started": results.started, "machine": training_machine(training.device),
        "tried": demos.counts[-1], "demo_line": demo_line(recipe), "kept": first.demos, "steps": first.steps,
        "batch": training.batch_size, "train_minutes": f"{first.train_minutes:.0f}",
        "at": f" (shipped: its checkpoint after {first.checkpoint})" if first.checkpoint is not None else "",
        "dagger": dagger_line(recipe, first.frames), "sittings": sittings_line(results), "reproduces": REPRODUCES,
        "dest": dest, "main_variant": evaluation.main_variant,
        "task": get_variant(evaluation.main_variant).gym_id.removeprefix("colorsort/"),
        "cameras": ",".join(demos.cameras) or "none", "image_size": demos.image_size,
        "table": table(largest, recipe.label), **more_sections(recipe, results, every_seed, dest)}
    card = string.Template(Path(asset_path(MODEL_CARD)).read_text())
    (dest / "README.md").write_text(card.substitute(values))


def inputs_line(recipe: Recipe) -> str:
    """What the policy reads."""
    demos = recipe.demos
    if demos.cameras:
        return (f"`observation.state` and the cameras {', '.join(demos.cameras)} at {demos.image_size} px, never "
                "`observation.environment_state`: the policy sees the boxes")
    return "`observation.state` and `observation.environment_state` (the simulator's box state): no cameras"


def backbone_line(recipe: Recipe) -> str:
    """The image encoder's training and augmentation, after the policy's description ("" without cameras)."""
    training = recipe.training
    line = ", its ResNet-18 trained from scratch (no pretrained weights)" if recipe.demos.cameras else ""
    if training.image_shift:
        line += f", every training image shifted at random by up to {training.image_shift:g} of its size"
    if training.image_relight:
        (b_lo, b_hi), (t_lo, t_hi) = LIGHT_BRIGHTNESS, RELIGHT_TEMPERATURE
        line += f", every training image relit at random (brightness x{b_lo:g}-{b_hi:g}, {t_lo:,}-{t_hi:,} K)"
    return line


def stored_line(recipe: Recipe) -> str:
    """How the weights are stored: rounded and averaged as the recipe asks ("" for lerobot-train's own)."""
    training = recipe.training
    line = ("" if training.weights == "float32" else
            f" The weights are stored in {training.weights}, rounded from `lerobot-train`'s float32 before any "
            "checkpoint was scored: every score here is of these weights (LeRobot loads them into its float32 "
            "model).")
    if training.average > 1:
        line += (f" Each checkpoint's weights are the mean of its own and the {training.average - 1} saved before "
                 f"it (one every {training.save_every} updates; `colorsort.training.weights.average`).")
    return line


def sittings_line(results: PipelineResults) -> str:
    """The later sittings: seeds added, run again and kept, or replaced."""
    line = "".join(f" Training {s.named_seeds()} added later by `{s.command}` on commit {s.commit}, started "
                   f"{s.started} ({took(s)})." for s in results.added)
    line += "".join(f" Training {s.named_seeds()} run again by `{s.command}` on commit {s.commit}, started "
                    f"{s.started} ({took(s)}): it reproduced every episode scored below, and its "
                    "policy was kept." for s in results.kept)
    line += "".join(f" Training {s.named_seeds()} first added by `{s.command}` on commit {s.commit} (its policy not "
                    "kept; run again, it scored otherwise): its rows were replaced by the later sitting's."
                    for s in results.replaced)
    return line


def more_sections(recipe: Recipe, results: PipelineResults, every_seed: list, dest: Path) -> dict[str, str]:
    """The README's sections after the scores, each "" where it has nothing to say: every training seed, the seeds'
    policies kept beside, the checkpoint chosen on validation seeds, the learning curve."""
    training, evaluation = recipe.training, recipe.evaluation
    out = dict.fromkeys(("seeds", "beside", "chosen", "curve"), "")
    if len(training.seeds) > 1:
        out["seeds"] = (f"\nThe same data and updates with each of the recipe's {len(training.seeds)} training seeds "
                        f"({', '.join(map(str, training.seeds))}; this policy is seed {training.seeds[0]}'s):\n\n"
                        f"{summary_table(every_seed, recipe.label)}\n")
    kept = [s for s in training.seeds[1:] if seed_folder(dest, s).is_dir()]
    if kept:
        folders = ", ".join(f"`{seed_folder(dest, s).name}/`" for s in kept)
        whose = (f"The policy of training seed {kept[0]} (its checkpoint scored below) is" if len(kept) == 1 else
                 f"The policies of training seeds {', '.join(map(str, kept))} (each its checkpoint scored below) are")
        out["beside"] = (f"\n{whose} in {folders}: `colorsort-eval --policy {seed_folder(dest, kept[0])} --variant "
                         f"{evaluation.main_variant}`.\n")
    if any(r.validation for r in every_seed):
        out["chosen"] = (f"\nThe checkpoint scored (and shipped) is the one of each run that did best on "
                         f"{evaluation.select_episodes} episodes of each training variant on validation seeds "
                         f"({VALIDATION_SEEDS[0]} on, never scored; `colorsort.training.selection`):\n\n"
                         f"{validation_table(every_seed)}\n")
    if results.curve:
        out["curve"] = (f"\nLearning curve on `{evaluation.main_variant}` (each checkpoint on the first "
                        f"{evaluation.curve_episodes} evaluation seeds; `learning_curve.png`):\n\n"
                        f"{curve_table(results.curve)}\n")
    return out
