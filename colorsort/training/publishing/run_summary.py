"""The pipeline's outputs for people: the Markdown table, success against demos, the learning curve."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

from colorsort.benchmark.metrics import EvalReport, wilson_interval
from colorsort.training.results_file import CurvePoint, ScoreRow

COLUMNS = ("variant", "policy", "demos", "training", "success rate (95% CI)", "correct", "misplaced", "dropped",
           "distractors let through", "boxes/min", "mean cycle [s]")


def scored_checkpoints(group: Sequence[ScoreRow]) -> str:
    """"4000/5000/4000": the update each training seed's row was scored at (its chosen checkpoint, else its last)."""
    return "/".join(str(r.scored_step) for r in group)


def updates(r: ScoreRow, with_choice: bool = True) -> str:
    """"3600 steps (7.8 passes)": a row's training updates, and the passes over its data they made; with the
    checkpoint the validation seeds chose, ", scored at 2400 after 36 min (chosen on validation seeds)"."""
    return f"{r.steps} steps" + (f" ({r.passes:.1f} passes)" if r.passes is not None else "") + (
        f", scored at {r.checkpoint} after {r.scored_minutes:.0f} min (chosen on validation seeds)"
        if with_choice and r.checkpoint is not None else "")


def seeds_updates(group: Sequence[ScoreRow]) -> str:
    """``updates`` of a row's training seeds: their one run length, and each seed's chosen checkpoint in turn
    with the minutes of training it took."""
    text = updates(group[0], with_choice=False)
    if any(r.checkpoint is not None for r in group):
        text += ", scored at " + scored_checkpoints(group) + " after " + \
            "/".join(f"{r.scored_minutes:.0f}" for r in group) + " min (chosen on validation seeds)"
    return text


def row_cells(r: ScoreRow, label: str) -> list[str]:
    e = r.report
    lo, hi = e.success_ci95
    cycle = f"{e.mean_cycle_time_s:.2f}" if e.mean_cycle_time_s is not None else "-"
    training = f"{updates(r)}, seed {r.seed}, {r.train_minutes:.0f} min"
    return [e.variant, label, str(r.demos), training,
            f"{100 * e.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%), {e.episodes} ep.",
            str(e.correct), str(e.misplaced), str(e.dropped),
            f"{e.distractors_let_through}/{e.distractors}", f"{e.boxes_per_minute:.1f}", cycle]


