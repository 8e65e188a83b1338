"""The tracking expert's cycle against the physical bound: the arm's joint speeds and the cell's geometry.

    python demos/bench_bound.py [--preset tracking-fast] [--seeds 3] [--boxes 20]

Prints, per bin and leg, the shortest cycle (``colorsort.expert.bound``: the box met at the best point
of the reach window) three ways: two bounds (each leg at the datasheet joint speeds, acceleration
unlimited; then at rest on the box and over the bin, with the expert's acceleration) and a ruckig
reference (every leg rest to rest, with the expert's acceleration and jerk); then the
expert's measured cycle per phase (``colorsort-sort``'s phase times on the same preset, sim seconds per
box placed) and the ratio of its active cycle (intercept, track, carry, release) to each, averaged over
the bins (a box's colour, so its bin, is drawn uniformly). Last, the same with a box every
``--saturate`` seconds (0.8 by default, 2.5 times the preset's rate): a box is always waiting, so the
cycle measured there is the expert's own and not the spawner's.
"""

from __future__ import annotations

import argparse

from colorsort.benchmark.sorting import SortConfig, run_sort
from colorsort.cell.env import ColorSort
from colorsort.cell.referee import Outcome
from colorsort.config import BIN_COLORS
from colorsort.expert.bound import LEGS, MODES, shortest_cycle
from colorsort.expert.factory import make_expert
from colorsort.expert.tracking import TrackingExpert
from colorsort.results import recorded

ACTIVE = ("intercept box", "track box", "move over bin", "release")  # the expert's phases that a cycle needs


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset", default="tracking-fast", choices=["tracking", "tracking-fast"])
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--boxes", type=int, default=20)
    p.add_argument("--saturate", type=float, default=0.8, help="spawn period [s] of the saturated run")
    p.add_argument("--saturate-seconds", type=float, default=60.0, help="sim time of the saturated run [s]")
    args = p.parse_args()

    env = ColorSort(robots="IRB140", preset=args.preset, has_offscreen_renderer=True, use_camera_obs=False,
                    ignore_done=True, seed=0)
    env.reset()
    expert = make_expert(env)
    assert isinstance(expert, TrackingExpert)
    cycles = {mode: {c: shortest_cycle(expert, c, mode) for c in BIN_COLORS} for mode in MODES}
    env.close()
    m = expert.config.motion
    print(f"IRB140 on '{args.preset}': the shortest cycle per bin [s], the box met at x on the belt; speed: each leg "
          f"at the datasheet joint speeds, acceleration unlimited (a bound); stops: at rest on the box and over the "
          f"bin, acceleration {m.acceleration:g} rad/s^2, jerk unlimited (a bound); ruckig: every leg rest to rest, "
          f"jerk {m.jerk:g} rad/s^3 too (a reference)")
    columns = [(mode, c) for mode in MODES for c in BIN_COLORS]
    print("| leg | " + " | ".join(f"{mode}: {c} (x = {cycles[mode][c].x:.2f} m)" for mode, c in columns) + " |")
    print("| --- |" + " --- |" * len(columns))
    for leg in LEGS:
        print(f"| {leg} | " + " | ".join(f"{cycles[mode][c].legs[leg]:.3f}" for mode, c in columns) + " |")
    print("| all | " + " | ".join(f"{cycles[mode][c].total:.3f}" for mode, c in columns) + " |")
    mean = {mode: sum(c.total for c in cycles[mode].values()) / len(BIN_COLORS) for mode in MODES}

    phases: dict[str, float] = {}
    placed = 0
    for seed in range(args.seeds):
        report = run_sort(SortConfig(preset=args.preset, boxes=args.boxes, seed=seed), progress=False,
                          log=lambda _: None)
        placed += report.correct
        for phase, seconds in report.phase_seconds.items():
            phases[phase] = phases.get(phase, 0.0) + seconds
    print(f"\nthe expert, seeds 0..{args.seeds - 1}, {args.boxes} boxes each: {placed} placed; sim seconds per box "
          "placed, by phase")
    print("| phase | seconds | in the active cycle |")
    print("| --- | --- | --- |")
    for phase, seconds in sorted(phases.items(), key=lambda kv: -kv[1]):
        print(f"| {phase} | {seconds / placed:.3f} | {'yes' if phase in ACTIVE else 'no (waiting for a box)'} |")
    active = sum(phases.get(p, 0.0) for p in ACTIVE) / placed
    print(f"\nexpert's active cycle {active:.3f} s; against the bins' mean cycle: "
          + "; ".join(f"{mode} {mean[mode]:.3f} s (ratio {active / mean[mode]:.2f})" for mode in MODES))

    phases, placed = saturated(args.preset, args.saturate, args.saturate_seconds)
    active = sum(phases.get(p, 0.0) for p in ACTIVE) / placed
    print(f"\nsaturated: a box every {args.saturate:g} s for {args.saturate_seconds:g} s of sim time (seed 0), "
          f"{placed} placed (the rest ride off the belt); seconds per box placed: "
          + ", ".join(f"{p} {phases.get(p, 0.0) / placed:.3f}" for p in ACTIVE)
          + f"; active cycle {active:.3f} s: "
          + "; ".join(f"{mode} ratio {active / mean[mode]:.2f}" for mode in MODES))


def saturated(preset: str, period: float, seconds: float) -> tuple[dict[str, float], int]:
    """The expert's sim seconds per phase and boxes placed with a box spawned every ``period`` [s]."""
    env = ColorSort(robots="IRB140", preset=preset, spawn_period=period, has_offscreen_renderer=True,
                    use_camera_obs=False, ignore_done=True, seed=0, time_limit=seconds + 10.0)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    phases: dict[str, float] = {}
    while env.cur_time < seconds:
        action = expert.act(obs)
        phase = expert.phase.value
        phases[phase] = phases.get(phase, 0.0) + env.control_timestep
        obs, *_ = env.step(action)
    placed = sum(e.outcome is Outcome.PLACED for e in env.events)
    env.close()
    return phases, placed


if __name__ == "__main__":
    with recorded(__file__):
        main()
