"""Versions of the code whose output the pipeline caches: each bumped by the change that alters what it makes.

A cached stage's key holds the versions of the code that made its data beside its typed settings
(``colorsort.training.cache``), so a change to the expert names new demo folders instead of reusing the old
expert's; a sweep's journal of finished episodes holds them too (``colorsort.benchmark.sweep_journal``).
``tests/test_versions.py`` fails when a part's behaviour fingerprint changes and its version does not
(``python tests/fingerprints.py --write`` records the new one with the bumped version).
"""

from __future__ import annotations

EXPERT_VERSION = 2  # colorsort/expert: the scripted demonstrator's actions, from what it sees (2: the touch-off)
CELL_VERSION = 1  # colorsort/cell: physics, the belt, the seal, the referee, the box stream, rendering
RECORDER_VERSION = 2  # colorsort/data: what a recorded frame and a dataset's metadata hold (2: each episode's draws)
SHIFTS_VERSION = 1  # colorsort/shifts: what each held-out shift draws and changes at each level

VERSIONS: dict[str, int] = {"expert": EXPERT_VERSION, "cell": CELL_VERSION, "recorder": RECORDER_VERSION,
                           "shifts": SHIFTS_VERSION}


def code_versions(*parts: str) -> dict[str, int]:
    """The versions of ``parts`` (names of ``VERSIONS``), as a cache key holds them."""
    return {part: VERSIONS[part] for part in parts}
