"""Record the scripted expert's episodes as one LeRobot v3.0 dataset: the whole job.

Episode ``i`` (0 <= i < episodes) runs with env seed ``seed + i``, so a dataset is the same
whatever the executor, the number of workers or the shard size. ``collect`` checks the output
(``store.py``), records the missing episodes in shards of at most ``shard_size`` episodes on the
executor (``shards.py``, ``executors/``), merges every finished shard once, in episode order,
with LeRobot's ``aggregate_datasets`` and publishes the result in one rename.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from colorsort.data import store
from colorsort.data.config import CollectConfig
from colorsort.data.recorder import TriedEpisode
from colorsort.data.shards import PRELOAD, ShardJob, merge_in_child, merge_shards, record, shard_name, summary_of
from colorsort.executors.base import Task, TaskResult, chunks, forwarded_env
from colorsort.executors.factory import make_executor

# Set for every recorder (and passed to every worker), not at import: the AV1 encoder's banner and info
# lines off; one progress bar, not one per episode saved; Mesa's CPU renderer draws in the calling
# thread, with no helper threads competing with the video encoder and other workers for cores.
RECORDING_ENVIRONMENT = {"SVT_LOG": "1", "HF_DATASETS_DISABLE_PROGRESS_BARS": "1", "LP_NUM_THREADS": "0"}


@dataclass
class CollectSummary:
    root: str
    repo_id: str
    executor: str = "local"
    tried: int = 0  # episodes tried by this run
    kept: int = 0
    not_kept: dict[str, int] = field(default_factory=dict)  # reason -> episodes
    frames: int = 0  # frames recorded by this run (kept episodes)
    sim_time_s: float = 0.0  # [s] sim time recorded by this run (kept episodes)
    shards: int = 0  # shards this run recorded (or tried to)
    shards_kept: int = 0  # finished shards of an earlier, killed run that --resume kept
    retried: int = 0  # shards run again because their worker process died
    dataset_episodes: int = 0  # in the dataset at the end, earlier runs included
    dataset_frames: int = 0
    wall_s: float = 0.0
    size_mb: float = 0.0
    interrupted: bool = False
    errors: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)  # summed over shards, plus "merging"

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds recorded per wall-clock second."""
        return self.sim_time_s / self.wall_s if self.wall_s > 0 else 0.0


def collect(config: CollectConfig, progress: bool = True, log: Callable[[str], None] = print) -> CollectSummary:
    """Record, merge and report, as the module docstring says: plan, record, merge.

    Raises:
        FileExistsError: the output (or a killed run's staging folder) exists and neither --resume
            nor --overwrite was given.
        ValueError: --resume on a dataset, or a killed run's shards, recorded with other settings.
    """
    for key, value in RECORDING_ENVIRONMENT.items():
        os.environ.setdefault(key, value)
    start = time.perf_counter()
    root = Path(config.out).resolve()
    staging = store.StagingRun.open(config, root, log)
    summary = CollectSummary(str(root), config.repo_id, config.executor.name, shards_kept=len(staging.shards()))
    todo = plan(staging)
    if staging.marker and not todo and not summary.shards_kept:
        staging.discard()
        log(f"{root} already holds all {config.episodes} episodes tried; nothing to do")
        return summary
    record_shards(staging, todo, summary, progress)
    t = time.perf_counter()
    merge_and_publish(staging)
    summary.seconds["merging"] = time.perf_counter() - t
    summary.wall_s = time.perf_counter() - start
    info = root / "meta" / "info.json"
    if info.is_file():
        meta = json.loads(info.read_text())
        summary.dataset_frames, summary.dataset_episodes = meta["total_frames"], meta["total_episodes"]
        summary.size_mb = store.dir_size_mb(root)
    return summary


def plan(staging: store.StagingRun) -> list[int]:
    """The episode numbers still to record: those neither the dataset nor a finished shard has tried."""
    tried, _ = staging.tried()
    return [i for i in range(staging.config.episodes) if i not in tried]


class _Progress:
    """The progress bar and the summary's counters, fed by the executor's messages."""

    def __init__(self, summary: CollectSummary, episodes: int, shards: int, show: bool):
        self.summary, self.shards, self.done = summary, shards, 0
        self.bar = tqdm(total=episodes, unit="episode", desc="recording", disable=not show, smoothing=0.1)

    def on_episode(self, r: TriedEpisode) -> None:
        s = self.summary
        s.tried += 1
        if r.kept:
            s.kept, s.frames, s.sim_time_s = s.kept + 1, s.frames + r.frames, s.sim_time_s + r.sim_time_s
        else:
            s.not_kept[r.reason] = s.not_kept.get(r.reason, 0) + 1
        self.bar.update(1)
        self._show()

    def on_shard(self, result: TaskResult) -> None:
        self.done += 1
        self._show()

    def _show(self) -> None:
        s = self.summary
        self.bar.set_postfix(kept=s.kept, not_kept=s.tried - s.kept, shards=f"{self.done}/{self.shards}")


def record_shards(staging: store.StagingRun, todo: list[int], summary: CollectSummary, progress: bool) -> None:
    """Record ``todo`` in shards on the configured executor; each finished shard lands in the staging folder."""
    config = staging.config
    blocks = chunks(todo, config.shard_size, config.executor.workers)
    tasks = [Task(shard_name(b[0]), record, ShardJob(config, tuple(b), str(staging.folder / shard_name(b[0])),
                                                       staging.run)) for b in blocks]
    summary.shards = len(tasks)
    executor = make_executor(config.executor, PRELOAD, forwarded_env(RECORDING_ENVIRONMENT))
    bar = _Progress(summary, len(todo), len(tasks), progress)
    try:
        results = executor.run(tasks, bar.on_episode, bar.on_shard) if tasks else []
    finally:
        bar.bar.close()
    summary.retried = sum(r.attempts > 1 for r in results)
    summary.interrupted = any(r.stopped or (r.value and r.value.interrupted) for r in results)
    summary.errors = [r.error or r.value.error for r in results if r.error or (r.value and r.value.error)]
    for r in results:
        for key, value in (r.value.seconds if r.value else {}).items():
            summary.seconds[key] = summary.seconds.get(key, 0.0) + value


def merge_and_publish(staging: store.StagingRun) -> None:
    """Merge the dataset (when resuming) and every finished shard on disk, in episode order, and publish the
    result with its marker; with nothing new kept, only remember what was tried. The staging folder goes."""
    config, marker = staging.config, staging.marker
    shards = staging.shards()  # on disk: what every attempt, of this run or a killed one, finished
    tried, failed = staging.tried()
    reports = [summary_of(p, m) for p, m in shards]
    if any(s.kept for s in reports):
        sources = ([staging.root] if marker else []) + [Path(s.root) for s in reports if s.kept]
        merger = merge_shards if config.executor.name == "local" and config.executor.workers == 1 else merge_in_child
        merger(sources, staging.merged, config.repo_id)
        kept = (marker["episodes"] if marker else []) + [i for s in reports for i in s.kept]
        layout = next((s.sim_state for s in reports if s.sim_state), None)
        draws = {**(marker.get("draws", {}) if marker else {}), **{i: d for s in reports for i, d in s.draws.items()}}
        staging.publish({"settings": config.settings(), "episodes": kept, "tried": sorted(tried), "failed": failed,
                         "sim_state": layout, **({"draws": draws} if config.shift else {})})
    elif marker:
        staging.remember(tried, failed)
    staging.discard()