def table(rows: Sequence[ScoreRow], label: str) -> str:
    """A Markdown table: one row per (demo count, variant) evaluation."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + " --- |" * len(COLUMNS)]
    lines += ["| " + " | ".join(row_cells(r, label)) + " |" for r in rows]
    return "\n".join(lines)


SUMMARY_COLUMNS = ("variant", "policy", "demos", "training (each seed)", "success: mean (min-max over seeds)",
                   "each seed", "episodes per seed", "correct", "misplaced", "dropped")


def span(values: list[float]) -> str:
    """``"lo-hi"`` of ``values`` rounded to whole numbers, or the one number when both ends round alike."""
    lo, hi = f"{min(values):.0f}", f"{max(values):.0f}"
    return lo if lo == hi else f"{lo}-{hi}"


def summary_table(rows: Sequence[ScoreRow], label: str) -> str:
    """A Markdown table: one row per (demo count, variant), its training seeds' success as mean, range and each.

    Box counts are totals over every seed's episodes. With one seed per row this is ``table``."""
    groups: dict[tuple, list[ScoreRow]] = {}
    for r in rows:
        groups.setdefault((r.demos_tried, r.variant), []).append(r)
    if all(len(g) == 1 for g in groups.values()):
        return table(rows, label)
    lines = ["| " + " | ".join(SUMMARY_COLUMNS) + " |", "|" + " --- |" * len(SUMMARY_COLUMNS)]
    for g in groups.values():
        rates = [100 * r.report.success_rate for r in g]
        minutes = span([r.train_minutes for r in g])
        cells = [g[0].variant, label, str(g[0].demos), f"{seeds_updates(g)}, {minutes} min",
                 f"{sum(rates) / len(rates):.0f}% ({min(rates):.0f}-{max(rates):.0f}%), {len(g)} seeds",
                 ", ".join(f"{x:.0f}%" for x in rates), str(g[0].report.episodes),
                 *(str(sum(getattr(r.report, k) for r in g)) for k in ("correct", "misplaced", "dropped"))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def first_episodes(report: EvalReport, episodes: int, step: int, minutes: float) -> CurvePoint:
    """The learning-curve point of ``report``'s first ``episodes`` episodes (the seeds a shorter evaluation runs),
    for the checkpoint after ``step`` updates and ``minutes`` of training."""
    kept = report.per_episode[:episodes]
    successes = sum(bool(e["success"]) for e in kept)
    counts = [sum(e[k] for e in kept) for k in ("correct", "misplaced", "dropped")]
    return CurvePoint(step, minutes, len(kept), successes, successes / len(kept),
                      wilson_interval(successes, len(kept)), *counts)


def validation_table(rows: Sequence[ScoreRow]) -> str:
    """A Markdown table: each training seed's checkpoints on the validation seeds, the chosen one marked."""
    seen: dict[int, ScoreRow] = {}
    for r in rows:
        if r.validation:
            seen.setdefault(r.seed, r)
    lines = ["| seed | update | training [min] | success on validation seeds | by variant | correct | dropped |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for seed, r in seen.items():
        for p in r.validation:
            mark = " (chosen)" if p.step == r.checkpoint else ""
            by = ", ".join(f"{v} {100 * x:.0f}%" for v, x in p.success_by_variant.items())
            lines.append(f"| {seed} | {p.step}{mark} | {p.minutes:.0f} | {p.successes}/{p.episodes} "
                         f"| {by} | {p.correct} | {p.dropped} |")
    return "\n".join(lines)


def curve_table(points: Sequence[CurvePoint]) -> str:
    lines = ["| updates | training [min] | success (95% CI) | correct | misplaced | dropped |",
             "| --- | --- | --- | --- | --- | --- |"]
    for p in points:
        lo, hi = p.success_ci95
        lines.append(f"| {p.step} | {p.minutes:.0f} | {100 * p.success_rate:.0f}% "
                     f"({100 * lo:.0f}-{100 * hi:.0f}%), {p.episodes} ep. | {p.correct} | {p.misplaced} "
                     f"| {p.dropped} |")
    return "\n".join(lines)


def _errorbars(ax, x: Sequence[float], rates: Sequence[tuple[float, tuple[float, float]]],
               label: str | None = None) -> None:
    """Points at ``x`` of (success rate, its 95% interval)."""
    rate = [100 * r for r, _ in rates]
    lo = [100 * (r - ci[0]) for r, ci in rates]
    hi = [100 * (ci[1] - r) for r, ci in rates]
    ax.errorbar(x, rate, yerr=[lo, hi], marker="o", capsize=4, label=label)
    ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)


def _save(fig, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def plot_demos(rows: Sequence[ScoreRow], label: str, variant: str, path: Path) -> None:
    """Success rate on ``variant`` against the number of demos: each seed's point and their mean (one seed: its
    95% Wilson interval)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups: dict[int, list[ScoreRow]] = {}
    for r in rows:
        groups.setdefault(r.demos, []).append(r)
    n = sorted(groups)
    fig, ax = plt.subplots(figsize=(5, 3.5), dpi=120)
    if all(len(g) == 1 for g in groups.values()):
        _errorbars(ax, n, [(groups[x][0].report.success_rate, groups[x][0].report.success_ci95) for x in n])
    else:
        for x in n:
            ax.scatter([x] * len(groups[x]), [100 * r.report.success_rate for r in groups[x]], color="gray", s=12,
                       zorder=3, label="one training seed" if x == n[0] else None)
        means = [100 * sum(r.report.success_rate for r in groups[x]) / len(groups[x]) for x in n]
        ax.plot(n, means, marker="o", label="mean over seeds")
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for x in n:
        r = groups[x][0]
        ax.annotate(updates(r), (x, 100 * r.report.success_rate), textcoords="offset points",
                    xytext=(6, -12), fontsize=7)
    ax.set_xscale("log")
    ax.set_xticks(n, [str(x) for x in n])
    ax.minorticks_off()  # the log axis's own labels (3x10^1) would print over the demo counts
    ax.set_xlabel("expert demos")
    ax.set_ylabel(f"success on {variant} [%]")
    ax.set_title(f"{label} on ColorSort, {rows[0].report.episodes} evaluation seeds", fontsize=9)
    _save(fig, path)


def plot_curve(points: Sequence[CurvePoint], label: str, variant: str, machine: str, path: Path) -> None:
    """Success rate on ``variant`` (95% Wilson interval) against minutes of training, each checkpoint annotated."""
    plot_curves([(label, points)], variant, machine, path,
                f"{label} learning {variant}, {points[0].episodes} evaluation seeds per checkpoint")


def plot_curves(curves: Sequence[tuple[str, Sequence[CurvePoint]]], variant: str, machine: str, path: Path,
                title: str | None = None) -> None:
    """Several runs' success on ``variant`` (95% Wilson intervals) against minutes of training on one axis, each
    checkpoint annotated with its updates, a legend naming each run where there are several."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.6), dpi=120)
    several = len(curves) > 1
    for label, points in curves:
        minutes = [p.minutes for p in points]
        _errorbars(ax, minutes, [(p.success_rate, p.success_ci95) for p in points], label if several else None)
        for p in points:
            ax.annotate(f"{p.step}", (p.minutes, 100 * p.success_rate), textcoords="offset points",
                        xytext=(5, -12), fontsize=7)
    ax.set_xlim(0, max(p.minutes for _, points in curves for p in points) * 1.08)
    ax.set_xlabel(f"training [min], {machine}; labels: updates", fontsize=8)
    ax.set_ylabel(f"success on {variant} [%]")
    if several:
        ax.legend(fontsize=7, loc="best")
    episodes = sorted({p.episodes for _, points in curves for p in points})
    title = title or f"learning {variant}, {'/'.join(map(str, episodes))} evaluation seeds per checkpoint"
    ax.set_title(textwrap.fill(title, 70), fontsize=9)  # a long label would run past the figure's edge
    _save(fig, path)
