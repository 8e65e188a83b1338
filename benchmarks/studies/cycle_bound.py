"""The shortest cycle of a pick on the tracking belt, from the arm's limits and the cell's geometry.

For a 10 cm box at ``x`` on the belt's centre line and a bin, a cycle is six legs: down onto the box
from where the expert's touch-off starts (over the tallest box the cell accepts), the seal (one control
period: the vacuum switch reports it at the next step), the lift (as high as the expert lifts before its
carry takes over: ``tracking.carry_height``), the carry to the bin's first
drop slot, the release (one control period), and the way back over the next box at the same ``x``.
Each motion leg takes, between its two joint configurations (mink IK of the cup poses):

- ``speed`` (the bound): the largest joint displacement over that joint's datasheet speed, as if
  the arm could accelerate at will. No motion of the arm between the two poses is shorter, so no
  expert's cycle can be: this is the physical bound.
- ``stops`` (the bound with acceleration): the cup is at rest on the box (a standing box) and over
  the bin at the release, and moves freely through the other two points: each leg is the least time
  to start from or come to rest there, per joint, at the datasheet speeds and the expert's
  accelerations (``expert.limits``; on the tracking belt each joint's own), jerk unlimited
  (``time_to_stop``). A motion that stops where it stops can do no better.
- ``jerk`` (the bound at the expert's planner's limits): ``stops`` with the jerk limited too, at the
  expert's jerk (``time_from_rest``): the tightest of the three bounds, and the one that prices what
  the expert's jerk costs on the short legs (down onto the box, the lift). The tracking expert follows
  the box down and up along a dense path its planner does not time; ``commanded_peaks`` measures what
  it commands, phase by phase, against its limits.
- ``ruckig`` (a reference): a time-optimal ruckig motion from rest to rest at the datasheet speeds
  and the expert's acceleration and jerk. An expert that blends legs (it meets a moving box already
  moving and carries from the moving state) can beat it.

``shortest_cycle`` takes the best ``x`` in the arm's reach window. What the expert's guarded descent costs beyond
the arm's limits is ``touch_cost``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.errors import ConfigError
from colorsort.expert.planning import JointLimits, JointTrajectory, Waypoint, plan_motion
from colorsort.expert.tracking import TrackingExpert, carry_height

LEGS = ("down onto the box", "seal", "lift", "carry to the bin", "release", "back over the next box")
MODES = ("speed", "stops", "jerk", "ruckig")


def time_to_stop(d: np.ndarray, vmax: np.ndarray, a: np.ndarray | float) -> np.ndarray:
    """[s] per joint: the least time to move ``d`` [rad] and be at rest at the end (or to start from rest),
    the other end's velocity free, at speeds up to ``vmax`` [rad/s] and accelerations up to ``a`` [rad/s^2]
    (per joint or every joint)."""
    d = np.abs(d)
    cruise = d >= vmax**2 / (2 * a)
    return np.where(cruise, d / vmax + vmax / (2 * a), np.sqrt(2 * d / a))


def distance_from_rest(t: float, vmax: float, a: float, j: float) -> float:
    """[rad] the farthest one joint gets in ``t`` [s] from rest (no speed, no acceleration) at speeds up to
    ``vmax`` [rad/s], accelerations up to ``a`` [rad/s^2] and jerk up to ``j`` [rad/s^3]: acceleration
    raised at full jerk, held, then lowered at full jerk so that the speed levels off at ``vmax``."""
    peak = min(a, float(np.sqrt(vmax * j)))  # a short climb to vmax never reaches the acceleration limit
    ramp, hold = peak / j, max(vmax - peak**2 / j, 0.0) / peak  # [s] each jerk phase, the constant-acceleration one
    if t <= ramp:
        return j * t**3 / 6
    p, v = j * ramp**3 / 6, j * ramp**2 / 2
    if t <= ramp + hold:
        return p + v * (t - ramp) + peak * (t - ramp) ** 2 / 2
    p, v = p + v * hold + peak * hold**2 / 2, v + peak * hold
    tau = min(t - ramp - hold, ramp)
    p += v * tau + peak * tau**2 / 2 - j * tau**3 / 6
    return p + vmax * max(t - 2 * ramp - hold, 0.0)


def time_from_rest(d: np.ndarray, vmax: np.ndarray, a: np.ndarray | float, j: np.ndarray | float) -> np.ndarray:
    """[s] per joint: ``time_to_stop`` with the jerk limited to ``j`` [rad/s^3] too (from rest, or to rest:
    the same by time reversal), the inverse of ``distance_from_rest`` to 1 microsecond; ``a`` and ``j`` per
    joint or every joint."""
    times = []
    d = np.abs(np.asarray(d, float))
    for dist, v, aj, jj in zip(d, vmax, np.broadcast_to(a, d.shape), np.broadcast_to(j, d.shape), strict=True):
        lo, hi = 0.0, 1.0
        while distance_from_rest(hi, v, aj, jj) < dist:
            hi *= 2
        while hi - lo > 1e-6:
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if distance_from_rest(mid, v, aj, jj) < dist else (lo, mid)
        times.append(hi)
    return np.asarray(times)


@dataclass(frozen=True)
class Cycle:
    """One reference cycle: where the box is met [m], the bin, and each leg's duration [s] (``LEGS``)."""

    x: float
    bin: str
    legs: dict[str, float]

    @property
    def total(self) -> float:
        """[s]"""
        return sum(self.legs.values())


def cycle_at(expert: TrackingExpert, x: float, color: str, mode: str = "speed") -> Cycle:
    """The cycle for a box at ``x`` [m] on the belt's centre line going to the ``color`` bin (``MODES``)."""
    if mode not in MODES:
        raise ConfigError(f"mode={mode!r}: valid modes are {list(MODES)}")
    L, cfg = expert.layout, expert.config
    top = L.belt_top_z + L.box_size
    over, on, lift = (Waypoint(name, (x, L.belt_y, z), expert.cup_yaw) for name, z in (
        ("over the box", expert.descent.start), ("on the box", top), ("lifted", top + carry_height(cfg))))
    q_over = expert.ik.solve(over, expert.q_wait)
    q_on = expert.ik.solve(on, q_over)
    q_lift = expert.ik.solve(lift, q_on)
    q_drop = expert.q_drop[color][0]

    vmax, lim = np.asarray(expert.calibration.max_velocity, float), expert.limits

    def move(a: np.ndarray, b: np.ndarray) -> float:
        if mode == "speed":
            return float(np.max(np.abs(b - a) / vmax))
        if mode == "stops":
            return float(np.max(time_to_stop(b - a, lim.velocity, lim.acceleration)))
        if mode == "jerk":
            return float(np.max(time_from_rest(b - a, lim.velocity, lim.acceleration, lim.jerk)))
        return plan_motion(a, b, lim).duration

    legs = dict(zip(LEGS, (move(q_over, q_on), expert.dt, move(q_on, q_lift), move(q_lift, q_drop), expert.dt,
                           move(q_drop, q_over)), strict=True))
    return Cycle(x, color, legs)


def touch_cost(expert: TrackingExpert, cycle: Cycle) -> float:
    """[s] how much longer the expert's guarded descent onto a 10 cm box takes (at ``touch_speed``) than ``cycle``'s
    leg down onto it: the price of not knowing the box's height."""
    L = expert.layout
    guarded = (expert.descent.start - L.belt_top_z - L.box_size) / expert.config.touch_speed
    return max(guarded - cycle.legs["down onto the box"], 0.0)


def shortest_cycle(expert: TrackingExpert, color: str, mode: str = "speed", step: float = 0.01) -> Cycle:
    """The shortest cycle for the ``color`` bin over the reach window, the meeting point in ``step`` [m]."""
    lo, hi = expert.window
    return min((cycle_at(expert, float(x), color, mode) for x in np.arange(lo, hi + 1e-9, step)),
               key=lambda c: c.total)


def commanded_peaks(q: np.ndarray, phases: list[str], dt: float) -> dict[str, np.ndarray]:
    """Per phase, each joint's largest acceleration [rad/s^2] (row 0) and jerk [rad/s^3] (row 1) an expert
    commanded, as its controller sees them: finite differences of the reference ``q`` (K, n), one row per
    control period ``dt`` [s], ``phases`` (K,) the phase of each row. A second difference counts for its middle
    row's phase, a third for its second row's."""
    acceleration = np.abs(np.diff(q, 2, axis=0)) / dt**2  # row k + 1
    jerk = np.abs(np.diff(q, 3, axis=0)) / dt**3  # rows k + 1 and k + 2
    out: dict[str, np.ndarray] = {}
    for k, phase in enumerate(phases[1:-1]):
        peak = np.stack([acceleration[k], jerk[k] if k < len(jerk) else np.zeros(q.shape[1])])
        out[phase] = np.maximum(out.get(phase, peak), peak)
    return out


def waiting_time(approach: JointTrajectory, limits: JointLimits) -> float:
    """[s] how much of a planned interception ``approach`` waits for the box to come within reach: its
    duration less that of the time-optimal plan between the same states (same ``limits``, no minimum
    duration)."""
    q0, qd0, qdd0 = approach.sample(0.0)
    q1, qd1, _ = approach.sample(approach.duration)
    fastest = plan_motion(q0, q1, limits, start_velocity=qd0, start_acceleration=qdd0,
                          goal_velocity=qd1)
    return max(approach.duration - fastest.duration, 0.0)
