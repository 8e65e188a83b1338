"""A run's journal: every finished episode written as it arrives, so an interrupted sweep or evaluation resumes.

A whole sweep runs for many minutes on a few cores (docs/shifts.md); the journal, ``<--json>.partial.jsonl``, holds
one line per finished episode (its arm: a sweep's shift, or a plain run's ``variant/shifts``; its seed; its
``EpisodeResult``) after a header that says what made them (a plain run's says ``kind: evaluation``): the
policy's checkpoint (a digest of its files), the variant, the cameras and image size, the episode length and the
versions of the code that runs an episode (``colorsort.versions``: the cell, the expert, the shifts). An
episode of a sweep depends on its shift and seed alone, whatever the other arms, the workers or the jobs
(``tests/test_shifts.py``), so ``--resume`` runs only the episodes the journal lacks, and may add arms or episodes;
a journal whose header differs from the sweep asked for is refused, naming what differs, never reused. A line cut
short by a kill is dropped (that episode runs again). The journal is removed once the sweep's JSON is written.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.errors import ConfigError
from colorsort.versions import code_versions

FORMAT = 1
Key = tuple[str, int]  # (the arm's shift label, "none" for the control; the episode's seed)


def journal_path(json_path: str | Path) -> Path:
    """Where the sweep writing ``json_path`` keeps its journal."""
    path = Path(json_path)
    return path.with_name(path.name + ".partial.jsonl")


def checkpoint_digest(policy: str) -> str:
    """16 hex digits of the SHA-256 of a checkpoint folder's files (names and bytes; not its subfolders, where a
    baseline keeps other training seeds' policies); the name of ``expert`` or ``random``, whose code the versions
    cover."""
    folder = Path(policy)
    if not folder.is_dir():
        return policy
    sha = hashlib.sha256()
    for f in sorted(p for p in folder.iterdir() if p.is_file()):
        sha.update(f.relative_to(folder).as_posix().encode())
        sha.update(f.read_bytes())
    return sha.hexdigest()[:16]


def header(policy: str, variant: str, cameras: tuple[str, ...], image_size: tuple[int, int],
           episode_length: int | None) -> dict[str, Any]:
    """What made a sweep's episodes: a journal is resumed only by a sweep with the same header."""
    return {"format": FORMAT, "policy": str(policy), "checkpoint": checkpoint_digest(policy), "variant": variant,
            "cameras": list(cameras), "image_size": list(image_size), "episode_length": episode_length,
            "versions": code_versions("cell", "expert", "shifts")}


class SweepJournal:
    """The journal of one sweep: ``done`` (the episodes it holds) and ``add`` (one more, written at once)."""

    def __init__(self, path: Path, head: dict[str, Any], resume: bool):
        """Open ``path`` for the sweep ``head`` describes. Without ``resume`` an existing journal is refused (its
        episodes are not discarded silently); with it, a journal of another sweep is refused, naming what differs.

        Raises:
            ConfigError: as above.
        """
        self.path, self.done = path, {}
        if path.exists():
            if not resume:
                raise ConfigError(f"{path} holds the finished episodes of an unfinished sweep: --resume continues it "
                                  f"(the same command with --resume), or remove the file to start again")
            self.done = self.read(head)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(head) + "\n")

    def read(self, head: dict[str, Any]) -> dict[Key, EpisodeResult]:
        lines = self.path.read_text().splitlines()
        found = json.loads(lines[0]) if lines else {}
        differ = sorted(k for k in head.keys() | found.keys() if head.get(k) != found.get(k))
        if differ:
            said = "; ".join(f"{k}: {found.get(k)!r} there, {head.get(k)!r} now" for k in differ)
            raise ConfigError(f"{self.path} is the journal of another sweep ({said}): remove it to start again")
        done: dict[Key, EpisodeResult] = {}
        kept = [lines[0]]
        for line in lines[1:]:
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:  # the last line, cut short by a kill: that episode runs again
                continue
            done[(entry["shift"], entry["seed"])] = EpisodeResult(**entry["result"])
            kept.append(line)
        if len(kept) < len(lines):  # rewritten whole, so the next line does not continue a cut one
            partial = self.path.with_name(self.path.name + ".tmp")
            partial.write_text("\n".join(kept) + "\n")
            partial.replace(self.path)
        return done

    def add(self, shift: str, result: EpisodeResult) -> None:
        """Write one finished episode (``shift``: its arm's label) and flush it to disk."""
        fields = asdict(result)
        fields.pop("video")
        with self.path.open("a") as f:
            f.write(json.dumps({"shift": shift, "seed": result.seed, "result": fields}) + "\n")
        self.done[(shift, result.seed)] = result

    def finish(self) -> None:
        """The sweep's JSON is written: the journal has served."""
        self.path.unlink(missing_ok=True)
