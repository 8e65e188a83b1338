"""Analyses of ``colorsort-eval --json`` files: where boxes went wrong by pose, by light, and how much later one
policy places its first box than another (``colorsort-analyze``).

- ``pose_report``: per band of |yaw| and of the offset from the belt's centre line (each box's ``yaw`` [deg] and
  ``offset`` [m]), how many boxes there were and how many went into a wrong bin or were dropped; where the files
  have how the cup held each box (``grip_offset`` [m] off the cup's axis, ``grip_yaw`` [deg]), how many of the
  dropped boxes were never picked, and the same bands of those over the boxes picked, with the median and 90th
  percentile of each.
- ``lights_report``: per band of brightness, the ``lighting`` episodes under it (each episode's lights replayed from
  its seed, ``Variant.lighting``, without rendering), their successes, wrong bins and drops; ``demo_brightness``:
  the brightness each episode of a ``colorsort-collect`` dataset was recorded under.
- ``first_box_delay``: the median over the seeds both placed a box of NEW's first placed box minus OLD's [s].
"""

from __future__ import annotations

import json
import statistics
from functools import partial
from pathlib import Path

from colorsort.config import Lighting
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.errors import ConfigError
from colorsort.variants import get_variant

YAW_BANDS = ((0.0, 15.0), (15.0, 30.0), (30.0, 45.0))  # [deg] |yaw|
OFFSET_BANDS = ((-0.05, -0.025), (-0.025, 0.0), (0.0, 0.025), (0.025, 0.05))  # [m], + toward the bins
# [m] off the cup's axis; past 25 mm the axis is beyond the edge of the box (a 5 cm cube)
GRIP_OFFSET_BANDS = ((0.0, 0.005), (0.005, 0.01), (0.01, 0.02), (0.02, 0.03), (0.03, 0.06))
GRIP_YAW_BANDS = ((0.0, 5.0), (5.0, 15.0), (15.0, 45.0))  # [deg] |turn| against the cup
BRIGHTNESS_BANDS = ((0.5, 0.65), (0.65, 0.8), (0.8, 1.0), (1.0, 1.6))  # x the cell's own lights
HEADER = ["| band | boxes | in a wrong bin | dropped |", "| --- | --- | --- | --- |"]


def bands(boxes: list[dict], key: str, edges: tuple[tuple[float, float], ...], scale: float, unit: str) -> list[str]:
    """One Markdown row per band of ``key`` (the last band closed at its top): boxes, wrong bin, dropped."""
    rows = []
    for k, (lo, hi) in enumerate(edges):
        last = k == len(edges) - 1
        inside = [b for b in boxes if lo <= b[key] < hi or (last and b[key] == hi)]
        wrong = sum(b["outcome"] == "misplaced" for b in inside)
        dropped = sum(b["outcome"] == "dropped" for b in inside)
        share = f"{100 * wrong / len(inside):.0f}%" if inside else "-"
        band = f"{key} {lo * scale:g} to {hi * scale:g} {unit}"
        rows.append(f"| {band} | {len(inside)} | {wrong} ({share}) | {dropped} |")
    return rows


def spread(boxes: list[dict], key: str, scale: float, unit: str) -> str:
    """``key``'s median and 90th percentile over ``boxes``, scaled to ``unit``."""
    values = sorted(b[key] * scale for b in boxes)
    def at(q: float) -> float:
        return values[min(len(values) - 1, round(q * (len(values) - 1)))]
    return f"{key} median {at(0.5):.1f} {unit}, 90th percentile {at(0.9):.1f} {unit}"


