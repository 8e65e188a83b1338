"""The evaluation report: a static page (``index.html``) that a browser opens from disk, with no server.

``colorsort-eval --report DIR`` writes ``DIR/index.html`` (the policy, each variant's success with
its 95% interval, every episode's boxes and how it ended, failures first, each filmed episode's
video), ``DIR/outcomes.svg`` (the boxes' outcomes per variant), ``DIR/videos/<variant>_seed<S>.mp4``
(H.264, which browsers play) and ``DIR/report.json`` (what ``--json`` writes). Nothing on the page
is fetched from the network.
"""

from __future__ import annotations

import html
import json
import platform
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from colorsort.benchmark.metrics import EvalReport
from colorsort.cell.referee import describe_box
from colorsort.variants import get_variant

SUCCESSES_FILMED = 3  # successes kept per variant besides every failure, unless --videos says otherwise
OUTCOME_COLORS = {"placed": "#3a9d4f", "rejected": "#8fb8de", "misplaced": "#e0902f", "dropped": "#c8372d"}
OUTCOME_WORDS = {"placed": "placed in its bin", "rejected": "let through", "misplaced": "misplaced",
                 "dropped": "dropped"}  # the plot's legend

STYLE = """
body { font: 15px/1.45 system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; padding: 0 1em; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border-bottom: 1px solid #ddd; padding: 4px 10px; text-align: right; }
th:first-child, td:first-child { text-align: left; }
.meta { color: #666; font-size: 13px; }
.episode { border: 1px solid #ddd; border-left: 6px solid #3a9d4f; margin: 1em 0; padding: 0.5em 1em; }
.episode.failed { border-left-color: #c8372d; }
.episode h3 { margin: 0.2em 0; }
.boxes { margin: 0.3em 0; }
.boxes li.placed, .boxes li.rejected { color: #2d7a3e; }
.boxes li.misplaced, .boxes li.dropped { color: #b0281f; font-weight: 600; }
video { display: block; margin: 0.5em 0; background: #000; }
"""


def film_name(variant: str, seed: int) -> str:
    """The video's path inside the report folder."""
    return f"videos/{variant}_seed{seed}.mp4"


def episodes_in_order(report: EvalReport) -> list[dict[str, Any]]:
    """A variant's episodes, failures first, each group in seed order."""
    return sorted(report.per_episode, key=lambda e: (bool(e["success"]), e["seed"]))


def choose_films[T](reports: list[EvalReport], films: dict[tuple[str, int], T],
                 limit: int | None) -> dict[tuple[str, int], T]:
    """The films a report keeps (``films``: mp4 bytes, or what stands for a film not yet drawn, by (variant,
    seed)): per variant, failures first then successes, at most ``limit``; with ``limit`` None, every failure and
    the first ``SUCCESSES_FILMED`` successes."""
    kept = {}
    for r in reports:
        order = [e for e in episodes_in_order(r) if (r.variant, e["seed"]) in films]
        if limit is None:
            failures = [e for e in order if not e["success"]]
            order = failures + [e for e in order if e["success"]][:SUCCESSES_FILMED]
        else:
            order = order[:limit]
        kept.update({(r.variant, e["seed"]): films[(r.variant, e["seed"])] for e in order})
    return kept


