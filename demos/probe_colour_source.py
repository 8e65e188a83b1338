"""Which camera a camera policy takes a box's colour from: its snapshot photo shows the box repainted.

    python demos/probe_colour_source.py --policy baselines/act-camera-snapshot --variant default \
        --episodes 10 --paint red:blue

The ``snapshot`` camera's photo is taken when the ray fires (``colorsort/cell/snapshot.py``). Here every
box of the first colour in play is painted the second colour for that photo only, and back at once:
the live cameras (``sensor``, ``wrist``, ``scene``), the expert's colour sensor and the referee see
the box as it is. A policy that takes the colour from the photo carries a red box painted blue to
the blue bin; one that takes it from the wrist camera's view of the held box carries it to the red
bin; one torn between them, to the bin in the middle. The episodes run as ``colorsort-eval`` runs
them; prints, with the photo as it is and painted, on the same evaluation seeds, how many episodes
succeeded and where the boxes of the first colour went. It prints only (no docs/results file): the
checkpoints it probes come from ``colorsort-baseline`` runs, not from ``make bench``.
"""

from __future__ import annotations

import argparse
import os
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext

os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import EpisodeRunner, EvalSettings, episode_seeds, observation_settings  # noqa: E402
from colorsort.benchmark.gym_env import ColorSortGymEnv  # noqa: E402
from colorsort.cell.boxes import BoxStatus  # noqa: E402
from colorsort.cell.snapshot import SNAPSHOT  # noqa: E402
from colorsort.config import BIN_COLORS, COLORS  # noqa: E402
from colorsort.variants import get_variant  # noqa: E402


def parse_paint(text: str) -> tuple[str, str]:
    """``"red:blue"`` -> ("red", "blue"); ValueError naming the colours otherwise."""
    parts = text.split(":")
    if len(parts) != 2 or parts[0] == parts[1] or any(c not in COLORS for c in parts):
        raise ValueError(f"--paint {text!r}: give two different colours as FROM:TO, each one of {list(COLORS)}")
    return parts[0], parts[1]


@contextmanager
def painted_snapshots(env: ColorSortGymEnv, source: str, shown: str) -> Iterator[None]:
    """While inside, each snapshot photo shows the boxes of colour ``source`` in play as ``shown``."""
    cell = env.env
    renderer = cell._cameras
    plain = renderer.observe_ray

    def observe_ray(sim, box_detected: bool) -> None:
        pool = cell.plant.pool
        geoms = [pool.geom[b.index] for b in pool.boxes if b.status is BoxStatus.IN_PLAY and b.color == source]
        for g in geoms:
            pool.model.geom_rgba[g] = COLORS[shown]
        try:
            plain(sim, box_detected)
        finally:
            for g in geoms:
                pool.model.geom_rgba[g] = COLORS[source]

    renderer.observe_ray = observe_ray
    try:
        yield
    finally:
        renderer.observe_ray = plain


def run(policy_spec: str, variant_name: str, seeds: list[int], paint: tuple[str, str] | None) -> list[dict]:
    """``colorsort-eval``'s result of each episode (its boxes' colour, outcome and bin) with the snapshot
    painted as ``paint`` says, or as it is."""
    cameras, size = observation_settings(policy_spec, None, None)
    if SNAPSHOT not in cameras:
        raise ValueError(f"{policy_spec} does not take the snapshot camera (its cameras: {list(cameras)})")
    runner = EpisodeRunner(EvalSettings(policy_spec, variant_name, size, cameras))
    try:
        with painted_snapshots(runner.env, *paint) if paint else nullcontext():
            return [runner.episode(seed) for seed in seeds]
    finally:
        runner.close()


def bins_of(episodes: list[dict], color: str) -> Counter:
    """Where the boxes of ``color`` went: a bin's colour, or the outcome (dropped, let through) when none."""
    return Counter(box["bin"] or box["outcome"] for episode in episodes for box in episode["boxes"]
                   if box["color"] == color)


def report(label: str, episodes: list[dict], color: str) -> str:
    wins = sum(e["success"] for e in episodes)
    went = bins_of(episodes, color)
    order = [b for b in BIN_COLORS if b in went] + sorted(k for k in went if k not in BIN_COLORS)
    where = ", ".join(f"{k} {went[k]}" for k in order) or "none"
    return f"| {label} | {wins}/{len(episodes)} | {sum(went.values())} | {where} |"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", required=True, help="a camera policy's pretrained_model folder that takes 'snapshot'")
    p.add_argument("--variant", default="default")
    p.add_argument("--episodes", type=int, default=10, help="the variant's first N evaluation seeds")
    p.add_argument("--paint", default="red:blue", help="FROM:TO: boxes of FROM look TO in the snapshot photo")
    args = p.parse_args()
    try:
        source, shown = parse_paint(args.paint)
        variant = get_variant(args.variant)
    except ValueError as e:
        p.error(str(e))
    seeds = episode_seeds(variant, args.episodes, None)
    try:
        plain = run(args.policy, args.variant, seeds, None)
    except ValueError as e:  # not a checkpoint, or one without the snapshot camera
        p.error(str(e))
    painted = run(args.policy, args.variant, seeds, (source, shown))
    print(f"{args.policy} on {args.variant}, evaluation seeds {seeds[0]}-{seeds[-1]}: where the {source} boxes went")
    print(f"| snapshot photo | success | {source} boxes | went to |")
    print("| --- | --- | --- | --- |")
    print(report("as it is", plain, source))
    print(report(f"{source} boxes painted {shown}", painted, source))


if __name__ == "__main__":
    main()