def pose_report(evaluations: list[dict]) -> list[str]:
    """The lines ``colorsort-analyze by-pose`` prints for ``evaluations`` (``colorsort-eval --json`` contents)."""
    boxes = [b for ev in evaluations for e in ev["per_episode"] for b in e["boxes"]
             if b["outcome"] in ("placed", "misplaced", "dropped")]
    if not boxes or "yaw" not in boxes[0]:
        raise ConfigError("no boxes with offset and yaw: write the files with this version's colorsort-eval --json")
    for b in boxes:
        b["turned"] = abs(b["yaw"])
    lines = [f"{len(boxes)} boxes", *HEADER,
             *bands(boxes, "turned", YAW_BANDS, 1, "deg"), *bands(boxes, "offset", OFFSET_BANDS, 100, "cm")]
    if any("grip_offset" in b for b in boxes):  # grips recorded: a box never picked or one lost after a seal
        dropped = [b for b in boxes if b["outcome"] == "dropped"]
        never = sum(b.get("grip_offset") is None for b in dropped)
        lines += ["", f"{len(dropped)} dropped: {never} never picked, {len(dropped) - never} lost after the cup "
                      "picked them"]
    picked = [b for b in boxes if b.get("grip_offset") is not None]
    if picked:
        for b in picked:
            b["gripped off axis"], b["gripped turned"] = b["grip_offset"], abs(b["grip_yaw"])
        held = f"{spread(picked, 'gripped off axis', 1000, 'mm')}; {spread(picked, 'gripped turned', 1, 'deg')}"
        lines += ["", f"how the cup held the {len(picked)} boxes it picked: {held}", *HEADER,
                  *bands(picked, "gripped off axis", GRIP_OFFSET_BANDS, 1000, "mm"),
                  *bands(picked, "gripped turned", GRIP_YAW_BANDS, 1, "deg")]
    return lines


def episode_lights(variant: str, seeds: list[int],
                   brightness: tuple[float, float] | None = None) -> dict[int, Lighting]:
    """The lights each seed of ``variant`` draws at reset (no cameras rendered); ``brightness``: the
    range a collection's ``--brightness`` drew from instead of the variant's."""
    env = ColorSortGymEnv(variant, cameras=())
    draw = partial(get_variant(variant).lighting, brightness=brightness)
    lights = {}
    for seed in seeds:
        env.env.reset(seed=seed, lighting=draw)  # as the gym env's reset, and the collector's
        lights[seed] = env.env.plant.lighting
    env.close()
    return lights


def light_rows(episodes: list[dict], lights: dict[int, Lighting]) -> list[str]:
    """One Markdown row per brightness band (the last closed at its top)."""
    out = []
    for k, (lo, hi) in enumerate(BRIGHTNESS_BANDS):
        last = k == len(BRIGHTNESS_BANDS) - 1
        inside = [e for e in episodes if lo <= lights[e["seed"]].brightness < hi
                  or (last and lights[e["seed"]].brightness == hi)]
        won = sum(e["success"] for e in inside)
        wrong, dropped = sum(e["misplaced"] for e in inside), sum(e["dropped"] for e in inside)
        share = f"{100 * won / len(inside):.0f}%" if inside else "-"
        out.append(f"| brightness {lo:g} to {hi:g} | {len(inside)} | {won} ({share}) | {wrong} | {dropped} |")
    return out


def demo_brightness(root: Path) -> list[float]:
    """The brightness of each kept episode of a ``colorsort-collect`` dataset, in episode order."""
    settings = json.loads((root / "meta" / "colorsort.json").read_text())
    seeds = [settings["settings"]["seed"] + i for i in settings["episodes"]]
    brightness = settings["settings"].get("brightness")  # set when collected with --brightness
    lights = episode_lights(settings["settings"]["variant"], seeds, tuple(brightness) if brightness else None)
    return [lights[s].brightness for s in seeds]


def lights_report(evaluations: list[dict]) -> list[str]:
    """The lines ``colorsort-analyze by-lights`` prints for ``evaluations`` of one variant."""
    variants = {ev["variant"] for ev in evaluations}
    if len(variants) != 1:
        raise ConfigError(f"give evaluations of one variant; these are of {sorted(variants)}")
    episodes = [e for ev in evaluations for e in ev["per_episode"]]
    lights = episode_lights(variants.pop(), sorted({e["seed"] for e in episodes}))
    return [f"{len(episodes)} episodes", "| lights | episodes | successes | boxes in a wrong bin | dropped |",
            "| --- | --- | --- | --- | --- |", *light_rows(episodes, lights)]


def first_placed(evaluation: dict) -> dict[int, float]:
    """{seed: sim time [s] of its first box placed in the bin of its colour} for the episodes that placed one."""
    return {e["seed"]: min(b["time"] for b in e["boxes"] if b["outcome"] == "placed")
            for e in evaluation["per_episode"] if any(b["outcome"] == "placed" for b in e["boxes"])}


def first_box_delay(new: dict, old: dict) -> tuple[float, int]:
    """(median [s] of new's first placed box minus old's over the seeds both placed one, how many seeds)."""
    a, b = first_placed(new), first_placed(old)
    shared = sorted(a.keys() & b.keys())
    if not shared:
        raise ConfigError("no evaluation seed where both runs placed a box: give two evaluations of the same seeds")
    return statistics.median(a[s] - b[s] for s in shared), len(shared)
