"""Docs tables written from a shipped baseline's ``scores.json``, never typed.

A Markdown page marks where a baseline's table goes::

    <!-- scores baselines/act-camera table -->
    (generated: do not edit)
    <!-- end scores -->

``fill`` rewrites everything between the two markers from ``baselines/act-camera/scores.json``;
``python demos/baseline_tables.py`` does so for README.md and every page under ``docs/``, and a
test fails when a page differs from what its JSON gives. Kinds:

- ``table``: every scored row (with several training seeds: mean, range and each seed);
- ``curve``: the learning curve, success on the main variant at each checkpoint.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from colorsort.training.report import curve_table, summary_table

KINDS = ("table", "curve")
BLOCK = re.compile(r"(<!-- scores (?P<dir>\S+) (?P<kind>\S+) -->\n)(?P<body>.*?)(<!-- end scores -->)", re.S)


def label(scores: dict) -> str:
    """The policy's label in a table ("ACT, sensor+wrist"), from the recipe stored with its scores."""
    cameras = scores["recipe"]["cameras"]
    return f"ACT, {'+'.join(cameras) if cameras else 'state'}"


def render(scores: dict, kind: str) -> str:
    """The Markdown ``kind`` table of a baseline's ``scores.json`` contents."""
    if kind == "table":
        return summary_table(scores["rows"], label(scores))
    if kind == "curve":
        if not scores.get("curve"):
            raise ValueError("this baseline's scores.json has no learning curve "
                             "(it saved no checkpoints along the way)")
        return curve_table(scores["curve"])
    raise ValueError(f"Unknown table kind {kind!r}. Valid kinds: {list(KINDS)}")


def fill(text: str, root: Path) -> str:
    """``text`` with every scores block rewritten from ``root/<dir>/scores.json``."""
    def block(m: re.Match) -> str:
        path = root / m["dir"] / "scores.json"
        if not path.is_file():
            raise ValueError(f"a scores block names {m['dir']}, which has no scores.json")
        scores = json.loads(path.read_text())
        note = f"Written by `python demos/baseline_tables.py` from `{m['dir']}/scores.json` ({scores['command']}):"
        return f"{m[1]}{note}\n\n{render(scores, m['kind'])}\n\n{m[5]}"

    return BLOCK.sub(block, text)


def pages(root: Path) -> list[Path]:
    """The pages that may hold scores blocks: README.md and the docs."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]
