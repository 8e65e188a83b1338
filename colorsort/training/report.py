"""The pipeline's outputs for people: the Markdown table, success against demos, the learning curve."""

from __future__ import annotations

from pathlib import Path

from colorsort.benchmark.metrics import wilson_interval

COLUMNS = ("variant", "policy", "demos", "training", "success rate (95% CI)", "correct", "misplaced", "dropped",
           "distractors let through", "boxes/min", "mean cycle [s]")


def row_cells(r: dict, label: str) -> list[str]:
    lo, hi = r["success_ci95"]
    cycle = f"{r['mean_cycle_time_s']:.2f}" if r["mean_cycle_time_s"] is not None else "-"
    return [r["variant"], label, str(r["demos"]), f"{r['steps']} steps, {r['train_minutes']:.0f} min",
            f"{100 * r['success_rate']:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%), {r['episodes']} ep.",
            str(r["correct"]), str(r["misplaced"]), str(r["dropped"]),
            f"{r['distractors_let_through']}/{r['distractors']}", f"{r['boxes_per_minute']:.1f}", cycle]


def table(rows: list[dict], label: str) -> str:
    """A Markdown table: one row per (demo count, variant) evaluation."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + " --- |" * len(COLUMNS)]
    lines += ["| " + " | ".join(row_cells(r, label)) + " |" for r in rows]
    return "\n".join(lines)


def first_episodes(report: dict, episodes: int) -> dict:
    """Success and box counts of ``report``'s first ``episodes`` episodes (the seeds a shorter evaluation runs)."""
    kept = report["per_episode"][:episodes]
    successes = sum(bool(e["success"]) for e in kept)
    return {"episodes": len(kept), "successes": successes, "success_rate": successes / len(kept),
            "success_ci95": list(wilson_interval(successes, len(kept))),
            **{k: sum(e[k] for e in kept) for k in ("correct", "misplaced", "dropped")}}


def curve_table(points: list[dict]) -> str:
    lines = ["| updates | training [min] | success (95% CI) | correct | misplaced | dropped |",
             "| --- | --- | --- | --- | --- | --- |"]
    for p in points:
        lo, hi = p["success_ci95"]
        lines.append(f"| {p['step']} | {p['minutes']:.0f} | {100 * p['success_rate']:.0f}% "
                     f"({100 * lo:.0f}-{100 * hi:.0f}%), {p['episodes']} ep. | {p['correct']} | {p['misplaced']} "
                     f"| {p['dropped']} |")
    return "\n".join(lines)


def _errorbars(ax, x: list[float], points: list[dict]) -> None:
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
    """Success rate on ``variant`` (95% Wilson interval) against the number of demos."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["demos"] for r in rows]
    fig, ax = plt.subplots(figsize=(5, 3.5), dpi=120)
    _errorbars(ax, n, rows)
    for r, x in zip(rows, n):
        ax.annotate(f"{r['steps']} steps", (x, 100 * r["success_rate"]), textcoords="offset points",
                    xytext=(6, -12), fontsize=7)
    ax.set_xscale("log")
    ax.set_xticks(n, [str(x) for x in n])
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
    ax.set_xlabel(f"training time [min] on {machine} (labels: updates)")
    ax.set_ylabel(f"success on {variant} [%]")
    ax.set_title(f"{label} learning {variant}, {points[0]['episodes']} evaluation seeds per checkpoint", fontsize=9)
    _save(fig, path)