def plot_outcomes(reports: list[EvalReport], path: Path) -> None:
    """Boxes per outcome for each variant, as stacked horizontal bars (SVG), success rate beside."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 1.1 + 0.45 * len(reports)))
    names = [r.variant for r in reports][::-1]
    left = [0.0] * len(reports)
    for outcome, color in OUTCOME_COLORS.items():
        counts = [sum(b["outcome"] == outcome for e in r.per_episode for b in e["boxes"])
                  for r in reports][::-1]
        ax.barh(names, counts, left=left, color=color, label=OUTCOME_WORDS[outcome])
        left = [a + b for a, b in zip(left, counts, strict=True)]
    for y, r in enumerate(reports[::-1]):
        ax.text(left[y], y, f"  {100 * r.success_rate:.0f}% success", va="center", fontsize=9)
    ax.set_xlabel("boxes")
    ax.set_xlim(0, max(left + [1.0]) * 1.3)
    ax.legend(loc="lower left", bbox_to_anchor=(0, 1.0), fontsize=8, frameon=False, ncols=4)
    ax.spines[["top", "right"]].set_visible(False)
    fig.tight_layout()
    fig.savefig(path, format="svg")
    plt.close(fig)


def _summary(reports: list[EvalReport]) -> str:
    rows = []
    for r in reports:
        lo, hi = r.success_ci95
        rows.append(f"<tr><td><a href='#variant-{r.variant}'>{r.variant}</a></td><td>{r.episodes}</td>"
                    f"<td>{100 * r.success_rate:.0f}%</td><td>{100 * lo:.0f}-{100 * hi:.0f}%</td><td>{r.correct}</td>"
                    f"<td>{r.misplaced}</td><td>{r.dropped}</td>"
                    f"<td>{r.distractors_let_through}/{r.distractors}</td><td>{r.boxes_per_minute:.1f}</td></tr>")
    head = ("<tr><th>variant</th><th>episodes</th><th>success</th><th>95% interval</th><th>placed</th>"
            "<th>misplaced</th><th>dropped</th><th>distractors let through</th><th>boxes/min</th></tr>")
    return f"<table id='summary'>{head}{''.join(rows)}</table>"


def _episode(variant: str, boxes: int, e: dict[str, Any], filmed: bool) -> str:
    items = "".join(f"<li class='{b['outcome']}'>{b['time']:.1f} s: "
                    f"{html.escape(describe_box(b['color'], b['outcome'], b['bin']))}</li>" for b in e["boxes"])
    video = (f"<video controls muted preload='metadata' width='480' height='360' src='{film_name(variant, e['seed'])}'>"
             "</video>" if filmed else "<p class='meta'>not filmed</p>")
    state = "ok" if e["success"] else "failed"
    drawn = (f"<p class='meta'>shift: <code>{html.escape(json.dumps(e['shift']))}</code></p>"
             if e.get("shift") else "")  # each shift's level and the values drawn for this episode
    ended = e["ended"]
    if ended == "time limit":
        ended += f" ({len(e['boxes'])} of {boxes} boxes left play)"
    return (f"<div class='episode {state}' id='{variant}-seed{e['seed']}'><h3>seed {e['seed']}: "
            f"{html.escape(ended)}</h3><p class='meta'>{e['steps']} steps, {e['sim_time']:.1f} s "
            f"of sim time</p>{drawn}<ol class='boxes'>{items or '<li>no box left play</li>'}</ol>{video}</div>")


def write_report(out: str | Path, reports: list[EvalReport], films: dict[tuple[str, int], bytes],
                 payload: Any, command: str) -> Path:
    """Write the report into the folder ``out`` (created): the page, the plot, the kept films and
    ``report.json`` (``payload``, what ``--json`` writes). Returns the page's path."""
    out = Path(out)
    (out / "videos").mkdir(parents=True, exist_ok=True)
    for (variant, seed), video in films.items():
        (out / film_name(variant, seed)).write_bytes(video)
    (out / "report.json").write_text(json.dumps(payload, indent=1))
    plot_outcomes(reports, out / "outcomes.svg")
    sections = []
    for r in reports:
        lo, hi = r.success_ci95
        boxes = get_variant(r.variant).boxes
        episodes = "".join(_episode(r.variant, boxes, e, (r.variant, e["seed"]) in films)
                           for e in episodes_in_order(r))
        shifted = f" under {html.escape(r.shift)}" if r.shift != "none" else ""
        sections.append(f"<section id='variant-{r.variant}'><h2>{r.variant}{shifted}: {r.successes} of {r.episodes} "
                        f"episodes succeeded ({100 * r.success_rate:.0f}%, 95% interval {100 * lo:.0f}-"
                        f"{100 * hi:.0f}%)</h2>{episodes}</section>")
    policy = html.escape(reports[0].policy if reports else "-")
    when = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    page = (f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>ColorSort evaluation: {policy}"
            f"</title><style>{STYLE}</style></head><body><h1>ColorSort evaluation: {policy}</h1>"
            f"<p class='meta'><code>{html.escape(command)}</code><br>{when}, {html.escape(platform.platform())}, "
            f"{len(films)} episodes filmed (scene camera, failures first)</p>"
            f"{_summary(reports)}<img src='outcomes.svg' alt='boxes per outcome and variant'>"
            f"<p class='meta'>Success: every box of the episode where it belongs (its colour's bin, or let "
            f"through when it has none); an episode ends at its first box misplaced or dropped, or at the "
            f"variant's time limit. <a href='report.json'>report.json</a> holds the same as "
            f"<code>--json</code>.</p>{''.join(sections)}</body></html>\n")
    index = out / "index.html"
    index.write_text(page, encoding="utf-8")
    return index
