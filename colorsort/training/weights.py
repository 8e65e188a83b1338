"""How a training run's checkpoints store their weights: as ``lerobot-train`` writes them (float32) or rounded to
float16.

LeRobot's diffusion policy from one 64 px camera with a U-Net of 64 and 128 channels has 12.56 M parameters: 50.3 MB
in float32, over what a shipped camera baseline may weigh (50 MB), 25 MB in float16. LeRobot loads either file into
its float32 model (``load_state_dict`` casts), so a rounded checkpoint is a policy like any other. The pipeline rounds
a run's checkpoints as soon as it has them, before it validates or scores any, so that every score is of the weights
stored; a float16 run is made from the float32 run of the same training where that one is there (``halved_copy``),
the rounding being the only difference.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

WEIGHTS = ("float32", "float16")
MODEL = "model.safetensors"
FULL = "model.float32.safetensors"  # in a checkpoint's training_state/


def store(run_dir: Path, weights: str) -> int:
    """Round every checkpoint of ``run_dir`` to ``weights`` (its floating tensors; nothing for float32); how many
    files it rewrote. The full-precision file is kept beside the optimizer's state (``training_state/``, never
    shipped: ``FULL``), so that what the rounding changes can be measured on the same training."""
    if weights == "float32":
        return 0
    import torch
    from safetensors.torch import load_file, save_file

    dtype = getattr(torch, weights)
    rewritten = 0
    for path in sorted(run_dir.glob(f"checkpoints/*/pretrained_model/{MODEL}")):
        if path.parent.parent.is_symlink():  # "last" points at a step's folder
            continue
        tensors = load_file(path)
        if all(t.dtype == dtype or not t.is_floating_point() for t in tensors.values()):
            continue
        mode, full = path.stat().st_mode, path.parent.parent / "training_state" / FULL
        if full.parent.is_dir() and not full.exists():
            shutil.copy2(path, full)
        save_file({k: t.to(dtype) if t.is_floating_point() else t for k, t in tensors.items()}, path,
                  metadata={"format": "pt"})
        path.chmod(mode)  # safetensors writes its files readable by their owner alone
        rewritten += 1
    return rewritten


def halved_copy(full: Path, run_dir: Path, weights: str) -> dict:
    """``run_dir`` made of the finished float32 run ``full``'s checkpoints rounded to ``weights``; its timing (the
    training's own, with ``"weights_of"`` naming ``full``)."""
    timing = json.loads(full.with_name(full.name + ".json").read_text())
    (run_dir / "checkpoints").mkdir(parents=True)
    for step_dir in sorted((full / "checkpoints").iterdir()):
        if step_dir.is_symlink():
            (run_dir / "checkpoints" / step_dir.name).symlink_to(step_dir.readlink())
        else:
            shutil.copytree(step_dir, run_dir / "checkpoints" / step_dir.name, copy_function=shutil.copy2)
    store(run_dir, weights)
    return {**timing, "weights_of": full.name}
