"""Tables and the heatmap of held-out sweeps (``colorsort-eval --sweep --json``), for README and docs/shifts.md.

A sweep's summary (``summary``) keeps what the tables need: policy, variant, seeds, the command that ran it, its
wall time and machine, and one row per arm (``shift_sweep.sweep_rows``). Pages mark the generated parts with
``<!-- shifts list -->``, ``<!-- shifts headline -->``, ``<!-- shifts table -->`` (one line a sweep, linking its page
of every arm: ``sweep_page``, docs/results/shifts/<policy>-<variant>.md) and ``<!-- shifts randomised -->`` (a
randomised recipe's seeds against its targets), each closed by ``<!-- end shifts -->``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from colorsort.benchmark.metrics import EvalReport, wilson_interval
from colorsort.benchmark.shift_sweep import sweep_rows
from colorsort.shifts import GROUPS, SHIFTS

SUMMARY_KEYS = ("policy", "variant", "seeds", "command", "wall_s", "resumed_episodes", "executor", "envs", "machine",
                "written", "rows")
HEATMAP_LEVEL = 2
RANDOMISED = "-dr"  # a policy trained with the shifts' training ranges; its name less this is the same recipe without
SEED_SUFFIX = re.compile(r"-seed\d+$")  # a training seed's sweep beside the shipped policy's (act-...-dr-seed1000)
# docs/shifts.md's targets for a randomised recipe, on the means over its training seeds: the control; every shift
# but the wholly unseen ones; the mean; the seeds' spread on any arm [points]; shifts beaten beyond the intervals
TARGET_CONTROL, TARGET_EVERY, TARGET_MEAN, TARGET_SPREAD, TARGET_BEATEN = 0.95, 0.80, 0.90, 0.20, 5
UNSEEN = ("box-shape", "novel-distractors")  # no training range: reported, not held to the every-shift floor


def mean_relative(relatives: list[float]) -> float:
    """The mean of relative successes, each counted at most 1 (100%): a shift on which a policy beat its control (by
    chance, on a few episodes) does not make up for one it failed."""
    return float(np.mean([min(r, 1.0) for r in relatives]))


def summary(sweep: dict) -> dict:
    """What the tables keep of a ``--sweep --json`` file (its per-episode reports stay in outputs/), the rows
    computed afresh from its reports."""
    kept = {k: sweep[k] for k in SUMMARY_KEYS if k in sweep}
    if "reports" in sweep:
        kept["rows"] = sweep_rows([EvalReport(**r) for r in sweep["reports"]])
    return kept


def load(folder: Path) -> list[dict]:
    """Every sweep summary in ``folder`` (``*.json``), by policy name (a training seed's row beside its policy's)."""
    return sorted((json.loads(p.read_text()) for p in sorted(folder.glob("*.json"))),
                  key=lambda s: (policy_name(s), s["variant"]))


def policy_name(sweep: dict) -> str:
    """The row's name: the policy folder's, ``expert`` or ``random``; a training seed's policy kept beside a
    baseline's (``baselines/act-camera-snapshot-dr/seed1000``) is ``act-camera-snapshot-dr-seed1000``."""
    if sweep["policy"] in ("expert", "random"):
        return sweep["policy"]
    folder = Path(sweep["policy"])
    return f"{folder.parent.name}-{folder.name}" if re.fullmatch(r"seed\d+", folder.name) else folder.name


def at_level(sweep: dict, level: int) -> list[dict]:
    return [r for r in sweep["rows"] if r["level"] == level]


def shifts_headline(sweeps: list[dict]) -> str:
    """One line per policy: control success, mean relative success at level 2 (``mean_relative``), worst shift
    there."""
    lines = ["| policy | variant | control | mean relative success at level 2 | worst shift at level 2 |",
             "| --- | --- | --- | --- | --- |"]
    for s in sweeps:
        control = next(r for r in s["rows"] if r["shift"] == "none")
        rows = [r for r in at_level(s, HEATMAP_LEVEL) if r["relative"] is not None]
        first = (f"| `{policy_name(s)}` | `{s['variant']}` | {100 * control['success']:.0f}% "
                 f"({control['episodes']} ep.) |")
        if not rows:  # the control sorted nothing: no relative success
            lines.append(f"{first} - | - |")
            continue
        worst = min(rows, key=lambda r: r["relative"])
        mean = mean_relative([r["relative"] for r in rows])
        lines.append(f"{first} {100 * mean:.0f}% over {len(rows)} shifts | `{worst['shift']}` "
                     f"{100 * worst['relative']:.0f}% |")
    return "\n".join(lines)


