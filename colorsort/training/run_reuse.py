"""Training runs made in part: a run resumed after an interruption (what counts as its training time), and a
shorter run taken from a longer one's first checkpoints under a constant learning rate."""

from __future__ import annotations

import json
import re
import shutil
import time
from pathlib import Path


def resume_marker(running_path: Path, last: Path) -> dict:
    """The interrupted run's marker with this resumption added to ``"resumed"``: the update it resumes after, when
    [unix time], the training kept from the segment it ends (``kept_s``: from the segment's start to its last
    checkpoint's save) and the gap since that save (``gap_s``: the updates after the checkpoint are lost, the wait is
    not training; neither counts as training time)."""
    running = json.loads(running_path.read_text())
    state = last / "training_state" / "training_step.json"
    saved, now = state.stat().st_mtime, time.time()
    segment_start = running["resumed"][-1]["at"] if running["resumed"] else running["started"]
    running["resumed"].append({"step": json.loads(state.read_text())["step"], "at": now,
                               "kept_s": round(max(0.0, saved - segment_start), 1),  # 0: no checkpoint since
                               "gap_s": round(now - max(saved, segment_start), 1)})
    running_path.write_text(json.dumps(running))
    return running


def longer_run(run_dir: Path, steps: int) -> Path | None:
    """A finished run like ``run_dir`` (same data, settings and seed) but longer, with a checkpoint at ``steps``.

    Under a constant learning rate (``train_config.json``'s ``scheduler`` null) nothing in ``lerobot-train``'s
    first ``steps`` updates depends on the total (the sampler, the augmentations and the optimizer draw from the
    seed alone), so that checkpoint is the last one of a run of ``steps`` updates. A schedule (cosine) depends on
    the total: such a run is never used.
    """
    name = re.fullmatch(r"(.+)-(\d+)steps(.*)", run_dir.name)
    assert name is not None, run_dir
    found = []
    for other in run_dir.parent.glob("*"):  # none when train/ is not there yet
        match = re.fullmatch(rf"{re.escape(name[1])}-(\d+)steps{re.escape(name[3])}", other.name)
        model = other / "checkpoints" / f"{steps:06d}" / "pretrained_model"
        if (match and int(match[1]) > steps and (model / "train_config.json").is_file()
                and other.with_name(other.name + ".json").is_file()
                and json.loads((model / "train_config.json").read_text()).get("scheduler") is None):
            found.append((int(match[1]), other))
    return min(found)[1] if found else None


def first_updates(longer: Path, steps: int, run_dir: Path) -> dict:
    """``run_dir`` made of ``longer``'s checkpoints up to ``steps`` (copied, times kept); its timing.

    Its wall time is the time ``longer`` took to reach ``steps`` (its checkpoint's save time minus its start)."""
    timing = json.loads(longer.with_name(longer.name + ".json").read_text())
    for step_dir in sorted((longer / "checkpoints").iterdir()):
        if step_dir.name.isdigit() and not step_dir.is_symlink() and int(step_dir.name) <= steps:
            shutil.copytree(step_dir, run_dir / "checkpoints" / step_dir.name, copy_function=shutil.copy2)
    (run_dir / "checkpoints" / "last").symlink_to(f"{steps:06d}")
    saved = (run_dir / "checkpoints" / "last" / "training_state" / "training_step.json").stat().st_mtime
    return {"started": timing["started"], "wall_s": round(saved - timing["started"], 1),
            "first_updates_of": longer.name}
