"""Names of the pipeline's cached stages, derived from the settings that feed each one.

A stage's folder or file is ``<stem>-<key>``: the stem says what it is for a reader (``jitter-8``,
``demos-48``), the key is the first 8 hex digits of the SHA-256 of its settings as sorted JSON, so any
setting that changes what a stage makes (a new perturbation, a learning rate) names another folder without
anyone inventing a suffix for it. The settings are typed (a ``CollectConfig``'s, not a command line's: a renamed
flag keys nothing) and hold the versions of the code that made the data (``colorsort.versions``), so a changed
expert, cell or recorder names new folders. Each stage folder keeps its settings in ``stage.json`` for the reader.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

SETTINGS_FILE = "stage.json"


def key(settings: dict[str, Any]) -> str:
    """8 hex digits that change whenever ``settings`` (JSON-able) do."""
    text = json.dumps(settings, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def name(stem: str, settings: dict[str, Any]) -> str:
    """``<stem>-<key>``: the cache name of a stage made from ``settings``."""
    return f"{stem}-{key(settings)}"


def remember(folder: Path, settings: dict[str, Any]) -> None:
    """Write the settings a stage folder was made from beside what it holds."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / SETTINGS_FILE).write_text(json.dumps(settings, indent=1, sort_keys=True) + "\n")
