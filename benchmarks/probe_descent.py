"""How low does the cup come over each box? A policy's descents, box by box, beside whether the vacuum sealed.

    python benchmarks/probe_descent.py --policy expert --variant tracking-jitter --episodes 10
    python benchmarks/probe_descent.py --policy baselines/act-camera-tracking-dagger --variant tracking-jitter \\
        --episodes 50

For every box that rode the belt: the cup body's lowest height [mm] over the box's top face, in any control step
while the cup's axis passed within 20 mm of the box's centre (on the belt, not yet lifted), and whether the cup
sealed it. Printed per band of the box's offset from the belt's centre line (+ toward the bins; the bands of
``colorsort-analyze by-pose``): how many boxes, how many were never sealed, the lowest heights (median, and the
range) of the sealed and the never-sealed ones, and where the cup's axis was from the sealed boxes' centres when
the seal closed (median, mm downstream along the belt and toward the bins). The pad touches a box's top with the
cup about 25 mm over it, so a box never sealed with the cup lower than that was touched off the pad's face, one
never sealed above it was not reached. Episode k runs with the variant's k-th evaluation seed (or ``--seed`` + k),
as colorsort-eval's.
``--expert NAME:VALUE,...`` changes the expert's settings from its belt's preset, as colorsort-collect's does.
``--releases`` prints instead where the cup let go of each box: per colour and outcome, the cup's y at the release
from the centre of the box's own bin (median and range, mm; + away from the belt; the bins stand 325 mm apart,
310 mm wide, red nearest the belt). ``--trace SEED,BOX`` prints instead, for box number BOX (0 the first to
appear) of the episode of env seed SEED, every control step with the cup's axis within 50 mm of it: the cup's
height over its top, suction, the seal.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterator
from typing import NamedTuple

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

import numpy as np  # noqa: E402

from colorsort.benchmark.evaluate import EpisodeRunner, EvalConfig, episode_seeds, observation_settings  # noqa: E402
from colorsort.benchmark.outcomes import OFFSET_BANDS  # noqa: E402
from colorsort.benchmark.policies import ExpertPolicy  # noqa: E402
from colorsort.config import BIN_COLORS  # noqa: E402
from colorsort.expert.config import changed, expert_preset, parse_changes  # noqa: E402
from colorsort.results import recorded  # noqa: E402
from colorsort.variants import get_variant  # noqa: E402

NEAR = 0.02  # [m] the cup's axis this near a box's centre counts as over it


def played(runner: EpisodeRunner, seed: int) -> Iterator[int]:
    """Play the episode of env seed ``seed`` with the runner's policy, yielding the step count after each step."""
    env = runner.env
    obs, _ = env.reset(seed=seed)
    runner.policy.reset(env, seed)
    done, step = False, 0
    while not done:
        obs, _, terminated, truncated, _ = env.step(runner.policy.act(obs))
        done, step = terminated or truncated, step + 1
        yield step


class Descent(NamedTuple):
    """One box's pass under the cup [m]."""

    offset: float  # the box's centre from the belt's centre line, + toward the bins
    lowest: float | None  # the cup's lowest height over the box's top face while over it; None: never over it
    seal: tuple[float, float] | None  # the cup's axis from the box's centre when it sealed (downstream, toward the
    # bins); None: never sealed


def descents(runner: EpisodeRunner, seed: int) -> list[Descent]:
    """One episode: a ``Descent`` per box that left the belt."""
    cell = runner.env.env
    lowest: dict[int, float] = {}
    offset: dict[int, float] = {}
    sealed: dict[int, tuple[float, float]] = {}
    for _ in played(runner, seed):
        seal, layout = cell.plant.seal, cell.layout
        resting = layout.belt_top_z + layout.box_size / 2 + 0.005  # [m] a box centre this low is on the belt
        cup = cell.plant.data.xpos[seal.cup]
        for box in cell.boxes_in_play():
            pos = cell.box_pos(box)
            if box.serial < 0 or pos[2] > resting:
                continue
            offset.setdefault(box.serial, float(pos[1] - layout.belt_y))
            if np.hypot(cup[0] - pos[0], cup[1] - pos[1]) < NEAR:
                height = float(cup[2] - pos[2] - layout.box_size / 2)
                lowest[box.serial] = min(lowest.get(box.serial, np.inf), height)
        if seal.held is not None:  # the pool's boxes and the seal's are in one order
            box = cell.boxes[seal.held]
            if box.serial not in sealed:
                pos = cell.box_pos(box)  # the belt runs toward -x
                sealed[box.serial] = (float(pos[0] - cup[0]), float(cup[1] - pos[1]))
    return [Descent(offset.get(e.serial, float("nan")), lowest.get(e.serial), sealed.get(e.serial))
            for e in cell.events[: runner.env.variant.boxes]]


def releases(runner: EpisodeRunner, seed: int) -> list[tuple[str, str, float]]:
    """One episode: (colour, outcome, the cup's y at the release from the centre of the colour's bin [m]) per box
    the cup let go of."""
    cell = runner.env.env
    let_go: dict[int, tuple[str, float]] = {}
    before = None
    for _ in played(runner, seed):
        seal = cell.plant.seal
        held = cell.boxes[seal.held] if seal.held is not None else None
        if before is not None and held is not before and before.color in BIN_COLORS:
            bin_y = cell.layout.bin_center(BIN_COLORS.index(before.color))[1]
            let_go.setdefault(before.serial, (before.color, float(cell.plant.data.xpos[seal.cup][1] - bin_y)))
        before = held
    outcome = {e.serial: e.outcome.value for e in cell.events}
    return [(color, outcome.get(serial, "in play"), dy) for serial, (color, dy) in let_go.items()]