def full_table(sweeps: list[dict]) -> str:
    """Every arm of every sweep: success and relative success with their 95% intervals, how boxes were lost."""
    lines = ["| policy | shift | level | episodes | success (95% CI) | relative to control (95% CI) | misplaced | "
             "dropped | stalled |", "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for s in sweeps:
        for r in s["rows"]:
            lo, hi = r["success_ci95"]
            rel = (f"{100 * r['relative']:.0f}% ({100 * r['relative_ci95'][0]:.0f}-{100 * r['relative_ci95'][1]:.0f}%)"
                   if r["relative"] is not None else "-")
            lines.append(f"| `{policy_name(s)}` | {'control' if r['shift'] == 'none' else r['shift']} | {r['level']} | "
                         f"{r['episodes']} | {100 * r['success']:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%) | {rel} | "
                         f"{r['misplaced']} | {r['dropped']} | {r['stalled']} |")
    return "\n".join(lines)


def provenance(sweeps: list[dict]) -> str:
    """How each sweep was made: its command, wall time and machine; a resumed sweep's time is that of the episodes
    its last run added to those of its journal."""
    def resumed(s: dict) -> str:
        n = s.get("resumed_episodes", 0)
        return f" (after {n} episodes of an earlier run, resumed from its journal)" if n else ""

    return "\n".join(f"- `{policy_name(s)}`: `{s.get('command', '?')}`, {s.get('wall_s', 0) / 60:.0f} min{resumed(s)} "
                     f"on {s.get('machine', '?')} ({s.get('written', '?')})" for s in sweeps)


def sweep_name(sweep: dict) -> str:
    """A sweep's file stem in docs/results/shifts/: ``<policy>-<variant>``."""
    return f"{policy_name(sweep)}-{sweep['variant']}"


def sweep_page(sweep: dict) -> str:
    """docs/results/shifts/<name>.md: every arm of one sweep and how it was made."""
    name = sweep_name(sweep)
    return (f"# Held-out shifts: `{policy_name(sweep)}` on `{sweep['variant']}`\n\n"
            f"Written by `python tools/shift_tables.py` from [{name}.json]({name}.json); every sweep: "
            f"[shift_results.md](../../shift_results.md); the shifts, their levels and the protocol: "
            f"[shifts.md](../../shifts.md).\n\n{full_table([sweep])}\n\nMade by:\n\n{provenance([sweep])}\n")


def sweep_index(sweeps: list[dict]) -> str:
    """One line per sweep: its levels, its episodes an arm, its control and a link to its page."""
    lines = ["| policy | variant | levels | episodes an arm | control | every arm |",
             "| --- | --- | --- | --- | --- | --- |"]
    for s in sweeps:
        control = next(r for r in s["rows"] if r["shift"] == "none")
        levels = sorted({r["level"] for r in s["rows"] if r["shift"] != "none"})
        side = sorted({r["episodes"] for r in s["rows"] if r["level"] not in (0, HEATMAP_LEVEL)})
        episodes = f"{control['episodes']} (control, level {HEATMAP_LEVEL})" + (
            f", {'/'.join(map(str, side))} (levels {', '.join(str(v) for v in levels if v != HEATMAP_LEVEL)})"
            if side else "")
        lines.append(f"| `{policy_name(s)}` | `{s['variant']}` | {', '.join(map(str, levels))} | {episodes} | "
                     f"{100 * control['success']:.0f}% | [{sweep_name(s)}](results/shifts/{sweep_name(s)}.md) |")
    return "\n".join(lines)


def heatmap(sweeps: list[dict], path: Path, level: int = HEATMAP_LEVEL) -> None:
    """Policies by shifts at ``level``: success relative to each policy's control, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    found = {r["shift"] for s in sweeps for r in at_level(s, level)}
    shifts = [n for g in GROUPS for n, shift in SHIFTS.items() if shift.group == g and n in found]  # by group
    grid = np.full((len(sweeps), len(shifts)), np.nan)
    for i, s in enumerate(sweeps):
        for r in at_level(s, level):
            if r["relative"] is not None:
                grid[i, shifts.index(r["shift"])] = 100 * r["relative"]
    fig, ax = plt.subplots(figsize=(2.0 + 0.55 * len(shifts), 2.6 + 0.4 * len(sweeps)))
    im = ax.imshow(np.minimum(grid, 100), cmap="RdYlGn", vmin=0, vmax=100, aspect="auto")
    ax.set_xticks(range(len(shifts)), shifts, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(sweeps)), [policy_name(s) for s in sweeps], fontsize=8)
    for i in range(len(sweeps)):
        for j in range(len(shifts)):
            if not np.isnan(grid[i, j]):
                ax.text(j, i, f"{grid[i, j]:.0f}", ha="center", va="center", fontsize=7)
    ax.set_title(f"success at level {level} relative to the control [%]", fontsize=9)
    fig.colorbar(im, ax=ax, fraction=0.03)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def shift_list() -> str:
    """Every shift by group: what it changes and its levels 1-3 in units (from the registry)."""
    lines = ["| group | shift | what changes | level 1 | level 2 | level 3 |", "| --- | --- | --- | --- | --- | --- |"]
    for group in GROUPS:
        for shift in (s for s in SHIFTS.values() if s.group == group):
            levels = " | ".join(shift.level_text(lv) for lv in (1, 2, 3))
            lines.append(f"| {group} | `{shift.name}` | {shift.summary} | {levels} |")
    return "\n".join(lines)


def shade_table() -> str:
    """box-shade's shades: per class, direction and level, the delta E reached, the hue turned (what the expert's
    colour classes read) and the nearest other colour the cell knows, with its distance."""
    from colorsort.config import ALL_COLORS, BIN_COLORS, COLORS
    from colorsort.expert.perception import hue_of
    from colorsort.shifts.box_shade import TOWARD, shade
    from colorsort.shifts.colour import delta_e

    names = {"red": ("orange", "crimson"), "green": ("teal", "lime"), "blue": ("slate", "navy")}
    lines = ["| class | toward | level | delta E from the class | hue turned [deg] | nearest other colour (delta E) |",
             "| --- | --- | --- | --- | --- | --- |"]
    for color in BIN_COLORS:
        for which in range(len(TOWARD[color])):
            for level in (1, 2, 3):
                rgba = shade(color, SHIFTS["box-shade"].magnitude(level), which)
                turn = (hue_of(rgba) - hue_of(COLORS[color]) + 180.0) % 360.0 - 180.0
                other = min((c for c in ALL_COLORS if c != color), key=lambda c: delta_e(rgba, ALL_COLORS[c]))
                lines.append(f"| {color} | {names[color][which]} | {level} | {delta_e(rgba, COLORS[color]):.1f} | "
                             f"{turn:+.1f} | {other} ({delta_e(rgba, ALL_COLORS[other]):.1f}) |")
    return "\n".join(lines)


def arm(sweep: dict, shift: str, level: int) -> dict | None:
    """A sweep's row of ``shift`` at ``level`` (``none`` at 0: the control), or None."""
    return next((r for r in sweep["rows"] if r["shift"] == shift and r["level"] == level), None)


