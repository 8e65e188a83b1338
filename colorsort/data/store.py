"""The on-disk store: what may be at the output, the collector's marker, staging and publishing.

The output directory only ever holds a complete dataset: shards are recorded in a hidden staging
folder beside it (``.<name>.staging``) and the merged result replaces the output in one rename.
``meta/colorsort.json`` (the marker) keeps the settings, the episode number of each dataset
episode in order, every episode number tried, why failed ones failed, the sim-state layout, and for data
recorded under shifts' training ranges (``--shift``) what each kept episode drew (``draws``: its episode number
-> per shift, its level and values, as ``colorsort-eval --json`` records them).
The staging folder outlives a run that was killed: its ``run.json`` names the run (an id and the
settings) that its finished shards belong to, and ``--resume`` keeps them. ``StagingRun`` owns
that folder for one run: it opens it, lists and checks its shards, and publishes or discards it.
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from colorsort.data.config import CollectConfig
from colorsort.errors import DataConflictError, DataExistsError

MARKER = "meta/colorsort.json"  # the collector's record: settings and the episodes tried
RUN_FILE = "run.json"  # in the staging folder: the run its shards belong to
SHARD_MARKER = "meta/colorsort-shard.json"  # in a shard: written once it is finished


def write_whole(path: Path, content: dict) -> None:
    """``content`` as JSON at ``path``, which appears whole or not at all (a process killed while
    writing leaves the old file, or none)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(content))
    os.replace(tmp, path)


def read_marker(root: Path) -> dict | None:
    path = Path(root) / MARKER
    return json.loads(path.read_text()) if path.is_file() else None


def settings_diff(recorded: dict, config: CollectConfig) -> dict:
    """The settings that differ: name -> (recorded, requested)."""
    return {k: (recorded.get(k), v) for k, v in config.settings().items() if recorded.get(k) != v}


def check_output(config: CollectConfig, root: Path) -> dict | None:
    """Validate what is at ``root`` against --resume / --overwrite; returns the marker to resume from.

    Raises:
        FileExistsError: the output exists and neither --resume nor --overwrite was given, or it is
            not a LeRobot dataset. ValueError: --resume on a dataset recorded with other settings.
    """
    if not root.exists():
        return None
    if root.is_dir() and not any(root.iterdir()):
        return None
    is_dataset = (root / "meta" / "info.json").is_file()
    if config.overwrite:
        if not is_dataset:
            raise DataExistsError(f"{root} exists and is not a LeRobot dataset: not overwriting it")
        return None
    if not config.resume:
        raise DataExistsError(f"{root} already exists. Pass --resume to add the missing episodes to it, "
                              "--overwrite to replace it, or choose another --out")
    marker = read_marker(root)
    if marker is None:
        raise DataConflictError(f"Cannot resume {root}: it has no {MARKER}, so it was not recorded by "
                                "colorsort-collect")
    if marker["settings"] != config.settings():
        raise DataConflictError(f"Cannot resume {root} with other settings (recorded, requested): "
                                f"{settings_diff(marker['settings'], config)}")
    return marker


def open_staging(config: CollectConfig, root: Path, log) -> tuple[Path, str]:
    """The staging folder beside ``root`` and its run id: the one a killed run left, on --resume;
    else a new one (a killed run's folder with no finished shard in it is removed, and said so).

    Raises:
        FileExistsError: a killed run left finished shards and neither --resume nor --overwrite was given.
        ValueError: --resume with other settings than the killed run's.
    """
    staging = root.parent / f".{root.name}.staging"
    run_file = staging / RUN_FILE
    if staging.exists():
        done = finished_shards(staging)
        if config.resume and run_file.is_file():
            run = json.loads(run_file.read_text())
            if run["settings"] != config.settings():
                raise DataConflictError(f"Cannot resume the run in {staging} with other settings "
                                        f"(recorded, requested): {settings_diff(run['settings'], config)}")
            return staging, run["run"]
        if done and not config.overwrite:
            episodes = sum(len(m["kept"]) for _, m in done)
            raise DataExistsError(f"{staging} holds {len(done)} finished shards ({episodes} episodes kept) of a run "
                                  "that was killed. Pass --resume to keep them and record the rest, or --overwrite "
                                  "to discard them")
        log(f"removing {staging}, left by a run that was killed")
        shutil.rmtree(staging)
    staging.mkdir(parents=True)
    run = uuid.uuid4().hex[:12]
    write_whole(run_file, {"run": run, "settings": config.settings()})
    return staging, run


