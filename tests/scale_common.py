"""What the scale and crash tests share: a small state-only collection, its reference dataset, data comparisons,
and a worker killer."""

import json
import os
import signal
import threading
import time
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from colorsort.data.store import MARKER, SHARD_MARKER

# Four state-only episodes of two boxes each: long enough (seconds per episode) to kill a worker mid-shard.
SCALE = dict(episodes=4, boxes_per_episode=2, cameras=(), shard_size=2)
QUIET = dict(progress=False, log=lambda _: None)


def frames(root: Path) -> dict:
    """Every frame's columns, in dataset order."""
    tables = [pq.read_table(p).to_pydict() for p in sorted((root / "data").rglob("*.parquet"))]
    return {k: [v for t in tables for v in t[k]] for k in tables[0]}


def same_data(a: Path, b: Path) -> None:
    fa, fb = frames(a), frames(b)
    assert fa.keys() == fb.keys()
    for key in fa:
        assert np.array_equal(np.asarray(fa[key]), np.asarray(fb[key])), key
    assert json.loads((a / MARKER).read_text())["episodes"] == json.loads((b / MARKER).read_text())["episodes"]


def by_episode_number(root: Path) -> dict[int, dict]:
    """Each episode's frames, keyed by its episode number (seed - base seed), positions in the dataset left out."""
    f, numbers = frames(root), json.loads((root / MARKER).read_text())["episodes"]
    rows = np.asarray(f["episode_index"])
    return {n: {k: np.asarray(v)[rows == e] for k, v in f.items() if k not in ("episode_index", "index")}
            for e, n in enumerate(numbers)}


def same_episodes(a: Path, b: Path, only: Iterable[int] | None = None) -> None:
    """The same episodes (``only`` those numbers of ``a``: all of ``b``), each with the same data, in any order
    (--resume appends what it records)."""
    ea, eb = by_episode_number(a), by_episode_number(b)
    if only is not None:
        ea = {n: ea[n] for n in only}
    assert sorted(ea) == sorted(eb)
    for n in ea:
        for key in ea[n]:
            assert np.array_equal(ea[n][key], eb[n][key]), (n, key)


def kill_worker_of(staging: Path, shard: str, after_s: float, killed: list) -> threading.Thread:
    """Kill (SIGKILL) the process recording ``shard`` ``after_s`` seconds after it started it."""
    def watch():
        worker = staging / f"{shard}.worker.json"
        deadline = time.monotonic() + 120
        while not worker.is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(after_s)
        pid = json.loads(worker.read_text())["pid"]
        assert not (staging / shard / SHARD_MARKER).exists(), "the shard finished before it could be killed"
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread
