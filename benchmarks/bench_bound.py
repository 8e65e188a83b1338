"""The tracking expert's cycle against the physical bound: the arm's joint speeds and the cell's geometry.

    python benchmarks/bench_bound.py [--preset tracking-fast] [--seeds 10] [--boxes 20] [--jerk 150] [--acceleration 15]
        [--touch-speed 0.16] [--lift 0.08] [--drop-slots 2] [--wait-at-wait-pose]

Prints, per bin and leg, the shortest cycle (``studies.cycle_bound``: the box met at the best point
of the reach window) four ways: three bounds (each leg at the datasheet joint speeds, acceleration
unlimited; then at rest on the box and over the bin, with the expert's acceleration; then with its
jerk too) and a ruckig reference (every leg rest to rest, with the expert's acceleration and jerk); then the
expert's measured cycle per phase (the phase times ``colorsort-sort`` reports, on the same preset and seeds,
from each seed's first interception on, sim seconds per box placed) and the ratio of its active cycle
(intercept, track, carry, release, and the way back: the tracking preset waits over the bin when no box is
within reach yet and then meets it in one motion; an expert that waits at the wait pose counts the way there) to
each bound for the same boxes: the bins' cycles weighted by how many of the placed boxes went to each
(a box's colour is drawn uniformly, but a few seeds' mix is not: the far bin's cycle is 1.6 times the
near one's). The ratio to the bins' plain mean is printed too. An interception that
starts before its box is within reach ends as the box enters the reach window, so part of it is
waiting for the box: the script also gives that part (``bound.waiting_time``: the approach's duration
less the time-optimal plan between the same states) and the cycle without it, the time the arm's
motion takes. Last, the same with a box every ``--saturate`` seconds (0.8 by default, 2.5 times the
preset's rate), most boxes riding off the belt unpicked.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field, replace

import numpy as np
from studies.cycle_bound import LEGS, MODES, Cycle, commanded_peaks, shortest_cycle, touch_cost, waiting_time

from colorsort.cell.referee import Outcome
from colorsort.config import BIN_COLORS, make_config, sorting_time_limit
from colorsort.envs.robosuite_task import ColorSort
from colorsort.expert.config import TRACKING_EXPERT, ExpertConfig
from colorsort.expert.factory import make_expert
from colorsort.expert.planning import JointTrajectory
from colorsort.expert.tracking import TrackingExpert, TrackingPhase
from colorsort.results import recorded

# the expert's phases that a cycle needs: the way back from the bin counts whether it heads for the next box or,
# none being within reach yet, for the wait pose at the upstream end of the reach window, where boxes come in
# (an expert that waits over the bin instead meets the next box from there: its interception is the way back)
ACTIVE = tuple(p.value for p in (TrackingPhase.INTERCEPT, TrackingPhase.TRACK, TrackingPhase.LIFT,
                                 TrackingPhase.MOVE_OVER_BIN,
                                 TrackingPhase.RELEASE, TrackingPhase.MOVE_TO_WAIT))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset", default="tracking-fast", choices=["tracking", "tracking-fast"])
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--boxes", type=int, default=20)
    p.add_argument("--saturate", type=float, default=0.8, help="spawn period [s] of the saturated run")
    p.add_argument("--saturate-seconds", type=float, default=60.0, help="sim time of the saturated run [s]")
    p.add_argument("--jerk", type=float, default=TRACKING_EXPERT.motion.jerk,
                   help="the expert's joint jerk limit [rad/s^3] (its preset's by default), for the expert and the "
                        "ruckig reference")
    p.add_argument("--acceleration", type=float, default=TRACKING_EXPERT.motion.acceleration,
                   help="the expert's joint acceleration limit [rad/s^2], every joint, as --jerk (by default its "
                        "preset's: each joint's own torque-limited acceleration)")
    p.add_argument("--touch-speed", type=float, default=TRACKING_EXPERT.touch_speed,
                   help="the expert's guarded descent onto the moving box [m/s] (its preset's by default)")
    p.add_argument("--lift", type=float, default=TRACKING_EXPERT.track_lift_time,
                   help="the expert's time lifting the box off the moving belt [s] (its preset's by default)")
    p.add_argument("--drop-slots", type=int, default=TRACKING_EXPERT.drop_slots,
                   help="release points per bin, the quickest first (its preset's by default)")
    p.add_argument("--wait-at-wait-pose", action="store_true",
                   help="after a release with no box within reach, wait at the wait pose, not over the bin")
    args = p.parse_args()
    config = replace(TRACKING_EXPERT, touch_speed=args.touch_speed, track_lift_time=args.lift,
                     drop_slots=args.drop_slots, wait_over_bin=not args.wait_at_wait_pose,
                     motion=replace(TRACKING_EXPERT.motion, acceleration=args.acceleration, jerk=args.jerk))

    env = ColorSort(robots="IRB140", preset=args.preset, has_offscreen_renderer=True, use_camera_obs=False,
                    ignore_done=True, seed=0)
    env.reset()
    expert = make_expert(env, config)
    assert isinstance(expert, TrackingExpert)
    cycles = {mode: {c: shortest_cycle(expert, c, mode) for c in BIN_COLORS} for mode in MODES}
    env.close()
    lim = expert.limits
    accelerations = ", ".join(f"{a:.1f}" for a in lim.acceleration)
    jerks = ", ".join(f"{j:g}" for j in np.unique(lim.jerk))
    print(f"IRB140 on '{args.preset}': the shortest cycle per bin [s], the box met at x on the belt; speed: each leg "
          f"at the datasheet joint speeds, acceleration unlimited (a bound); stops: at rest on the box and over the "
          f"bin, the expert's joint accelerations ({accelerations} rad/s^2, joints 1-{len(lim.acceleration)}), jerk "
          f"unlimited (a bound); jerk: the same, jerk {jerks} rad/s^3 too (the bound at the expert's limits); "
          f"ruckig: every leg rest to rest at the expert's limits (a reference)")
    columns = [(mode, c) for mode in MODES for c in BIN_COLORS]
    print("| leg | " + " | ".join(f"{mode}: {c} (x = {cycles[mode][c].x:.2f} m)" for mode, c in columns) + " |")
    print("| --- |" + " --- |" * len(columns))
    for leg in LEGS:
        print(f"| {leg} | " + " | ".join(f"{cycles[mode][c].legs[leg]:.3f}" for mode, c in columns) + " |")
    print("| all | " + " | ".join(f"{cycles[mode][c].total:.3f}" for mode, c in columns) + " |")
    print(f"the touch-off (from {expert.descent.start:.2f} m, over the tallest box the cell accepts, down at "
          f"{config.touch_speed:g} m/s) onto a 10 cm box takes longer than the leg down onto it by: " + ", ".join(
              f"{mode} {touch_cost(expert, cycles[mode]['green']):.3f} s" for mode in MODES) + " (green)")
    mean = {mode: sum(c.total for c in cycles[mode].values()) / len(BIN_COLORS) for mode in MODES}

    totals = Tally()
    for seed in range(args.seeds):
        totals.add(run_expert(config, args.preset, seed, boxes=args.boxes))
    print(f"\nthe expert, seeds 0..{args.seeds - 1}, {args.boxes} boxes each: {totals.placed} placed; sim seconds per "
          "box placed, by phase")
    print("| phase | seconds | in the active cycle |")
    print("| --- | --- | --- |")
    for phase, seconds in sorted(totals.phases.items(), key=lambda kv: -kv[1]):
        print(f"| {phase} | {seconds / totals.placed:.3f} | {'yes' if phase in ACTIVE else 'no (waiting for a box)'} |")
    print(f"| of which, in intercept box: waiting for the box to come within reach | {totals.per_box_waited:.3f} | "
          "no |")
    print("\nthe largest joint acceleration and jerk the expert commanded, per phase (its reference's finite "
          "differences at the control period), and the largest share of its planner's limit any joint took")
    print("| phase | acceleration [rad/s^2] | of the joint's limit | jerk [rad/s^3] | of the joint's limit |")
    print("| --- | --- | --- | --- | --- |")
    for phase, (acceleration, jerk) in totals.peaks.items():
        print(f"| {phase} | {acceleration.max():.1f} | {np.max(acceleration / lim.acceleration):.2f} | "
              f"{jerk.max():.0f} | {np.max(jerk / lim.jerk):.2f} |")

    placed = {c: totals.bins.get(c, 0) for c in BIN_COLORS}
    mix = {mode: totals.bound(cycles[mode]) for mode in MODES}
    print("\nboxes placed per bin: " + ", ".join(f"{c} {n}" for c, n in placed.items()))
    print(f"expert's active cycle {totals.active:.3f} s, {totals.arm:.3f} s without the wait for the box; against "
          "the bound for the same boxes (the bins' cycles weighted by the boxes placed in each): " + "; ".join(
              f"{mode} {mix[mode]:.3f} s (ratio {totals.active / mix[mode]:.2f}, {totals.arm / mix[mode]:.2f})"
              for mode in MODES))
    print("against the bins' plain mean: " + "; ".join(
        f"{mode} {mean[mode]:.3f} s (ratio {totals.active / mean[mode]:.2f}, {totals.arm / mean[mode]:.2f})"
        for mode in MODES))

    sat = run_expert(config, args.preset, 0, seconds=args.saturate_seconds, spawn_period=args.saturate)
    print(f"\nsaturated: a box every {args.saturate:g} s for {args.saturate_seconds:g} s of sim time (seed 0), "
          f"{sat.placed} placed (the rest ride off the belt); seconds per box placed: "
          + ", ".join(f"{p} {sat.phases.get(p, 0.0) / sat.placed:.3f}" for p in ACTIVE)
          + f", of which waiting for the box {sat.per_box_waited:.3f}; active cycle {sat.active:.3f} s, "
          f"{sat.arm:.3f} s without the wait: "
          + "; ".join(f"{mode} ratio {sat.active / b:.2f}, {sat.arm / b:.2f}"
                      for mode, b in ((m, sat.bound(cycles[m])) for m in MODES))
          + " (the same boxes' bound)")


@dataclass
class Tally:
    """The expert's sim seconds per phase, boxes placed, and seconds its interceptions waited for the box."""

    phases: dict[str, float] = field(default_factory=dict)
    placed: int = 0
    waited: float = 0.0
    bins: dict[str, int] = field(default_factory=dict)  # boxes placed per bin
    peaks: dict[str, np.ndarray] = field(default_factory=dict)  # per phase, per joint: largest |acceleration|, |jerk|

    def add(self, other: Tally) -> None:
        for phase, seconds in other.phases.items():
            self.phases[phase] = self.phases.get(phase, 0.0) + seconds
        self.placed += other.placed
        self.waited += other.waited
        for color, n in other.bins.items():
            self.bins[color] = self.bins.get(color, 0) + n
        for phase, peak in other.peaks.items():
            self.peaks[phase] = np.maximum(self.peaks.get(phase, peak), peak)

    def bound(self, cycles: dict[str, Cycle]) -> float:
        """[s] the mean of the bins' ``cycles`` weighted by the boxes placed in each."""
        return sum(n * cycles[c].total for c, n in self.bins.items()) / self.placed

    @property
    def active(self) -> float:
        """[s] per box placed in the phases a cycle needs."""
        return sum(self.phases.get(p, 0.0) for p in ACTIVE) / self.placed

    @property
    def per_box_waited(self) -> float:
        """[s] per box placed."""
        return self.waited / self.placed

    @property
    def arm(self) -> float:
        """[s] the active cycle less the wait for the box: the time the arm's motion takes."""
        return self.active - self.per_box_waited


