"""Shipping a trained policy: LeRobot's ``pretrained_model`` files, its scores as JSON, plots and a README."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path

from colorsort.training.recipes import RELIGHT_TEMPERATURE, Recipe
from colorsort.training.report import curve_table, summary_table, table, validation_table
from colorsort.variants import LIGHT_BRIGHTNESS, VALIDATION_SEEDS, get_variant


def commit(shipped: Path | None = None) -> str:
    """The checkout's commit (marked when it has uncommitted changes outside ``shipped``, the folder being
    shipped, whose tracked files a reship replaces), or why there is none."""
    exclude = [f":(exclude){shipped.resolve()}"] if shipped is not None else []
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ":/", *exclude],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return sha + (" (with uncommitted changes)" if dirty else "")


def parameters(model: Path) -> int:
    """Parameters stored in a pretrained_model folder's weights."""
    from safetensors import safe_open

    with safe_open(str(model / "model.safetensors"), "np") as f:
        return sum(math.prod(f.get_slice(k).get_shape()) for k in f.keys())


def machine(device: str) -> str:
    """One line: this machine's CPU cores and the training device."""
    return f"a {os.cpu_count()}-core machine, training on {'the CPU' if device == 'cpu' else device}"


def lights(recipe: Recipe, variant: str) -> str:
    """" under lights of brightness x0.45-0.75" where the recipe collects ``variant``'s demos so, else ""."""
    brightness = recipe.brightness_on(variant)
    return f" under lights of brightness x{brightness[0]:g}-{brightness[1]:g}" if brightness else ""


def holds(recipe: Recipe) -> str:
    """"; every belt pass held back 0-100 steps, every pick 0-10" for the recipe's late passes and picks, else ""."""
    held = [f"every belt pass held back 0-{recipe.late_pass} steps"] if recipe.late_pass else []
    if recipe.late_pick:
        held.append(f"every pick 0-{recipe.late_pick}" if held else f"every pick held back 0-{recipe.late_pick} steps")
    return "; " + ", ".join(held) if held else ""


def ship(recipe: Recipe, model: Path, results: dict, plots: list[Path], dest: Path, command: str) -> None:
    """Copy ``model`` to ``dest`` with ``scores.json`` (``results``), the plots and a README of how it was made."""
    dest.mkdir(parents=True, exist_ok=True)
    for f in model.iterdir():
        shutil.copy2(f, dest / f.name)
    for p in plots:
        shutil.copy2(p, dest / p.name)
    (dest / "scores.json").write_text(json.dumps(results, indent=1))
    every_seed = [r for r in results["rows"] if r["demos_tried"] == recipe.demos[-1]]
    largest = [r for r in every_seed if r["seed"] == recipe.seeds[0]]
    size_mb = sum(f.stat().st_size for f in dest.iterdir()) / 1e6
    mix = ", ".join(f"{c} on {v}{lights(recipe, v)}" for v, c in recipe.split(recipe.demos[-1]).items())
    inputs = (f"`observation.state` and the cameras {', '.join(recipe.cameras)} at {recipe.image_size} px, never "
              "`observation.environment_state`: the policy sees the boxes" if recipe.cameras else
              "`observation.state` and `observation.environment_state` (the simulator's box state): no cameras")
    boxes = f"{recipe.boxes_per_episode} boxes each" + "".join(
        f", {variant}'s {n}" for variant, n in recipe.boxes_by_variant)
    backbone = ", its ResNet-18 trained from scratch (no pretrained weights)" if recipe.cameras else ""
    if recipe.image_shift:
        backbone += f", every training image shifted at random by up to {recipe.image_shift:g} of its size"
    if recipe.image_relight:
        (b_lo, b_hi), (t_lo, t_hi) = LIGHT_BRIGHTNESS, RELIGHT_TEMPERATURE
        backbone += f", every training image relit at random (brightness x{b_lo:g}-{b_hi:g}, {t_lo:,}-{t_hi:,} K)"
    curve = ""
    if results.get("curve"):
        curve = (f"\nLearning curve on `{recipe.main_variant}` (each checkpoint on the first {recipe.curve_episodes} "
                 f"evaluation seeds; `learning_curve.png`):\n\n{curve_table(results['curve'])}\n")
    seeds = ""
    if len(recipe.seeds) > 1:
        seeds = (f"\nThe same data and updates with each of the recipe's {len(recipe.seeds)} training seeds "
                 f"({', '.join(map(str, recipe.seeds))}; this policy is seed {recipe.seeds[0]}'s):\n\n"
                 f"{summary_table(every_seed, recipe.label)}\n")
    chosen = ""
    if any("validation" in r for r in every_seed):
        chosen = (f"\nThe checkpoint scored (and shipped) is the one of each run that did best on "
                  f"{recipe.select_episodes} episodes of each training variant on validation seeds "
                  f"({VALIDATION_SEEDS[0]} on, never scored; `colorsort.training.selection`):\n\n"
                  f"{validation_table(every_seed)}\n")
    at = f" (shipped: its checkpoint after {largest[0]['checkpoint']})" if "checkpoint" in largest[0] else ""
    cameras = ",".join(recipe.cameras) or "none"
    task = get_variant(recipe.main_variant).gym_id.removeprefix("colorsort/")
    (dest / "README.md").write_text(f"""# {dest.name}: a learned baseline for ColorSort, {recipe.label}

{recipe.policy.describe(parameters(dest))}{backbone}, on {inputs}.
{size_mb:.1f} MB.

Made by `{command}` (recipe `{recipe.name}`) on commit {commit(dest)}, started {results['started']}, on
{machine(recipe.device)}: {recipe.demos[-1]} expert demos tried ({mix}; {boxes}{holds(recipe)}),
{largest[0]['demos']} kept, {largest[0]['steps']} updates at batch {recipe.batch_size} in
{largest[0]['train_minutes']:.0f} min of `lerobot-train`{at}. Stages reused from earlier runs of the same command
count with the time they took then.

Run it:

```
colorsort-eval --policy {dest} --variant {recipe.main_variant} --episodes 50
HF_HUB_OFFLINE=1 lerobot-eval --env.type=colorsort --env.task={task} --env.cameras={cameras} \\
    --env.image_size={recipe.image_size} --policy.path={dest} --policy.device=cpu \\
    --eval.n_episodes=50 --eval.batch_size=2
```

Scores (`colorsort-eval`, each variant's fixed evaluation seeds; `scores.json` holds them with every episode):

{table(largest, recipe.label)}
{seeds}{chosen}{curve}""")
    print(f"shipped {dest} ({size_mb:.1f} MB)")

