"""Docs tables written from a shipped baseline's ``scores.json``, never typed.

A Markdown page marks where a baseline's table goes::

    <!-- scores baselines/act-camera table -->
    (generated: do not edit)
    <!-- end scores -->

``fill`` rewrites everything between the two markers from ``baselines/act-camera/scores.json``;
``python tools/baseline_tables.py`` does so for README.md and every page under ``docs/``, and a
test fails when a page differs from what its JSON gives. Kinds:

- ``table``: every scored row (with several training seeds: mean, range and each seed);
- ``curve``: the learning curve, success on the main variant at each checkpoint;
- ``mistakes``: where the boxes put in a wrong bin went, box colour -> bin, per variant over every seed;
- ``headline``: with ``baselines`` as the folder, one line per shipped baseline that has a
  ``scores.json``: its method, inputs, parameters, training time and success on each variant (the landing page's
  table, which compares methods and what each costs).
"""

from __future__ import annotations

import math
import os
import re
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from colorsort.errors import ConfigError, UnknownName
from colorsort.expert.config import changes_text
from colorsort.training.method_names import method_name
from colorsort.training.publishing.run_summary import curve_table, scored_checkpoints, span, summary_table
from colorsort.training.results_file import PipelineResults, ScoreRow

KINDS = ("table", "curve", "mistakes", "headline")
BLOCK = re.compile(r"(<!-- scores (?P<dir>\S+) (?P<kind>\S+) -->\n)(?P<body>.*?)(<!-- end scores -->)", re.S)


MACHINES = {"cpu": "on the CPU", "cuda": "on a GPU", "mps": "on Apple's GPU"}


def method_label(scores: PipelineResults) -> str:
    """The policy's label in a table ("ACT, sensor+wrist"), from the recipe stored with its scores.

    The recipe is stored in sections (``Recipe.to_json``); the shipped scores of before that, flat."""
    recipe = scores.recipe
    dagger = recipe.get("dagger", {})  # stored only where a recipe ran DAgger's rounds
    name = method_name(recipe.get("policy", {"type": "act"})["type"], dagger.get("rounds", 0),
                       dagger.get("retrain", "scratch"), section(scores, "training").get("average", 1))
    cameras = recipe["demos"]["cameras"] if isinstance(recipe.get("demos"), dict) else recipe["cameras"]
    return f"{name}, {'+'.join(cameras) if cameras else 'state'}"


def section(scores: PipelineResults, name: str) -> dict:
    """A section of the stored recipe ("training"); the whole recipe where it was stored flat (older scores)."""
    part = scores.recipe.get(name)
    return part if isinstance(part, dict) else scores.recipe


def trained_on(scores: PipelineResults) -> str:
    """Where the policy trained ("on the CPU"), from its recipe's device."""
    return MACHINES[section(scores, "training").get("device", "cpu")]


def main_variant(scores: PipelineResults) -> str:
    """The variant its learning curve was measured on, from its recipe."""
    return section(scores, "evaluation").get("main_variant", "default")


def parameters(checkpoint: Path) -> int | None:
    """The number of weights in ``checkpoint/model.safetensors``, read from the tensors' shapes (safetensors'
    ``safe_open``: no tensor is loaded); None when there is no such file."""
    from safetensors import safe_open

    path = checkpoint / "model.safetensors"
    if not path.is_file():
        return None
    with safe_open(str(path), "np") as f:
        return sum(math.prod(f.get_slice(k).get_shape()) for k in f.keys())


def millions(count: int | None) -> str:
    """"11.8 M"; "-" when unknown."""
    return "-" if count is None else f"{count / 1e6:.1f} M"


def render(scores: PipelineResults, kind: str) -> str:
    """The Markdown ``kind`` table of a baseline's ``scores.json``."""
    if kind == "table":
        return summary_table(scores.rows, method_label(scores))
    if kind == "curve":
        if not scores.curve:
            raise ConfigError("this baseline's scores.json has no learning curve "
                              "(it saved no checkpoints along the way)")
        return curve_table(scores.curve)
    if kind == "mistakes":
        return mistakes_table(scores.rows)
    raise UnknownName("table kind", kind, list(KINDS), "kinds")


def largest_by_variant(rows: Sequence[ScoreRow]) -> dict[str, list[ScoreRow]]:
    """The rows of the largest demo count, one list per variant (one row per training seed), in their order."""
    largest = max(r.demos_tried for r in rows)
    groups: dict[str, list[ScoreRow]] = {}
    for r in rows:
        if r.demos_tried == largest:
            groups.setdefault(r.variant, []).append(r)
    return groups


