"""Shards: collection's unit of work, each a complete LeRobot dataset of a few dozen episodes.

A shard records its episodes into ``<staging>/shard-NNNNNN`` (NNNNNN: its first episode number),
finalizes that dataset as soon as its last episode is saved, then writes its marker
``meta/colorsort-shard.json``: the run it belongs to, the settings, the episodes it tried and kept,
and why the others were not kept. A shard with no marker was killed while recording; it is
discarded and its episodes are recorded again. Beside each shard, ``shard-NNNNNN.worker.json``
says which process (host, pid) records it, and which attempt that is. The shards are merged once,
at the end, with LeRobot's ``aggregate_datasets``, in episode order.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import shutil
import socket
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from colorsort.data.config import CollectConfig
from colorsort.data.recorder import ShardSummary, record_shard
from colorsort.data.store import SHARD_MARKER, read_shard, write_whole
from colorsort.errors import StageError
from colorsort.executors.base import TaskContext

# What worker processes import once, before they fork (seconds of torch):
PRELOAD = ("colorsort.data.shards", "lerobot.datasets.lerobot_dataset", "lerobot.datasets.aggregate")


@dataclass(frozen=True)
class ShardJob:
    """One shard to record: episodes ``indices`` of ``config`` into ``root``, for run ``run``."""

    config: CollectConfig
    indices: tuple[int, ...]
    root: str  # absolute: workers may run elsewhere, on a shared file system
    run: str


def shard_name(first: int) -> str:
    return f"shard-{first:06d}"


def summary_of(root: Path, marker: dict) -> ShardSummary:
    return ShardSummary(str(root), tried=marker["tried"], kept=marker["kept"], failed=marker["failed"],
                       interrupted=marker["interrupted"], error=marker["error"], seconds=marker["seconds"],
                       sim_state=marker["sim_state"], draws=marker.get("draws", {}))


def record(job: ShardJob, ctx: TaskContext) -> ShardSummary:
    """The task that records one shard (run again after its process died: it starts the shard afresh)."""
    root = Path(job.root)
    marker = read_shard(root)
    if marker is not None:  # an earlier attempt finished it and then died
        return summary_of(root, marker)
    if root.exists():
        shutil.rmtree(root)  # what an attempt killed while recording left
    worker = root.with_name(root.name + ".worker.json")
    attempt = previous_attempt(worker) + 1
    write_whole(worker, {"host": socket.gethostname(), "pid": os.getpid(), "attempt": attempt,
                         "started": time.time()})
    report = record_shard(job.config, list(job.indices), root, ctx.send, ctx.stopping)
    if report.incomplete:  # no marker: the shard counts as unfinished and --resume records it again
        shutil.rmtree(root, ignore_errors=True)
        return report
    record_ = {"run": job.run, "settings": job.config.settings(), "indices": list(job.indices),
               **{k: v for k, v in asdict(report).items() if k != "root"}}
    write_whole(root / SHARD_MARKER, record_)
    return report


def previous_attempt(worker: Path) -> int:
    """The attempt number a shard's worker file records: 0 when there is none; 1 when it cannot be
    read (written by a version that wrote it in place, killed mid-write): at least one attempt was made."""
    if not worker.is_file():
        return 0
    try:
        return int(json.loads(worker.read_text())["attempt"])
    except (ValueError, KeyError, TypeError):
        return 1


def merge_shards(sources: list[Path], dest: Path, repo_id: str) -> None:
    """One dataset at ``dest`` from ``sources`` (complete datasets), episodes in order, with LeRobot's
    ``aggregate_datasets``."""
    if len(sources) == 1:
        shutil.move(sources[0], dest)
        return
    import warnings

    import av
    from lerobot.datasets.aggregate import aggregate_datasets

    av.logging.set_libav_level(av.logging.ERROR)  # FFmpeg's notes on every video it concatenates
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Cannot enable progress bars")
        aggregate_datasets([repo_id] * len(sources), repo_id, roots=sources, aggr_root=dest)


def merge_in_child(sources: list[Path], dest: Path, repo_id: str) -> None:
    """``merge_shards`` in a child process: the caller never has to import lerobot (seconds of torch)."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(list(PRELOAD))
    p = ctx.Process(target=merge_shards, args=(sources, dest, repo_id))
    p.start()
    p.join()
    if p.exitcode != 0:
        raise StageError(f"merging {len(sources)} datasets into {dest} failed (exit code {p.exitcode}); "
                           f"the recorded shards are kept in {dest.parent}")
