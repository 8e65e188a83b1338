"""Recording in several processes: episode numbers split into contiguous shards, one worker each.

Workers fork from a ``forkserver`` that imported the recorder and lerobot (seconds of torch) once
and has never opened a GL context; each worker opens its own. Ctrl-C goes to the parent, which
asks the workers to stop through an event: each finalizes what it saved.
"""

from __future__ import annotations

import multiprocessing as mp
import queue
import shutil
import signal
import traceback
from pathlib import Path
from typing import Callable

import numpy as np

from colorsort.data.config import CollectConfig
from colorsort.data.recorder import EpisodeResult, ShardReport, record_shard
from colorsort.logs import quiet_robosuite_info


def split(indices: list[int], parts: int) -> list[list[int]]:
    """``indices`` in ``parts`` contiguous blocks, sizes differing by at most one."""
    sizes = [len(indices) // parts + (k < len(indices) % parts) for k in range(parts)]
    starts = np.cumsum([0] + sizes)
    return [indices[starts[k] : starts[k + 1]] for k in range(parts) if sizes[k] > 0]


def context():
    """The multiprocessing context workers (and the merge) run in."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["colorsort.data.recorder", "lerobot.datasets.lerobot_dataset",
                                "lerobot.datasets.aggregate"])
    return ctx


def _worker(config: CollectConfig, indices: list[int], root: str, messages, stop_event) -> None:
    """A recording process: Ctrl-C goes to the parent, which asks it to stop through ``stop_event``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    quiet_robosuite_info()
    try:
        shard = record_shard(config, indices, Path(root), lambda r: messages.put(("episode", r)), stop_event.is_set)
    except BaseException:  # noqa: BLE001 - e.g. the env could not be built
        shard = ShardReport(root, error=traceback.format_exc())
    messages.put(("shard", shard))


def run_workers(config: CollectConfig, blocks: list[list[int]], staging: Path,
                on_episode: Callable[[EpisodeResult], None], log: Callable[[str], None]) -> list[ShardReport]:
    """Record ``blocks`` side by side into ``staging/shard-KK``; returns the shards' reports, in order."""
    ctx = context()
    messages, stop_event = ctx.Queue(), ctx.Event()
    procs = [ctx.Process(target=_worker, args=(config, b, str(staging / f"shard-{k:02d}"), messages, stop_event),
                        daemon=False) for k, b in enumerate(blocks)]
    for p in procs:
        p.start()
    shards: dict[str, ShardReport] = {}
    while len(shards) < len(procs):
        try:
            kind, payload = messages.get(timeout=0.5)
        except queue.Empty:
            dead = [p for p in procs if not p.is_alive() and p.exitcode not in (0, None)]
            if dead and messages.empty():
                for k, p in enumerate(procs):
                    root = str(staging / f"shard-{k:02d}")
                    if not p.is_alive() and root not in shards and p.exitcode != 0:
                        shards[root] = ShardReport(root, error=f"worker {k} died with exit code {p.exitcode}")
            continue
        except KeyboardInterrupt:
            log("stopping: the workers finish saving what they recorded ...")
            stop_event.set()
            continue
        if kind == "episode":
            on_episode(payload)
        else:
            shards[payload.root] = payload
    for p in procs:
        p.join()
    return [shards[str(staging / f"shard-{k:02d}")] for k in range(len(procs))]


def merge(sources: list[Path], dest: Path, repo_id: str) -> None:
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
    """``merge`` in a worker process: the parent never has to import lerobot."""
    p = context().Process(target=merge, args=(sources, dest, repo_id))
    p.start()
    p.join()
    if p.exitcode != 0:
        raise RuntimeError(f"merging {len(sources)} datasets into {dest} failed (exit code {p.exitcode}); "
                           f"the recorded shards are kept in {dest.parent}")