def release_table(who: str, variant: str, episodes: int, boxes: list[tuple[str, str, float]]) -> None:
    """Print ``releases``' rows of every episode, grouped by colour and outcome."""
    print(f"{who} on {variant}, {episodes} episodes, {len(boxes)} boxes let go")
    print("| colour | outcome | boxes | the cup's y at the release from its bin's centre [mm]: median (range) |")
    print("| --- | --- | --- | --- |")
    for color in BIN_COLORS:
        for outcome in sorted({o for c, o, _ in boxes if c == color}):
            ys = [1000 * dy for c, o, dy in boxes if (c, o) == (color, outcome)]
            print(f"| {color} | {outcome} | {len(ys)} | {np.median(ys):.0f} ({min(ys):.0f} to {max(ys):.0f}) |")


def trace(runner: EpisodeRunner, seed: int, serial: int) -> None:
    """Print the steps of episode ``seed`` in which the cup passes within 50 mm of box ``serial``'s centre."""
    cell = runner.env.env
    print(f"{runner.policy.name}, seed {seed}, box {serial}")
    print("| step | cup over the top [mm] | axis from the centre [mm] | suction | sealed |")
    print("| --- | --- | --- | --- | --- |")
    for step in played(runner, seed):
        seal, layout = cell.plant.seal, cell.layout
        cup = cell.plant.data.xpos[seal.cup]
        for box in cell.boxes_in_play():
            pos = cell.box_pos(box)
            near = np.hypot(cup[0] - pos[0], cup[1] - pos[1])
            if box.serial == serial and near < 0.05:
                held = seal.held is not None and cell.boxes[seal.held].serial == serial
                print(f"| {step} | {1000 * (cup[2] - pos[2] - layout.box_size / 2):.1f} | {1000 * near:.0f} "
                      f"| {'on' if seal.commanded else 'off'} | {'yes' if held else 'no'} |")


def summary(heights: list[float | None]) -> str:
    """'median (min-max)' of the heights [mm], and how many boxes the cup never passed over (None)."""
    found = [1000 * h for h in heights if h is not None]
    missed = len(heights) - len(found)
    text = f"{np.median(found):.1f} ({min(found):.1f}-{max(found):.1f})" if found else "-"
    return text + (f", {missed} never under the cup" if missed else "")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", default="expert", help="expert, or a LeRobot checkpoint folder")
    p.add_argument("--variant", default="tracking-jitter")
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--seed", type=int, default=None, help="first seed (default: the variant's evaluation seeds)")
    p.add_argument("--trace", default=None, metavar="SEED,BOX", help="step by step over one box of one episode")
    p.add_argument("--releases", action="store_true", help="where the cup let go of each box, by colour and outcome")
    p.add_argument("--expert", default=None, metavar="NAME:VALUE,...",
                   help="with --policy expert: its settings changed from its preset")
    args = p.parse_args()
    if args.expert and args.policy != "expert":
        p.error("--expert changes the scripted expert's settings: give it with --policy expert")
    variant = get_variant(args.variant)
    cameras, size = observation_settings(args.policy, None, None)
    runner = EpisodeRunner(EvalConfig(args.policy, variant.name, size, cameras))
    if args.expert:
        runner.policy = ExpertPolicy(changed(expert_preset(variant.task_config.tracking), parse_changes(args.expert)))
    boxes: list[Descent] = []
    let_go: list[tuple[str, str, float]] = []
    try:
        if args.trace:
            seed, serial = (int(t) for t in args.trace.split(","))
            trace(runner, seed, serial)
            return
        seeds = episode_seeds(variant, args.episodes, args.seed)
        if args.releases:
            let_go = [box for seed in seeds for box in releases(runner, seed)]
        else:
            boxes = [box for seed in seeds for box in descents(runner, seed)]
    finally:
        runner.close()
    who = f"expert ({args.expert})" if args.expert else args.policy
    if args.releases:
        release_table(who, variant.name, args.episodes, let_go)
        return
    print(f"{who} on {variant.name}, {args.episodes} episodes, {len(boxes)} boxes")
    print("| offset [cm] | boxes | never sealed | lowest [mm], sealed: median (range) | lowest [mm], never sealed "
          "| the seal's axis from the centre [mm]: downstream, toward the bins |")
    print("| --- | --- | --- | --- | --- | --- |")
    for lo, hi in OFFSET_BANDS:
        inside = [b for b in boxes if lo <= b.offset < hi or (hi == OFFSET_BANDS[-1][1] and b.offset == hi)]
        won = [b for b in inside if b.seal is not None]
        lost = [b.lowest for b in inside if b.seal is None]
        where = np.median([b.seal for b in won if b.seal is not None], axis=0) * 1000 if won else None
        print(f"| {100 * lo:g} to {100 * hi:g} | {len(inside)} | {len(lost)} | {summary([b.lowest for b in won])} | "
              f"{summary(lost) if lost else ''} | {'' if where is None else f'{where[0]:.0f}, {where[1]:.0f}'} |")


if __name__ == "__main__":
    with recorded(__file__):
        main()
