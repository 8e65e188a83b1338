"""The pipeline's stages, each a documented command run as a subprocess, each reused when already finished.

Every cached stage is named ``<stem>-<key>``, the key derived from the typed settings that feed it and the
versions of the code that makes its data (``cache``, ``colorsort.versions``).
Layout of the working folder ``out``::

    data/<variant>-<n>-<key>/  colorsort-collect's dataset of n demos on one variant; stage.json its settings
    data/demos-<N>-<key>/     the training set: the parts merged (cameras: box state removed)
    data/labels-<variant>-r<R>-<key>/  colorsort-takeover's expert labels of DAgger round R on one variant
    data/demos-<N>-dagger<R>-<key>/  round R's training set: round R-1's with round R's labels merged
    train/demos-<N>-<key>-<S>steps-<key>-seed<K>/  lerobot-train's run of S updates with seed K (from scratch, or
                              from a checkpoint's weights, named in the settings key); <run>.json its
                              timing and settings; under a constant rate, the first S updates of a longer run;
                              <run>.running.json while it trains (an interrupted run resumes from its last checkpoint)
                              with training.weights=float16 its checkpoints rounded, with training.average=k each
                              the mean of the latest k (``weights``), or copied from a finished run of the same
                              training with lerobot-train's own weights and rounded or averaged
    eval/<run>[-at<U>]-<exec>-<variant>-<key>.json  colorsort-eval's report of the run's last checkpoint (or
                              the one after U updates, when the validation seeds chose it), executing its chunks
                              as <exec> says (ens0.01: temporal ensembling; chunk10: 10 open-loop)
    curve/<run>-<exec>-<step>-<key>.json    an earlier checkpoint's report (the learning curve)
    select/<run>-<exec>-<step>-<variant>-<key>.json  a checkpoint on validation seeds (``selection``)
    logs/                     each command's output
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from colorsort.benchmark.eval_command import EvalCommandConfig
from colorsort.data.config import CollectConfig
from colorsort.errors import DataConflictError, StageError
from colorsort.executors.base import ExecutorConfig
from colorsort.expert.config import changes_text
from colorsort.training import cache
from colorsort.training.recipes import Recipe
from colorsort.training.run_reuse import first_updates, longer_run, resume_marker
from colorsort.training.weights import average, derived_copy, saved_every, store
from colorsort.variants import get_variant
from colorsort.versions import code_versions

if TYPE_CHECKING:  # imported where it runs: it loads the policies and the Gymnasium env
    from colorsort.training.takeover import TakeoverConfig

REPO_ID = "local/colorsort-baseline"
BIN = Path(sys.executable).parent  # the console scripts of this interpreter's environment
SEED_STRIDE = 1_000_000  # training variant k's demos use seeds k * SEED_STRIDE + i: no two overlap
# No hub downloads; torch's threads fixed (2 unless set): a training's weights depend on the count (the order of float
# sums), so with it fixed the same command gives the same weights bit for bit (tests/test_pipeline.py)
RUN_ENV = {"HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "2")}


def run(cmd: list[str], log: Path, append: bool = False) -> float:
    """Run ``cmd`` (printed first) with its output to ``log`` (after what it holds, if ``append``); its wall time
    [s]. StageError on failure."""
    print("$ " + shlex.join(cmd), flush=True)
    log.parent.mkdir(parents=True, exist_ok=True)
    t = time.perf_counter()
    with log.open("a" if append else "w") as f:
        result = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env={**os.environ, **RUN_ENV})
    if result.returncode != 0:
        raise StageError(f"exit code {result.returncode}: {shlex.join(cmd)}\n{log.read_text()[-3000:]}")
    return time.perf_counter() - t


def collect_demos(recipe: Recipe, n: int, out: Path, workers: int) -> Path:
    """The training set of ``n`` demos: one ``colorsort-collect`` per training variant, merged (reused if there).

    Demo i of training variant k has seed ``k * SEED_STRIDE + i``, so a smaller set's parts are the
    first episodes of a larger one's. With cameras the merged set loses ``observation.environment_state``:
    a camera policy must see the boxes, not read them from the simulator."""
    demos = recipe.demos
    split = demos.split(n)
    configs = {variant: collect_config(recipe, variant, k, count, workers)
               for k, (variant, count) in enumerate(split.items())}
    commands = {variant: command_of(config) for variant, config in configs.items()}
    parts = {variant: out / "data" / cache.name(f"{variant}-{split[variant]}", part_settings(config))
             for variant, config in configs.items()}
    merged = {"parts": [p.name for p in parts.values()], "drop_box_state": bool(demos.cameras)}
    root = out / "data" / cache.name(f"demos-{n}", merged)
    marker = root / "meta" / "complete"
    if (root / "meta" / "info.json").is_file() and marker.is_file():
        merged_from = marker.read_text().split()
        if merged_from != merged["parts"]:  # the same key from other parts: a stage left by other code
            raise DataConflictError(f"{root} was merged from {merged_from}, not {merged['parts']}: give another "
                                    "--out, or --fresh to rebuild it")
        print(f"reusing {root}")
        return root
    for variant, part in parts.items():
        if not (part / "meta" / "colorsort.json").is_file():
            shutil.rmtree(part, ignore_errors=True)
            run([*commands[variant], "--out", str(part)], out / "logs" / f"collect-{part.name}.log")
            cache.remember(part, part_settings(configs[variant]))
        else:
            print(f"reusing {part}")
    merge_parts(list(parts.values()), root, drop_box_state=bool(demos.cameras))
    cache.remember(root, merged)
    return root


def collect_config(recipe: Recipe, variant: str, k: int, count: int, workers: int) -> CollectConfig:
    """What ``colorsort-collect`` records of ``count`` demos of training variant ``variant`` (the k-th)."""
    demos, v = recipe.demos, get_variant(variant)
    return CollectConfig(episodes=count, boxes_per_episode=demos.boxes(variant), preset=v.preset, robot=v.robot,
                         variant=variant, seed=SEED_STRIDE * k, repo_id=REPO_ID, cameras=demos.cameras,
                         image_size=(demos.image_size, demos.image_size), executor=ExecutorConfig(workers=workers),
                         perturbations=demos.perturbations_on(variant), turn_to_box=demos.turn_to_box,
                         expert=demos.expert, shift=demos.shift)


def command_of(config: CollectConfig) -> list[str]:
    """The ``colorsort-collect`` command that records ``config`` (a recipe's part), without ``--out``."""
    return ([str(BIN / "colorsort-collect"), "--variant", str(config.variant), "--episodes", str(config.episodes),
             "--boxes-per-episode", str(config.boxes_per_episode), "--seed", str(config.seed),
             "--cameras", ",".join(config.cameras) or "none", "--image-size", str(config.image_size[0]),
             "--workers", str(config.executor.workers), "--repo-id", config.repo_id]
            + [f"--{p.name.replace('_', '-')}={p.text}" for p in config.perturbations]
            + ([] if config.turn_to_box else ["--no-turn"])
            + ([f"--expert={changes_text(config.expert)}"] if config.expert else [])
            + ([f"--shift={config.shift}"] if config.shift else []))


def collect_command(recipe: Recipe, variant: str, k: int, count: int, workers: int) -> list[str]:
    """``colorsort-collect`` of ``count`` demos of training variant ``variant`` (the k-th), without ``--out``."""
    return command_of(collect_config(recipe, variant, k, count, workers))


def part_settings(config: CollectConfig) -> dict:
    """What a part's demos depend on, the key of its cache: what it records (``CollectConfig.settings`` and the
    episodes; not the workers, nor how a flag is spelt: the same seeds give the same data) and the versions of the
    code that records it (the expert, the cell, the recorder; the shifts' where the demos are recorded under their
    training ranges)."""
    return {"collect": {**config.settings(), "episodes": config.episodes},
            "code": code_versions("expert", "cell", "recorder", *(("shifts",) if config.shift else ()))}


def merge_parts(parts: list[Path], root: Path, drop_box_state: bool) -> None:
    """LeRobot's ``aggregate_datasets`` of ``parts`` into ``root``, then ``remove_feature`` of the box state."""
    from lerobot.datasets.aggregate import aggregate_datasets
    from lerobot.datasets.dataset_tools import remove_feature
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    shutil.rmtree(root, ignore_errors=True)
    merged = root.with_name(f".{root.name}.merged")
    shutil.rmtree(merged, ignore_errors=True)
    aggregate_datasets([REPO_ID] * len(parts), REPO_ID, roots=parts, aggr_root=merged if drop_box_state else root)
    if drop_box_state:
        remove_feature(LeRobotDataset(REPO_ID, root=merged), "observation.environment_state", output_dir=root,
                       repo_id=REPO_ID)
        shutil.rmtree(merged)
    (root / "meta" / "complete").write_text("\n".join(p.name for p in parts) + "\n")  # what it was merged from


def checkpoint_name(model: Path) -> str:
    """A checkpoint's ``pretrained_model`` by its run's cache name, with ``@<update>`` unless it is the last one."""
    run_dir, checkpoint = model.parents[1].parent, model.parent.name
    return run_dir.name if checkpoint == "last" else f"{run_dir.name}@{int(checkpoint)}"


def label(recipe: Recipe, model: Path, variant: str, k: int, round_: int, out: Path) -> Path:
    """``colorsort-takeover`` of DAgger round ``round_`` on training variant ``variant`` (the k-th): ``model`` (a
    checkpoint's ``pretrained_model``) drives, the expert labels (reused if there). Round r's episodes of variant k
    have seeds from ``TAKEOVER_SEED + k * SEED_STRIDE + (r - 1) * episodes``: no round or variant repeats one."""
    config = label_config(recipe, model, variant, k, round_)
    settings = {"colorsort-takeover": {"policy": checkpoint_name(model), **config.settings()},
                "code": code_versions("expert", "cell", "recorder")}
    root = out / "data" / cache.name(f"labels-{variant}-r{round_}", settings)
    if (root / cache.SETTINGS_FILE).is_file():
        print(f"reusing {root}")
        return root
    shutil.rmtree(root, ignore_errors=True)
    run([str(BIN / "colorsort-takeover"), *replace(config, out=str(root)).argv()],
        out / "logs" / f"takeover-{root.name}.log")
    cache.remember(root, settings)
    return root


def label_config(recipe: Recipe, model: Path, variant: str, k: int, round_: int) -> TakeoverConfig:
    """The ``colorsort-takeover`` of ``label`` (its ``out`` left empty): the expert that made the demos labels, in the
    demos' codec."""
    from colorsort.training.takeover import TAKEOVER_SEED, TakeoverConfig

    dagger = recipe.dagger
    seed = TAKEOVER_SEED + k * SEED_STRIDE + (round_ - 1) * dagger.episodes
    return TakeoverConfig(policy=str(model), out="", variant=variant, episodes=dagger.episodes,
                          handover=dagger.handover, seed=seed, repo_id=REPO_ID, vcodec=CollectConfig.vcodec,
                          expert=recipe.demos.expert, turn_to_box=recipe.demos.turn_to_box)


def add_labels(recipe: Recipe, data: Path, labels: list[Path], stem: str, out: Path) -> Path:
    """The training set ``data`` with the expert's ``labels`` added (``aggregate_datasets``; reused if there). With
    cameras the labels lose ``observation.environment_state`` first, as the demos did."""
    from lerobot.datasets.dataset_tools import remove_feature
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    merged = {"data": data.name, "labels": [p.name for p in labels]}
    root = out / "data" / cache.name(stem, merged)
    if (root / "meta" / "complete").is_file():
        print(f"reusing {root}")
        return root
    stripped = [out / "data" / f".{part.name}.stripped" for part in labels] if recipe.demos.cameras else []
    for part, copy in zip(labels, stripped, strict=False):
        shutil.rmtree(copy, ignore_errors=True)
        remove_feature(LeRobotDataset(REPO_ID, root=part), "observation.environment_state", output_dir=copy,
                       repo_id=REPO_ID)
    merge_parts([data, *(stripped or labels)], root, drop_box_state=False)
    for copy in stripped:
        shutil.rmtree(copy)
    cache.remember(root, merged)
    return root


def size(data: Path) -> tuple[int, int]:
    """(episodes, frames) of the LeRobot dataset at ``data``."""
    info = json.loads((data / "meta" / "info.json").read_text())
    return info["total_episodes"], info["total_frames"]


def train_command(recipe: Recipe, data: Path, steps: int, seed: int, run_dir: Path,
                  init: Path | None = None) -> list[str]:
    """``lerobot-train`` of the recipe's policy on ``data`` for ``steps`` updates with ``seed`` into ``run_dir``;
    from scratch, or with ``init`` (a checkpoint's ``pretrained_model``) from its weights (``--policy.path``)."""
    training = recipe.training
    save_every = training.save_every if 0 < training.save_every < steps else steps
    policy = f"--policy.type={recipe.policy.type}" if init is None else f"--policy.path={init}"
    return [str(BIN / "lerobot-train"), f"--dataset.repo_id={REPO_ID}", f"--dataset.root={data}",
            policy, f"--policy.device={training.device}", "--policy.push_to_hub=false",
            *recipe.policy.args(recipe.demos.image_size), *training.augment_args(),
            f"--batch_size={training.batch_size}", f"--steps={steps}", f"--save_freq={save_every}", "--log_freq=200",
            f"--num_workers={training.num_workers}", f"--seed={seed}", "--wandb.enable=false",
            f"--output_dir={run_dir}"]


def train_settings(recipe: Recipe, init: Path | None = None) -> dict:
    """What a training run's weights depend on beside its data, length and seed: ``lerobot-train``'s arguments
    (the inference settings aside: they change how a policy acts, not what it learns; ``set_inference``), and the
    checkpoint it starts from (``init``), by name."""
    inference = tuple(f"--policy.{k}=" for k in recipe.policy.inference())
    args = train_command(recipe, Path("DATA"), 1, 0, Path("RUN"))[1:]
    skip = ("--dataset.root=", "--steps=", "--save_freq=", "--seed=", "--output_dir=", *inference)
    settings: dict = {"lerobot-train": [a for a in args if not a.startswith(skip)]}
    if recipe.training.weights != "float32":  # float32 runs keep the folders they always had
        settings["weights"] = recipe.training.weights
    if recipe.training.average > 1:  # which checkpoints are averaged depends on how often they are saved
        settings["average"] = [recipe.training.average, recipe.training.save_every]
    if init is not None:
        settings["from"] = checkpoint_name(init)
    return settings


def twins(recipe: Recipe, data: Path, steps: int, seed: int, out: Path, init: Path | None = None) -> list[Path]:
    """The runs of the same training whose checkpoints hold ``lerobot-train``'s own weights (float32, or float16 with
    the float32 file kept), from which a rounded or averaged run is copied instead of trained; none for a run that
    is one of them."""
    training = recipe.training
    if training.weights == "float32" and training.average == 1:
        return []
    plain = [{"training.weights": "float32", "training.average": 1}]
    if training.average > 1:
        plain.append({"training.weights": training.weights, "training.average": 1})
    return [out / "train" / run_name(recipe.override(o), data, steps, seed, init) for o in plain]


def run_name(recipe: Recipe, data: Path, steps: int, seed: int, init: Path | None = None) -> str:
    """A training run's folder name under ``train/``: its data, length, settings (``train_settings``) and seed."""
    return f"{data.name}-{steps}steps-{cache.key(train_settings(recipe, init))}-seed{seed}"


def finished(run_dir: Path) -> bool:
    """Whether ``run_dir`` is a finished training run (its last checkpoint and its timing are there)."""
    return ((run_dir / "checkpoints" / "last" / "pretrained_model" / "config.json").is_file()
            and run_dir.with_name(run_dir.name + ".json").is_file())


def train(recipe: Recipe, data: Path, steps: int, seed: int, out: Path,
          init: Path | None = None) -> tuple[Path, dict]:
    """``lerobot-train`` (from scratch, or from ``init``'s weights); the run folder and its timing (reused if there,
    resumed if interrupted).

    The timing is ``{"started": unix time, "wall_s": s, "settings": ...}``, and ``"resumed"`` where the run was
    interrupted and resumed from its last checkpoint (``resume``): its gaps are not training time."""
    run_dir = out / "train" / run_name(recipe, data, steps, seed, init)
    timing_path = run_dir.with_name(run_dir.name + ".json")  # not with_suffix: "-shift0.1-seed1000" has a dot
    running_path = run_dir.with_name(run_dir.name + ".running.json")
    if finished(run_dir):
        print(f"reusing {run_dir}")
        set_inference(run_dir, recipe)
        return run_dir, json.loads(timing_path.read_text())
    weights, k = recipe.training.weights, recipe.training.average
    for twin in twins(recipe, data, steps, seed, out, init):
        if (finished(twin) and not running_path.is_file()
                and (k == 1 or saved_every(twin, recipe.training.save_every, steps))):
            mean = f", each the mean of the latest {k}" if k > 1 else ""
            print(f"copying {twin}'s checkpoints in {weights}{mean}")
            if run_dir.exists():
                shutil.rmtree(run_dir)
            timing = derived_copy(twin, run_dir, weights, k)
            timing_path.write_text(json.dumps(timing))
            set_inference(run_dir, recipe)
            return run_dir, timing
    log = out / "logs" / f"train-{run_dir.name}.log"
    last = run_dir / "checkpoints" / "last"
    if (last / "training_state" / "training_step.json").is_file() and running_path.is_file():
        running = resume_marker(running_path, last)
        print(f"resuming {run_dir} after {running['resumed'][-1]['step']} updates")
        seconds = run([str(BIN / "lerobot-train"), f"--config_path={last / 'pretrained_model' / 'train_config.json'}",
                       "--resume=true", f"--dataset.root={data}", f"--output_dir={run_dir}"], log, append=True)
    else:
        if run_dir.exists():
            print(f"removing {run_dir}, an unfinished training run with no checkpoint or no {running_path.name}"
                  " to resume from")
            shutil.rmtree(run_dir)
        longer = longer_run(run_dir, steps)
        if longer is not None:
            print(f"taking the first {steps} updates of {longer}")
            timing = first_updates(longer, steps, run_dir)
            average(run_dir, k)
            store(run_dir, weights)
            timing_path.write_text(json.dumps(timing))
            set_inference(run_dir, recipe)
            return run_dir, timing
        running = {"started": time.time(), "settings": train_settings(recipe, init), "resumed": []}
        run_dir.parent.mkdir(parents=True, exist_ok=True)
        running_path.write_text(json.dumps(running))
        seconds = run(train_command(recipe, data, steps, seed, run_dir, init), log)
    average(run_dir, k)  # before the timing marks the run finished: every score is of the stored weights
    store(run_dir, weights)
    kept = sum(r["kept_s"] for r in running["resumed"])
    timing = {"started": running["started"], "wall_s": round(kept + seconds, 1),
              "settings": running["settings"], **({"resumed": running["resumed"]} if running["resumed"] else {})}
    timing_path.write_text(json.dumps(timing))
    running_path.unlink()
    return run_dir, timing


def set_inference(run_dir: Path, recipe: Recipe) -> None:
    """Give every checkpoint of a reused run the recipe's inference settings (``inference()`` of its policy settings).

    They decide how the policy acts, not its weights (``lerobot-train`` reads neither),
    so a run trained under other inference settings is the run the recipe would train.
    """
    wanted = recipe.policy.inference()
    for model in sorted(run_dir.glob("checkpoints/*/pretrained_model")):
        if model.parent.is_symlink():
            continue
        for name, section in (("config.json", None), ("train_config.json", "policy")):
            path = model / name
            if not path.is_file():
                continue
            data = json.loads(path.read_text())
            settings = data if section is None else data[section]
            if {k: settings.get(k) for k in wanted} != wanted:
                print(f"{path}: inference settings {wanted}")
                settings.update(wanted)
                path.write_text(json.dumps(data, indent=4))


def checkpoints(run_dir: Path, timing: dict) -> list[tuple[int, float, Path]]:
    """Every checkpoint of a training run as (update, minutes of training when it was saved, pretrained_model)."""
    found = []
    for step_dir in sorted((run_dir / "checkpoints").iterdir()):
        if step_dir.name.isdigit() and not step_dir.is_symlink():
            saved = (step_dir / "training_state" / "training_step.json").stat().st_mtime
            gaps = sum(r["gap_s"] for r in timing.get("resumed", ()) if r["at"] < saved)
            found.append((int(step_dir.name), (saved - timing["started"] - gaps) / 60, step_dir / "pretrained_model"))
    return found


def score_policy(recipe: Recipe, model: Path, variant: str, episodes: int, stem: Path, envs: int, log_dir: Path,
             first_seed: int | None = None, shift: str = "") -> dict:
    """``colorsort-eval`` of ``model`` on ``variant``'s first ``episodes`` evaluation seeds into
    ``<stem>-<key>.json`` (reused if there); with ``first_seed``, on the seeds from it instead (validation seeds);
    with ``shift`` (training ranges, ``--shift``), under it. The key is the evaluation's typed settings
    (``EvalCommandConfig.settings``) and the versions of the code that makes its episodes."""
    config = eval_config(recipe, model, variant, episodes, envs, first_seed, shift)
    code = code_versions("cell", *(("shifts",) if shift else ()))
    path = stem.with_name(cache.name(stem.name, {"colorsort-eval": config.settings(), "code": code}) + ".json")
    if path.is_file():
        print(f"reusing {path}")
        return json.loads(path.read_text())
    config = replace(config, json=str(path), resume=True)  # an evaluation a Ctrl-C cut continues from its journal
    run([str(BIN / "colorsort-eval"), *config.argv()], log_dir / f"{stem.parent.name}-{path.stem}.log")
    return json.loads(path.read_text())


def eval_config(recipe: Recipe, model: Path, variant: str, episodes: int, envs: int, first_seed: int | None = None,
                shift: str = "") -> EvalCommandConfig:
    """The ``colorsort-eval`` that scores ``model`` on ``variant`` for a recipe (``score_policy``'s arguments)."""
    return EvalCommandConfig(policy=str(model), variant=variant, episodes=episodes, seed=first_seed,
                             episode_length=recipe.evaluation.episode_length,
                             executor=ExecutorConfig(workers=envs), shift=tuple(s for s in shift.split(",") if s))