def arms(sweeps: list[dict], shift: str, level: int) -> list[dict]:
    """Every sweep's row of ``shift`` at ``level``; ValueError naming the shift where a sweep lacks it."""
    rows = [arm(s, shift, level) for s in sweeps]
    missing = [policy_name(s) for s, r in zip(sweeps, rows, strict=True) if r is None]
    if missing:
        raise ValueError(f"{shift} at level {level} is missing from the sweeps of {missing}")
    return [r for r in rows if r is not None]


def verdict(value: float, target: float, by_points: bool = True) -> str:
    """"met", or "missed" (with ``by_points``, by how many percentage points)."""
    if value >= target:
        return "met"
    return f"missed by {100 * (target - value):.0f} points" if by_points else "missed"


def randomised_table(sweeps: list[dict], level: int = HEATMAP_LEVEL) -> str:
    """Each randomised recipe (a policy named ``*-dr``, its other training seeds ``*-dr-seedN``) at ``level``, shift by
    shift: every seed's success, the seeds' mean relative success, their episodes pooled against the same recipe
    without randomisation (``beats`` when the pooled 95% interval lies above the other's), then the targets met or
    missed, by how much."""
    by_name = {policy_name(s): s for s in sweeps}
    blocks = []
    for base in sorted(n for n in by_name if n.endswith(RANDOMISED)):
        names = [n for n in sorted(by_name) if SEED_SUFFIX.sub("", n) == base]
        seeds, plain = [by_name[n] for n in names], without_randomisation(base, by_name)
        lines = [f"`{base}`: {len(seeds)} training seeds ({', '.join(f'`{n}`' for n in names)}), level {level}"
                 + (f", against `{policy_name(plain)}`" if plain else ""), "",
                 "| shift | " + " | ".join("shipped" if n == base else n[len(base) + 1:] for n in names)
                 + " | mean relative | pooled (95% CI) | without randomisation (95% CI) | beats it |",
                 "| --- | " + "--- | " * len(seeds) + "--- | --- | --- | --- |"]
        means, beaten, spreads = {}, [], {}
        shifts = [r["shift"] for r in at_level(seeds[0], level)]
        for shift, lv in [("none", 0)] + [(name, level) for name in shifts]:
            rows = arms(seeds, shift, lv)
            spreads[shift] = max(r["success"] for r in rows) - min(r["success"] for r in rows)
            won, n = sum(round(r["success"] * r["episodes"]) for r in rows), sum(r["episodes"] for r in rows)
            lo, hi = wilson_interval(won, n)
            other = arm(plain, shift, lv) if plain else None
            if shift != "none" and all(r["relative"] is not None for r in rows):
                means[shift] = mean_relative([r["relative"] for r in rows])
            if shift != "none" and other is not None and lo > other["success_ci95"][1]:
                beaten.append(shift)
            lines.append(f"| {'control' if shift == 'none' else shift} | "
                         + " | ".join(f"{100 * r['success']:.0f}%" for r in rows)
                         + f" | {f'{100 * means[shift]:.0f}%' if shift in means else '-'} | "
                         f"{100 * won / n:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%), {n} ep. | "
                         + ("-" if other is None else f"{100 * other['success']:.0f}% "
                            f"({100 * other['success_ci95'][0]:.0f}-{100 * other['success_ci95'][1]:.0f}%)")
                         + f" | {'-' if shift == 'none' or other is None else 'yes' if shift in beaten else 'no'} |")
        lines += [""] + target_lines(seeds, shifts, means, beaten, plain) + [spread_line(seeds, spreads)]
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks) if blocks else "(no randomised recipe has been swept)"


