"""The pipeline's outputs for people: the Markdown table, success against demos, the learning curve."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from colorsort.benchmark.metrics import wilson_interval

COLUMNS = ("variant", "policy", "demos", "training", "success rate (95% CI)", "correct", "misplaced", "dropped",
           "distractors let through", "boxes/min", "mean cycle [s]")


def scored_minutes(r: dict) -> float:
    """[min] of training behind the checkpoint a row scored: when the chosen one was saved (its validation
    point's), else the whole run."""
    if "checkpoint" not in r:
        return r["train_minutes"]
    return next(p["minutes"] for p in r["validation"] if p["step"] == r["checkpoint"])


def scored_checkpoints(group: list[dict]) -> str:
    """"4000/5000/4000": the update each training seed's row was scored at (its chosen checkpoint, else its last)."""
    return "/".join(str(r.get("checkpoint", r["steps"])) for r in group)


def updates(r: dict) -> str:
    """"3600 steps (7.8 passes)": a row's training updates, and the passes over its data they made; with the
    checkpoint the validation seeds chose, ", scored at 2400 after 36 min (chosen on validation seeds)"."""
    return f"{r['steps']} steps" + (f" ({r['passes']:.1f} passes)" if r.get("passes") is not None else "") + (
        f", scored at {r['checkpoint']} after {scored_minutes(r):.0f} min (chosen on validation seeds)"
        if "checkpoint" in r else "")


def seeds_updates(group: list[dict]) -> str:
    """``updates`` of a row's training seeds: their one run length, and each seed's chosen checkpoint in turn
    with the minutes of training it took."""
    text = updates({k: v for k, v in group[0].items() if k != "checkpoint"})
    if any("checkpoint" in r for r in group):
        text += ", scored at " + scored_checkpoints(group) + " after " + \
            "/".join(f"{scored_minutes(r):.0f}" for r in group) + " min (chosen on validation seeds)"
    return text


def row_cells(r: dict, label: str) -> list[str]:
    lo, hi = r["success_ci95"]
    cycle = f"{r['mean_cycle_time_s']:.2f}" if r["mean_cycle_time_s"] is not None else "-"
    seed = f", seed {r['seed']}" if "seed" in r else ""
    training = f"{updates(r)}{seed}, {r['train_minutes']:.0f} min"
    return [r["variant"], label, str(r["demos"]), training,
            f"{100 * r['success_rate']:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%), {r['episodes']} ep.",
            str(r["correct"]), str(r["misplaced"]), str(r["dropped"]),
            f"{r['distractors_let_through']}/{r['distractors']}", f"{r['boxes_per_minute']:.1f}", cycle]


def table(rows: list[dict], label: str) -> str:
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


def summary_table(rows: list[dict], label: str) -> str:
    """A Markdown table: one row per (demo count, variant), its training seeds' success as mean, range and each.

    Box counts are totals over every seed's episodes. With one seed per row this is ``table``."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["demos_tried"], r["variant"]), []).append(r)
    if all(len(g) == 1 for g in groups.values()):
        return table(rows, label)
    lines = ["| " + " | ".join(SUMMARY_COLUMNS) + " |", "|" + " --- |" * len(SUMMARY_COLUMNS)]
    for g in groups.values():
        rates = [100 * r["success_rate"] for r in g]
        minutes = span([r["train_minutes"] for r in g])
        cells = [g[0]["variant"], label, str(g[0]["demos"]), f"{seeds_updates(g)}, {minutes} min",
                 f"{sum(rates) / len(rates):.0f}% ({min(rates):.0f}-{max(rates):.0f}%), {len(g)} seeds",
                 ", ".join(f"{x:.0f}%" for x in rates), str(g[0]["episodes"]),
                 *(str(sum(r[k] for r in g)) for k in ("correct", "misplaced", "dropped"))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def first_episodes(report: dict, episodes: int) -> dict:
    """Success and box counts of ``report``'s first ``episodes`` episodes (the seeds a shorter evaluation runs)."""
    kept = report["per_episode"][:episodes]
    successes = sum(bool(e["success"]) for e in kept)
    return {"episodes": len(kept), "successes": successes, "success_rate": successes / len(kept),
            "success_ci95": list(wilson_interval(successes, len(kept))),
            **{k: sum(e[k] for e in kept) for k in ("correct", "misplaced", "dropped")}}


def validation_table(rows: list[dict]) -> str:
    """A Markdown table: each training seed's checkpoints on the validation seeds, the chosen one marked."""
    seen: dict[int, dict] = {}
    for r in rows:
        if "validation" in r:
            seen.setdefault(r["seed"], r)
    lines = ["| seed | update | training [min] | success on validation seeds | by variant | correct | dropped |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for seed, r in seen.items():
        for p in r["validation"]:
            mark = " (chosen)" if p["step"] == r["checkpoint"] else ""
            by = ", ".join(f"{v} {100 * x:.0f}%" for v, x in p["success_by_variant"].items())
            lines.append(f"| {seed} | {p['step']}{mark} | {p['minutes']:.0f} | {p['successes']}/{p['episodes']} "
                         f"| {by} | {p['correct']} | {p['dropped']} |")
    return "\n".join(lines)


def curve_table(points: list[dict]) -> str:
    lines = ["| updates | training [min] | success (95% CI) | correct | misplaced | dropped |",
             "| --- | --- | --- | --- | --- | --- |"]
    for p in points:
        lo, hi = p["success_ci95"]
        lines.append(f"| {p['step']} | {p['minutes']:.0f} | {100 * p['success_rate']:.0f}% "
                     f"({100 * lo:.0f}-{100 * hi:.0f}%), {p['episodes']} ep. | {p['correct']} | {p['misplaced']} "
                     f"| {p['dropped']} |")
    return "\n".join(lines)


def _errorbars(ax, x: Sequence[float], points: list[dict]) -> None:
    rate = [100 * p["success_rate"] for p in points]
    lo = [100 * (p["success_rate"] - p["success_ci95"][0]) for p in points]
    hi = [100 * (p["success_ci95"][1] - p["success_rate"]) for p in points]
    ax.errorbar(x, rate, yerr=[lo, hi], marker="o", capsize=4)
    ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)


def _save(fig, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def plot_demos(rows: list[dict], label: str, variant: str, path: Path) -> None:
    """Success rate on ``variant`` against the number of demos: each seed's point and their mean (one seed: its
    95% Wilson interval)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups: dict[int, list[dict]] = {}
    for r in rows:
        groups.setdefault(r["demos"], []).append(r)
    n = sorted(groups)
    fig, ax = plt.subplots(figsize=(5, 3.5), dpi=120)
    if all(len(g) == 1 for g in groups.values()):
        _errorbars(ax, n, [groups[x][0] for x in n])
    else:
        for x in n:
            ax.scatter([x] * len(groups[x]), [100 * r["success_rate"] for r in groups[x]], color="gray", s=12,
                       zorder=3, label="one training seed" if x == n[0] else None)
        means = [100 * sum(r["success_rate"] for r in groups[x]) / len(groups[x]) for x in n]
        ax.plot(n, means, marker="o", label="mean over seeds")
        ax.set_ylim(-2, 102)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for x in n:
        r = groups[x][0]
        ax.annotate(updates(r), (x, 100 * r["success_rate"]), textcoords="offset points",
                    xytext=(6, -12), fontsize=7)
    ax.set_xscale("log")
    ax.set_xticks(n, [str(x) for x in n])
    ax.minorticks_off()  # the log axis's own labels (3x10^1) would print over the demo counts
    ax.set_xlabel("expert demos")
    ax.set_ylabel(f"success on {variant} [%]")
    ax.set_title(f"{label} on ColorSort, {rows[0]['episodes']} evaluation seeds", fontsize=9)
    _save(fig, path)


def plot_curve(points: list[dict], label: str, variant: str, machine: str, path: Path) -> None:
    """Success rate on ``variant`` (95% Wilson interval) against minutes of training, each checkpoint annotated."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.6), dpi=120)
    minutes = [p["minutes"] for p in points]
    _errorbars(ax, minutes, points)
    for p in points:
        ax.annotate(f"{p['step']}", (p["minutes"], 100 * p["success_rate"]), textcoords="offset points",
                    xytext=(5, -12), fontsize=7)
    ax.set_xlim(0, max(minutes) * 1.08)
    ax.set_xlabel(f"training [min], {machine}; labels: updates", fontsize=8)
    ax.set_ylabel(f"success on {variant} [%]")
    ax.set_title(f"{label} learning {variant}, {points[0]['episodes']} evaluation seeds per checkpoint", fontsize=9)
    _save(fig, path)
