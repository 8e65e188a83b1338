"""Two runs of a baseline recipe side by side, per variant, from their ``scores.json`` (``colorsort-analyze compare``).

For each variant of the largest demo count: the mean success over the training seeds with each seed's, then the
boxes put in the right bin, a wrong bin and dropped, summed over every seed's episodes; last, the mean over the
variants. An older run's ``scores.json`` comes from git: ``git show COMMIT:baselines/NAME/scores.json > old.json``.
"""

from __future__ import annotations

from colorsort.training.publishing.tables import largest_by_variant
from colorsort.training.results_file import PipelineResults, ScoreRow


def cells(rows: list[ScoreRow] | None) -> tuple[str, str]:
    """("67% (100%, 85%, 15%)", "87 / 0 / 20"): mean success (each seed), right / wrong bin / dropped."""
    if not rows:
        return "-", "-"
    rates = ", ".join(f"{100 * r.report.success_rate:.0f}%" for r in rows)
    success = f"{mean_rate(rows):.0f}% ({rates})"
    boxes = (sum(getattr(r.report, k) for r in rows) for k in ("correct", "misplaced", "dropped"))
    return success, " / ".join(map(str, boxes))


def mean_rate(rows: list[ScoreRow]) -> float:
    """[%] the mean success of a variant's seeds."""
    return 100 * sum(r.report.success_rate for r in rows) / len(rows)


def compare(new: PipelineResults, old: PipelineResults, labels: tuple[str, str]) -> str:
    """The Markdown table of ``new`` beside ``old``, one line per variant of either."""
    a, b = largest_by_variant(new.rows), largest_by_variant(old.rows)
    head = [f"{labels[0]}: mean (each seed)", f"{labels[1]}: mean (each seed)",
            f"{labels[0]}: right / wrong bin / dropped", f"{labels[1]}: right / wrong bin / dropped"]
    lines = ["| variant | " + " | ".join(head) + " |", "| --- |" + " --- |" * len(head)]
    for variant in [*a, *(v for v in b if v not in a)]:
        (sa, ba), (so, bo) = cells(a.get(variant)), cells(b.get(variant))
        lines.append(f"| `{variant}` | {sa} | {so} | {ba} | {bo} |")
    means = [f"{sum(mean_rate(g) for g in groups.values()) / len(groups):.0f}%" for groups in (a, b)]
    lines.append(f"| every variant (mean of the variants' means) | {means[0]} | {means[1]} | | |")
    return "\n".join(lines)