def without_randomisation(base: str, by_name: dict[str, dict]) -> dict | None:
    """The swept recipe ``base`` (``*-dr``) is compared with: its name less ``-dr``, less its last words until a swept
    policy has it (``act-camera-snapshot-touch-dr`` against ``act-camera-snapshot``); None if none has."""
    words = base[: -len(RANDOMISED)].split("-")
    while words and "-".join(words) not in by_name:
        words.pop()
    return by_name.get("-".join(words)) if words else None


def target_lines(seeds: list[dict], shifts: list[str], means: dict[str, float], beaten: list[str],
                 plain: dict | None) -> list[str]:
    """docs/shifts.md's targets for a randomised recipe, each met or missed: the seeds' mean control, each shift's
    (the wholly unseen ones reported apart) and the overall mean relative success, and how many of ``shifts`` it beats
    the recipe without randomisation on."""
    control = float(np.mean([r["success"] for r in arms(seeds, "none", 0)]))
    below = sorted(((v, k) for k, v in means.items() if v < TARGET_EVERY and k not in UNSEEN))
    unseen = ", ".join(f"`{k}` {100 * means[k]:.0f}%" for k in UNSEEN if k in means)
    overall = mean_relative(list(means.values())) if means else 0.0
    lines = [f"- control {100 * control:.0f}% (target {100 * TARGET_CONTROL:.0f}%): {verdict(control, TARGET_CONTROL)}",
             f"- at least {100 * TARGET_EVERY:.0f}% of the control on every shift but the unseen ones: "
             + ("missed (" + ", ".join(f"`{k}` {100 * v:.0f}%" for v, k in below) + ")" if below else "met")
             + (f"; unseen: {unseen}" if unseen else ""),
             f"- at least {100 * TARGET_MEAN:.0f}% on average: {100 * overall:.0f}%, {verdict(overall, TARGET_MEAN)}"]
    if plain is not None:
        which = f" ({', '.join(f'`{b}`' for b in beaten)})" if beaten else ""
        lines.append(f"- beats `{policy_name(plain)}` beyond the intervals on at least {TARGET_BEATEN} shifts of "
                     f"{len(shifts)}: on {len(beaten)}{which}, {verdict(len(beaten), TARGET_BEATEN, by_points=False)}")
    return lines


def spread_line(seeds: list[dict], spreads: dict[str, float]) -> str:
    """The seeds' agreement: every arm's highest success less its lowest, against ``TARGET_SPREAD``."""
    if len(seeds) < 2:
        return f"- the seeds within {100 * TARGET_SPREAD:.0f} points of each other on every arm: one seed, not measured"
    apart = sorted(((v, k) for k, v in spreads.items() if v > TARGET_SPREAD + 1e-9), reverse=True)
    return (f"- the seeds within {100 * TARGET_SPREAD:.0f} points of each other on every arm: "
            + ("missed (" + ", ".join(f"`{k}` {100 * v:.0f} points" for v, k in apart) + ")" if apart else "met"))


def fill_shift_tables(text: str, sweeps: list[dict]) -> str:
    """``text`` with its marked regions (the shift list, the headline, the table) rewritten."""
    parts = {"list": shift_list(), "shades": shade_table(), "headline": shifts_headline(sweeps),
             "randomised": randomised_table(sweeps),
             "table": sweep_index(sweeps) + "\n\nMade by:\n\n" + provenance(sweeps)}
    for mark, body in parts.items():
        pattern = re.compile(rf"(<!-- shifts {mark} -->\n).*?(<!-- end shifts -->)", flags=re.S)
        found = pattern.search(text)
        if found:
            text = text[: found.start()] + f"{found.group(1)}{body}\n{found.group(2)}" + text[found.end():]
    return text