def mistakes_table(rows: Sequence[ScoreRow]) -> str:
    """A Markdown table: per variant of the largest demo count, its boxes in a wrong bin by colour and the bin
    they went to ("red -> green 10"), summed over every training seed's episodes; variants without any are left out."""
    counts = {variant: Counter(f"{b['color']} -> {b['bin']}" for r in group for e in r.report.per_episode
                               for b in e["boxes"] if b["outcome"] == "misplaced")
              for variant, group in largest_by_variant(rows).items()}
    lines = ["| variant | boxes in a wrong bin | box colour -> the bin it went to |", "| --- | --- | --- |"]
    for variant, c in counts.items():
        if c:
            lines.append(f"| {variant} | {sum(c.values())} | {', '.join(f'{k} {n}' for k, n in c.most_common())} |")
    if len(lines) == 2:
        lines.append("| every variant | 0 | |")
    return "\n".join(lines)


def baselines_headline(folder: Path, links_from: Path | None = None) -> str:
    """A Markdown table: per baseline in ``folder`` (each subfolder with a ``scores.json``), its method, inputs,
    parameters, training (with the demos' expert settings where they differ from its preset) and success per
    variant; with several training seeds, their mean, range and how many. Each baseline links its README, relative
    to the folder ``links_from`` (default: ``folder``'s parent)."""
    links_from = folder.parent if links_from is None else links_from
    lines = ["| baseline | method | inputs | parameters | training | success on each variant (one seed: 95% CI, "
             "episodes; several: mean and range over the seeds) |", "| --- | --- | --- | --- | --- | --- |"]
    for path in sorted(folder.glob("*/scores.json")):
        scores = PipelineResults.load(path)
        by_variant = largest_by_variant(scores.rows)
        cells = [variant_cell(v, g) for v, g in by_variant.items()]
        runs = next(iter(by_variant.values()))  # one row per training seed
        first = runs[0]
        minutes = [r.scored_minutes for r in runs]
        chosen = (f", scored at {scored_checkpoints(runs)} (chosen on validation seeds)"
                  if any(r.checkpoint is not None for r in runs) else "")
        expert = section(scores, "demos").get("expert")  # the expert's settings changed from its preset, if any
        demos = f"{first.demos} demos" + (f" (expert `{changes_text(expert)}`)" if expert else "")
        training = (f"{demos}, {first.steps} updates{chosen}, {span(minutes)} min {trained_on(scores)}"
                    + (f" per seed, {len(runs)} seeds" if len(runs) > 1 else ""))
        name = path.parent.name
        method, _, inputs = method_label(scores).partition(", ")
        link = Path(os.path.relpath(path.parent / "README.md", links_from)).as_posix()
        lines.append(f"| [`{name}`]({link}) | {method} | {inputs} | "
                     f"{millions(parameters(path.parent))} | {training} | {'; '.join(cells)} |")
    return "\n".join(lines)


def variant_cell(variant: str, rows: Sequence[ScoreRow]) -> str:
    """"`default` 68% (54-79%, 50)" for one training seed (the 95% interval); "`default` mean 91%, seeds
    84-98% (3 x 50)" for several (the mean and range of the seeds' rates)."""
    if len(rows) == 1:
        (e,) = (r.report for r in rows)
        lo, hi = e.success_ci95
        return f"`{variant}` {100 * e.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%, {e.episodes})"
    rates = [100 * r.report.success_rate for r in rows]
    return (f"`{variant}` mean {sum(rates) / len(rates):.0f}%, seeds {min(rates):.0f}-{max(rates):.0f}% "
            f"({len(rows)} x {rows[0].report.episodes})")


def commands(scores: PipelineResults) -> str:
    """The commands that made a baseline's scores: the first, then each that added training seeds."""
    return "; ".join([scores.command, *(f"{s.named_seeds()} added by {s.command}" for s in scores.added)])


def fill_baseline_tables(text: str, root: Path, page: Path | None = None) -> str:
    """``text`` (of ``page``, default ``root/README.md``: links are relative to it) with every scores block
    rewritten from ``root/<dir>/scores.json``."""
    page_folder = (root / "README.md" if page is None else page).parent

    def block(m: re.Match) -> str:
        if m["kind"] == "headline":
            note = f"Written by `python tools/baseline_tables.py` from `{m['dir']}/*/scores.json`:"
            return f"{m[1]}{note}\n\n{baselines_headline(root / m['dir'], page_folder)}\n\n{m[5]}"
        path = root / m["dir"] / "scores.json"
        if not path.is_file():
            raise ConfigError(f"a scores block names {m['dir']}, which has no scores.json")
        scores = PipelineResults.load(path)
        note = f"Written by `python tools/baseline_tables.py` from `{m['dir']}/scores.json` ({commands(scores)}):"
        return f"{m[1]}{note}\n\n{render(scores, m['kind'])}\n\n{m[5]}"

    return BLOCK.sub(block, text)


def pages(root: Path) -> list[Path]:
    """The pages that may hold scores blocks: README.md and the docs."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]
