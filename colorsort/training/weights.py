"""How a training run's checkpoints store their weights: as ``lerobot-train`` writes them (float32) or rounded to
float16, and each one's own or the mean of the latest few.

LeRobot's diffusion policy from one 64 px camera with a U-Net of 64 and 128 channels has 12.56 M parameters: 50.3 MB
in float32, over what a shipped camera baseline may weigh (50 MB), 25 MB in float16. LeRobot loads either file into
its float32 model (``load_state_dict`` casts), so a rounded checkpoint is a policy like any other. The pipeline rounds
a run's checkpoints as soon as it has them, before it validates or scores any, so that every score is of the weights
stored; a float16 run is made from the float32 run of the same training where that one is there (``derived_copy``),
the rounding being the only difference.

Diffusion Policy's own training scores an exponential moving average of the weights, which ``lerobot-train`` does not
keep; ``average`` gives a run's checkpoints the nearest thing its saved files allow: each one's weights the mean of its
own and the ``k - 1`` saved before it (latest weight averaging, Kaddour 2022), so that a checkpoint is not the
accident of its last few hundred updates. ``lerobot-train``'s own weights stay beside the training state (``FULL``).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

WEIGHTS = ("float32", "float16")
MODEL = "model.safetensors"
FULL = "model.float32.safetensors"  # in a checkpoint's training_state/


def _steps(run_dir: Path) -> list[Path]:
    """A run's checkpoint folders in the order they were saved (``last`` is a link to one of them)."""
    return sorted(p for p in (run_dir / "checkpoints").iterdir() if p.name.isdigit() and not p.is_symlink())


def saved_every(run_dir: Path, every: int, steps: int) -> bool:
    """Whether ``run_dir`` has a checkpoint every ``every`` updates up to ``steps`` (what averaging them needs)."""
    return {f"{s:06d}" for s in range(every, steps + 1, every)} <= {p.name for p in _steps(run_dir)}


def average(run_dir: Path, k: int) -> int:
    """Give every checkpoint of ``run_dir`` the mean of its own and the ``k - 1`` previous checkpoints' float32 weights
    (fewer for the first ones); how many files it rewrote. Each file's metadata names the checkpoints averaged
    (``"averaged"``), so a second call rewrites nothing; ``lerobot-train``'s own file is kept as ``FULL``."""
    if k < 2:
        return 0
    import torch
    from safetensors import safe_open
    from safetensors.torch import load_file, save_file

    folders = _steps(run_dir)
    for step_dir in folders:
        model, full = step_dir / "pretrained_model" / MODEL, step_dir / "training_state" / FULL
        if not full.exists():
            shutil.copy2(model, full)
    rewritten = 0
    for i, step_dir in enumerate(folders):
        window = folders[max(0, i - k + 1):i + 1]
        names = ",".join(p.name for p in window)
        model = step_dir / "pretrained_model" / MODEL
        with safe_open(str(model), "pt") as f:
            if (f.metadata() or {}).get("averaged") == names:
                continue
        total: dict[str, torch.Tensor] = {}
        for other in window:  # the last is step_dir itself, whose non-floating tensors (counters) are kept
            own = load_file(other / "training_state" / FULL)
            for key, tensor in own.items():
                total[key] = total[key] + tensor.double() if key in total else tensor.double()
        mean = {key: (total[key] / len(window)).to(t.dtype) if t.is_floating_point() else t for key, t in own.items()}
        mode = model.stat().st_mode
        save_file(mean, model, metadata={"format": "pt", "averaged": names})
        model.chmod(mode)
        rewritten += 1
    return rewritten


def store(run_dir: Path, weights: str) -> int:
    """Round every checkpoint of ``run_dir`` to ``weights`` (its floating tensors; nothing for float32); how many
    files it rewrote. The full-precision file is kept beside the optimizer's state (``training_state/``, never
    shipped: ``FULL``), so that what the rounding changes can be measured on the same training."""
    if weights == "float32":
        return 0
    import torch
    from safetensors import safe_open
    from safetensors.torch import load_file, save_file

    dtype = getattr(torch, weights)
    rewritten = 0
    for step_dir in _steps(run_dir):
        path = step_dir / "pretrained_model" / MODEL
        tensors = load_file(path)
        if all(t.dtype == dtype or not t.is_floating_point() for t in tensors.values()):
            continue
        mode, full = path.stat().st_mode, path.parent.parent / "training_state" / FULL
        if full.parent.is_dir() and not full.exists():
            shutil.copy2(path, full)
        with safe_open(str(path), "pt") as f:
            metadata = f.metadata() or {"format": "pt"}  # an averaged file's names the checkpoints in it
        save_file({k: t.to(dtype) if t.is_floating_point() else t for k, t in tensors.items()}, path, metadata=metadata)
        path.chmod(mode)  # safetensors writes its files readable by their owner alone
        rewritten += 1
    return rewritten


def derived_copy(twin: Path, run_dir: Path, weights: str, k: int = 1) -> dict:
    """``run_dir`` made of the finished run ``twin``'s checkpoints (``lerobot-train``'s own weights: float32, or
    rounded with the float32 file kept), each averaged over the latest ``k`` (``average``) and stored in ``weights``;
    its timing (the training's own, with ``"weights_of"`` naming ``twin``)."""
    timing = json.loads(twin.with_name(twin.name + ".json").read_text())
    (run_dir / "checkpoints").mkdir(parents=True)
    for step_dir in sorted((twin / "checkpoints").iterdir()):
        if step_dir.is_symlink():
            (run_dir / "checkpoints" / step_dir.name).symlink_to(step_dir.readlink())
        else:
            shutil.copytree(step_dir, run_dir / "checkpoints" / step_dir.name, copy_function=shutil.copy2)
            kept = run_dir / "checkpoints" / step_dir.name / "training_state" / FULL
            if kept.exists():  # a rounded twin: its float32 file is lerobot-train's
                shutil.copy2(kept, kept.parent.parent / "pretrained_model" / MODEL)
    average(run_dir, k)
    store(run_dir, weights)
    return {**timing, "weights_of": twin.name}
