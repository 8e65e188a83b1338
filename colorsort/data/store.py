"""The on-disk store: what may be at the output, the collector's marker, staging and publishing.

The output directory only ever holds a complete dataset: shards are recorded in a hidden staging
folder beside it (``.<name>.staging``) and the merged result replaces the output in one rename.
``meta/colorsort.json`` (the marker) keeps the settings, the episode number of each dataset
episode in order, every episode number tried, why failed ones failed, and the sim-state layout.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from colorsort.data.config import CollectConfig

MARKER = "meta/colorsort.json"  # the collector's record: settings and the episodes tried


def read_marker(root: Path) -> dict | None:
    path = Path(root) / MARKER
    return json.loads(path.read_text()) if path.is_file() else None


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
            raise FileExistsError(f"{root} exists and is not a LeRobot dataset: not overwriting it")
        return None
    if not config.resume:
        raise FileExistsError(f"{root} already exists. Pass --resume to add the missing episodes to it, "
                              "--overwrite to replace it, or choose another --out")
    marker = read_marker(root)
    if marker is None:
        raise ValueError(f"Cannot resume {root}: it has no {MARKER}, so it was not recorded by colorsort-collect")
    if marker["settings"] != config.settings():
        diff = {k: (marker["settings"].get(k), v) for k, v in config.settings().items() if marker["settings"].get(k) != v}
        raise ValueError(f"Cannot resume {root} with other settings (recorded, requested): {diff}")
    return marker


def fresh_staging(root: Path, log) -> Path:
    """An empty staging folder beside ``root`` (one left by a killed run is removed, and said so)."""
    staging = root.parent / f".{root.name}.staging"
    if staging.exists():
        log(f"removing {staging}, left by a run that was killed")
        shutil.rmtree(staging)
    staging.mkdir(parents=True)
    return staging


def publish(merged: Path, root: Path, staging: Path, record: dict) -> None:
    """Write the marker into ``merged`` and put it at ``root`` in one rename (the old dataset, if any,
    is moved into ``staging`` first)."""
    (merged / MARKER).write_text(json.dumps(record))
    if root.exists():
        root.rename(staging / "previous")
    merged.rename(root)


def dir_size_mb(root: Path) -> float:
    return sum(f.stat().st_size for f in root.rglob("*") if f.is_file()) / 1e6