def run_expert(config: ExpertConfig, preset: str, seed: int, boxes: int | None = None, seconds: float | None = None,
               spawn_period: float | None = None) -> Tally:
    """Run the IRB 140's expert (``config``) until ``boxes`` boxes have left play or ``seconds`` [s] of sim time
    have passed (one of the two), a box spawned every ``spawn_period`` [s] (the preset's by default)."""
    task = make_config(preset)
    if spawn_period is not None:
        task = replace(task, spawn_period=spawn_period)
    if boxes is not None and seconds is None:
        count, end = float(boxes), sorting_time_limit(boxes, task)
        time_limit = end
    elif seconds is not None and boxes is None:
        count, end = float("inf"), seconds
        time_limit = end + 10.0
    else:
        raise ValueError(f"boxes={boxes}, seconds={seconds}: give one of the two")
    env = ColorSort(robots="IRB140", config=replace(task, time_limit=time_limit), has_offscreen_renderer=True,
                    use_camera_obs=False, ignore_done=True, seed=seed)
    obs = env.reset()
    expert = make_expert(env, config)
    assert isinstance(expert, TrackingExpert)
    expert.reset(obs)
    tally, before, started = Tally(), None, False
    references: list[np.ndarray] = []
    phases: list[str] = []
    while len(env.events) < count and env.cur_time < end:
        action = expert.act(obs)
        phase = expert.phase
        assert expert.motion is not None
        references.append(expert.motion.sample(expert.time)[0])  # the reference this action was led from
        phases.append(phase.value)
        if phase is TrackingPhase.INTERCEPT and before is not TrackingPhase.INTERCEPT:
            assert isinstance(expert.motion.trajectory, JointTrajectory)
            tally.waited += waiting_time(expert.motion.trajectory, expert.limits)
        before = phase
        started = started or phase is TrackingPhase.INTERCEPT  # the start-up move from home is no cycle's
        if started:
            tally.phases[phase.value] = tally.phases.get(phase.value, 0.0) + env.control_timestep
        obs, *_ = env.step(action)
    for e in env.events:
        if e.outcome is Outcome.PLACED and e.bin is not None:
            tally.bins[e.bin] = tally.bins.get(e.bin, 0) + 1
    tally.placed = sum(tally.bins.values())
    tally.peaks = commanded_peaks(np.array(references), phases, env.control_timestep)
    env.close()
    return tally


if __name__ == "__main__":
    with recorded(__file__):
        main()
