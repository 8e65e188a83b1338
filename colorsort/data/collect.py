"""Record the scripted expert's episodes as one LeRobot v3.0 dataset: the whole job.

Episode ``i`` (0 <= i < episodes) runs with env seed ``seed + i``, so a dataset is the same
whatever the number of workers. ``collect`` checks the output (``store.py``), records the
missing episodes in one or more shards (``recorder.py``, ``shards.py``), merges them with
LeRobot's ``aggregate_datasets`` and publishes the result in one rename.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from tqdm import tqdm

from colorsort.data import store
from colorsort.data.config import CollectConfig
from colorsort.data.recorder import EpisodeResult, ShardReport, record_shard
from colorsort.data.shards import merge, merge_in_child, run_workers, split

# Set for every recorder (and inherited by worker processes), not at import: the AV1 encoder's banner
# and info lines off; one progress bar, not one per episode saved; Mesa's CPU renderer draws in the
# calling thread, with no helper threads competing with the video encoder and other workers for cores.
RECORDING_ENVIRONMENT = {"SVT_LOG": "1", "HF_DATASETS_DISABLE_PROGRESS_BARS": "1", "LP_NUM_THREADS": "0"}


@dataclass
class CollectSummary:
    root: str
    repo_id: str
    tried: int = 0  # episodes tried by this run
    kept: int = 0
    not_kept: dict[str, int] = field(default_factory=dict)  # reason -> episodes
    frames: int = 0  # frames recorded by this run (kept episodes)
    sim_time_s: float = 0.0  # [s] sim time recorded by this run (kept episodes)
    dataset_episodes: int = 0  # in the dataset at the end, earlier runs included
    dataset_frames: int = 0
    wall_s: float = 0.0
    size_mb: float = 0.0
    interrupted: bool = False
    errors: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)  # summed over workers, plus "merging"

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds recorded per wall-clock second."""
        return self.sim_time_s / self.wall_s if self.wall_s > 0 else 0.0


def collect(config: CollectConfig, progress: bool = True, log: Callable[[str], None] = print) -> CollectSummary:
    """Record, merge and report, as the module docstring says.

    Raises:
        FileExistsError: the output exists and neither --resume nor --overwrite was given.
        ValueError: --resume on a dataset recorded with other settings.
    """
    for key, value in RECORDING_ENVIRONMENT.items():
        os.environ.setdefault(key, value)
    start = time.perf_counter()
    root = Path(config.out).resolve()
    marker = store.check_output(config, root)
    tried = set(marker["tried"]) if marker else set()
    failed = dict(marker.get("failed", {})) if marker else {}
    todo = [i for i in range(config.episodes) if i not in tried]
    summary = CollectSummary(str(root), config.repo_id)
    if marker and not todo:
        log(f"{root} already holds all {config.episodes} episodes tried; nothing to do")
        return summary
    staging = store.fresh_staging(root, log)
    blocks = split(todo, min(config.workers, len(todo)))
    shards: list[ShardReport] = []
    bar = tqdm(total=len(todo), unit="episode", desc="recording", disable=not progress, smoothing=0.1)

    def on_episode(r: EpisodeResult) -> None:
        tried.add(r.index)
        summary.tried += 1
        if r.kept:
            summary.kept += 1
            summary.frames += r.frames
            summary.sim_time_s += r.sim_time_s
        else:
            failed[str(r.index)] = r.reason
            summary.not_kept[r.reason] = summary.not_kept.get(r.reason, 0) + 1
        bar.update(1)
        bar.set_postfix(kept=summary.kept, not_kept=summary.tried - summary.kept)

    try:
        if len(blocks) == 1:
            shards.append(record_shard(config, blocks[0], staging / "shard-00", on_episode))
        else:
            shards = run_workers(config, blocks, staging, on_episode, log)
    finally:
        bar.close()
    summary.interrupted = any(s.interrupted for s in shards)
    summary.errors = [s.error for s in shards if s.error]
    for s in shards:
        for key, value in s.seconds.items():
            summary.seconds[key] = summary.seconds.get(key, 0.0) + value

    t = time.perf_counter()
    sources = ([root] if marker else []) + [Path(s.root) for s in shards if s.kept]
    if any(s.kept for s in shards):
        merged = staging / "merged"
        (merge_in_child if len(shards) > 1 else merge)(sources, merged, config.repo_id)
        kept = (marker["episodes"] if marker else []) + [i for s in shards for i in s.kept]
        layout = next((s.sim_state for s in shards if s.sim_state), None)
        record = {"settings": config.settings(), "episodes": kept, "tried": sorted(tried), "failed": failed,
                  "sim_state": layout}
        store.publish(merged, root, staging, record)
    elif marker:  # nothing new kept: still remember what was tried
        marker.update(tried=sorted(tried), failed=failed)
        (root / store.MARKER).write_text(json.dumps(marker))
    shutil.rmtree(staging, ignore_errors=True)
    summary.seconds["merging"] = time.perf_counter() - t
    summary.wall_s = time.perf_counter() - start
    info = root / "meta" / "info.json"
    if info.is_file():
        meta = json.loads(info.read_text())
        summary.dataset_frames, summary.dataset_episodes = meta["total_frames"], meta["total_episodes"]
        summary.size_mb = store.dir_size_mb(root)
    return summary