def publish(merged: Path, root: Path, staging: Path, record: dict) -> None:
    """Write the marker into ``merged`` and put it at ``root`` in one rename (the old dataset, if any,
    is moved into ``staging`` first)."""
    (merged / MARKER).write_text(json.dumps(record))
    if root.exists():
        root.rename(staging / "previous")
    merged.rename(root)


def dir_size_mb(root: Path) -> float:
    return sum(f.stat().st_size for f in root.rglob("*") if f.is_file()) / 1e6


def read_shard(root: Path) -> dict | None:
    """A finished shard's marker; None while it is unfinished (or was killed)."""
    path = Path(root) / SHARD_MARKER
    return json.loads(path.read_text()) if path.is_file() else None


def finished_shards(staging: Path) -> list[tuple[Path, dict]]:
    """The finished shards in ``staging`` with their markers, in episode order."""
    found = [(p, read_shard(p)) for p in sorted(Path(staging).glob("shard-*")) if p.is_dir()]
    return [(p, m) for p, m in found if m is not None]


def unfinished_shards(staging: Path) -> list[Path]:
    return [p for p in sorted(Path(staging).glob("shard-*")) if p.is_dir() and read_shard(p) is None]


def check_shards(shards: list[tuple[Path, dict]], run: str, config: CollectConfig, in_dataset: set[int]) -> None:
    """ValueError for a shard that is not this run's: another run id, other settings, or episodes that
    the dataset or another shard already holds."""
    seen = set(in_dataset)
    for path, marker in shards:
        if marker["run"] != run:
            raise DataConflictError(f"{path} was recorded by run {marker['run']}, not by run {run} that this staging "
                             "folder belongs to: it comes from another run; move it away")
        if marker["settings"] != config.settings():
            raise DataConflictError(f"{path} was recorded with other settings (recorded, requested): "
                             f"{settings_diff(marker['settings'], config)}")
        twice = seen & set(marker["tried"])
        if twice:
            raise DataConflictError(f"{path} holds episodes {sorted(twice)} that the dataset or another shard already "
                             "holds: it comes from another run; move it away")
        seen |= set(marker["tried"])


@dataclass
class StagingRun:
    """One collection run's staging folder beside the output ``root``, and what it knows.

    Attributes:
        marker: the output's marker when resuming a dataset (its episodes stay), else None.
        run: the run id the folder's shards must carry.
    """

    config: CollectConfig
    root: Path
    folder: Path
    run: str
    marker: dict | None

    @classmethod
    def open(cls, config: CollectConfig, root: Path, log: Callable[[str], None]) -> StagingRun:
        """Check the output (``check_output``), open the staging folder (``open_staging``), discard the
        shards a killed worker left unfinished and check the finished ones (``check_shards``)."""
        marker = check_output(config, root)
        folder, run = open_staging(config, root, log)
        for path in unfinished_shards(folder):
            log(f"discarding {path.name}: its worker was killed while recording it")
            shutil.rmtree(path)
        staging = cls(config, root, folder, run, marker)
        staging.shards()
        return staging

    def shards(self) -> list[tuple[Path, dict]]:
        """The finished shards on disk (of this run or a killed one it resumes), checked, in episode order."""
        found = finished_shards(self.folder)
        check_shards(found, self.run, self.config, set(self.marker["tried"]) if self.marker else set())
        return found

    def tried(self) -> tuple[set[int], dict[str, str]]:
        """Episode numbers tried so far (the dataset's and the finished shards'), and why the failed ones failed."""
        tried = set(self.marker["tried"]) if self.marker else set()
        failed = dict(self.marker.get("failed", {})) if self.marker else {}
        for _, m in self.shards():
            tried.update(m["tried"])
            failed.update(m["failed"])
        return tried, failed

    @property
    def merged(self) -> Path:
        """Where the merged dataset is built before it is published."""
        return self.folder / "merged"

    def publish(self, record: dict) -> None:
        """Put the merged dataset at the output with ``record`` as its marker, in one rename."""
        publish(self.merged, self.root, self.folder, record)

    def remember(self, tried: set[int], failed: dict[str, str]) -> None:
        """Nothing new was kept: record in the existing dataset's marker what was tried."""
        assert self.marker is not None
        self.marker.update(tried=sorted(tried), failed=failed)
        write_whole(self.root / MARKER, self.marker)

    def discard(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)
