"""Benchmark metrics: the success rate with its 95% Wilson interval and the sorting figures.

Success: every box of the episode where it belongs (``referee.judge``). Boxes placed correctly,
misplaced, dropped; distractors (boxes with no bin) let through; boxes per minute (boxes handled
right, placed in their bin or let through, per minute of sim time); mean cycle time (sim time
between consecutive boxes handled right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from colorsort.benchmark.episode_result import EpisodeResult


@dataclass
class EvalReport:
    policy: str
    variant: str
    episodes: int = 0
    successes: int = 0
    success_rate: float = 0.0
    success_ci95: tuple[float, float] = (0.0, 0.0)
    correct: int = 0
    misplaced: int = 0
    dropped: int = 0
    distractors: int = 0
    distractors_let_through: int = 0
    boxes_per_minute: float = 0.0
    mean_cycle_time_s: float | None = None
    sim_time_s: float = 0.0
    seeds: list[int] = field(default_factory=list)
    per_episode: list[dict] = field(default_factory=list)
    shift: str = "none"  # the held-out shifts applied (``colorsort.shifts``), e.g. "camera-pose:2"; "none": control


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95% Wilson score interval of a success rate (sensible at 0 and 1, unlike the normal approximation)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def aggregate(policy: str, variant: str, results: list[EpisodeResult], shift: str = "none") -> EvalReport:
    """The report over per-episode results (in seed order)."""
    report = EvalReport(policy=policy, variant=variant, seeds=[r.seed for r in results], shift=shift)
    cycles: list[float] = []
    handled = 0
    for r in results:
        report.episodes += 1
        report.successes += int(r.success)
        for key in ("correct", "misplaced", "dropped", "distractors"):
            setattr(report, key, getattr(report, key) + getattr(r, key))
        report.distractors_let_through += r.let_through
        report.sim_time_s += r.sim_time
        handled += len(r.sorted_times)
        cycles += list(np.diff(r.sorted_times))
        report.per_episode.append(r.to_json())
    report.success_rate = report.successes / report.episodes
    report.success_ci95 = wilson_interval(report.successes, report.episodes)
    report.boxes_per_minute = 60.0 * handled / report.sim_time_s if report.sim_time_s > 0 else 0.0
    report.mean_cycle_time_s = float(np.mean(cycles)) if cycles else None
    return report


def format_report(r: EvalReport) -> str:
    lo, hi = r.success_ci95
    cycle = f"{r.mean_cycle_time_s:.2f} s" if r.mean_cycle_time_s is not None else "-"
    rows = [
        ("policy", r.policy), ("variant", r.variant), *((("shift", r.shift),) if r.shift != "none" else ()),
        ("episodes", str(r.episodes)),
        ("success rate", f"{100 * r.success_rate:.1f}%  (95% CI {100 * lo:.1f}-{100 * hi:.1f}%)"),
        ("boxes placed correctly", str(r.correct)), ("misplaced", str(r.misplaced)), ("dropped", str(r.dropped)),
        ("distractors let through", f"{r.distractors_let_through}/{r.distractors}"),
        ("boxes per minute", f"{r.boxes_per_minute:.1f}"), ("mean cycle time", cycle),
        ("seeds", f"{r.seeds[0]}..{r.seeds[-1]}" if r.seeds else "-"),
        ("stalled (time limit)", str(sum(e["ended"] == "time limit" for e in r.per_episode))),
        *drawn(r.per_episode),
    ]
    return "\n".join(f"{k:<24} {v}" for k, v in rows)


def drawn(per_episode: list[dict]) -> list[tuple[str, str]]:
    """What held-out shifts drew over the episodes, a row per shift and number drawn (``edge_cm 8.0-12.0``, or the
    values themselves where there are three or fewer); a draw of vectors (a camera's move) is in ``--json`` only."""
    found: dict[tuple[str, str], list[float]] = {}
    for episode in per_episode:
        for name, draws in episode.get("shift", {}).items():
            for key, value in draws.items():
                if key != "level" and isinstance(value, int | float) and not isinstance(value, bool):
                    found.setdefault((name, key), []).append(float(value))
    rows = []
    for (name, key), values in found.items():
        distinct = sorted(set(values))
        shown = ", ".join(f"{v:g}" for v in distinct) if len(distinct) <= 3 else f"{min(values):g}-{max(values):g}"
        rows.append((f"drawn: {name}", f"{key} {shown} over {len(values)} episodes"))
    return rows


def format_table(reports: list[EvalReport]) -> str:
    """One line per variant: episodes, success rate with its 95% interval, boxes handled, boxes per minute."""
    lines = [f"{'variant':<16} {'episodes':>8} {'success':>8} {'95% CI':>13} {'placed':>6} {'misplaced':>9} "
             f"{'dropped':>7} {'boxes/min':>9}"]
    for r in reports:
        lo, hi = r.success_ci95
        lines.append(f"{r.variant:<16} {r.episodes:>8} {100 * r.success_rate:>7.1f}% {100 * lo:>5.1f}-{100 * hi:5.1f}% "
                     f"{r.correct:>6} {r.misplaced:>9} {r.dropped:>7} {r.boxes_per_minute:>9.1f}")
    return "\n".join(lines)
