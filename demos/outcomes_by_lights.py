"""How a policy's `lighting` episodes fared by the light they were played under.

    colorsort-eval --policy baselines/act-camera-snapshot --variant lighting --episodes 20 --json outputs/lights.json
    python demos/outcomes_by_lights.py outputs/lights.json
    python demos/outcomes_by_lights.py --demos outputs/baselines/camera-snapshot/data/lighting-8-late100

Every episode of the ``lighting`` variant draws its lights from its seed (``Variant.lighting``: brightness
x0.5-1.6 of the cell's, a tint from warm to cold). This replays each episode's reset, without rendering, to
read the lights it drew, and prints per band of brightness how many episodes there were, how many succeeded,
and how many boxes went into a wrong bin or were dropped. ``--demos ROOT`` prints instead the brightness each
episode of a ``colorsort-collect`` dataset was recorded under (its seeds are the collection's seed + episode,
its range the collection's ``--brightness`` where given).
"""

from __future__ import annotations

import argparse
import json
from functools import partial
from pathlib import Path

from colorsort.benchmark.gym_env import ColorSortGymEnv
from colorsort.config import Lighting
from colorsort.variants import get_variant

BRIGHTNESS_BANDS = ((0.5, 0.65), (0.65, 0.8), (0.8, 1.0), (1.0, 1.6))  # x the cell's own lights


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


def rows(episodes: list[dict], lights: dict[int, Lighting]) -> list[str]:
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


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("evals", nargs="*", type=Path, help="colorsort-eval --json files")
    p.add_argument("--demos", type=Path, help="a colorsort-collect dataset: the brightness of each episode")
    args = p.parse_args()
    if args.demos is not None:
        values = demo_brightness(args.demos)
        print(f"{len(values)} episodes of {args.demos}, brightness: {', '.join(f'{b:.2f}' for b in values)}")
        return
    if not args.evals:
        p.error("give colorsort-eval --json files, or --demos ROOT")
    runs = [json.loads(f.read_text()) for f in args.evals]
    variants = {r["variant"] for r in runs}
    if len(variants) != 1:
        raise SystemExit(f"give evaluations of one variant; these are of {sorted(variants)}")
    episodes = [e for r in runs for e in r["per_episode"]]
    lights = episode_lights(variants.pop(), sorted({e["seed"] for e in episodes}))
    print(f"{len(episodes)} episodes of {', '.join(map(str, args.evals))}")
    print("| lights | episodes | successes | boxes in a wrong bin | dropped |")
    print("| --- | --- | --- | --- | --- |")
    print("\n".join(rows(episodes, lights)))


if __name__ == "__main__":
    main()
