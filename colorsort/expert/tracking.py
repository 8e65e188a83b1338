"""The tracking expert: it picks boxes from a belt that never stops (conveyor tracking).

When the ray fires it takes one photo, whatever it is doing; the box's pose then follows from the
photo and the belt's encoder alone: ``x = x_photo - (travel - travel_photo)``, y and yaw as seen
(the encoder's speed, travel per control period, predicts ahead). For each box it can meet, it
plans an interception: where and when the cup is over the box moving with it (ruckig plans to a
target velocity as well as a position), then follows the box down while it seals and lifts (a dense
IK path at the belt's velocity), and carries it off from partway up the lift (``track_carry_at``) to
sort it as the stopping-belt expert does. Each leg starts where and when the one before ends. A box it can no
longer meet within the arm's reach before the belt's end it lets go: it rides off the end
(``rejected`` if it has no bin, ``dropped`` otherwise); ``let_go`` counts them.

Phases: ``MOVE_TO_WAIT`` (just upstream of the reach window), ``WAIT_FOR_BOX``,
``INTERCEPT``, ``TRACK`` (suction on, down, seal, up, moving with the belt), ``MOVE_OVER_BIN``,
``RELEASE``; after a release it goes straight to the next box it can meet, and when none can be met yet
it waits over the bin (``wait_over_bin``: the way to the next box is then one motion from rest to the box)
or at the wait pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from functools import cached_property

import numpy as np

from colorsort.cell.privileged import NOTHING_HELD, TakeOver
from colorsort.config import BIN_COLORS, CellLayout
from colorsort.expert.base import Cycle, Expert, Handler, ray_blocked, sealed
from colorsort.expert.config import ExpertConfig
from colorsort.expert.perception import wrap_quarter_turn
from colorsort.expert.planning import JointTrajectory, UnreachableWaypoint, Waypoint, plan_motion


class TrackingPhase(Enum):
    """The tracking expert's phases."""

    MOVE_TO_WAIT = "move to wait pose"
    WAIT_FOR_BOX = "wait for box"
    INTERCEPT = "intercept box"  # over the moving box, moving with it
    TRACK = "track box"  # down onto the moving box, seal and lift, moving with it
    MOVE_OVER_BIN = "move over bin"
    RELEASE = "release"
    CLEAR = "lift clear"  # a take-over's first motion (``Expert.take_over``)


@dataclass
class Sighting:
    """A box the camera saw when it crossed the ray."""

    cycle: Cycle
    x: float  # [m] its top face's centre when the photo was taken
    y: float  # [m]
    yaw: float  # [rad] the cup's yaw that fits it
    travel: float  # [m] the belt encoder at the photo


class DensePath:
    """A joint path sampled every control period, with the interface of ``JointTrajectory``.

    Args:
        q: joint positions [rad], (K + 1, n), one per period ``dt`` [s] from time 0.
    """

    def __init__(self, q: np.ndarray, dt: float):
        self.q, self.dt = q, dt
        self.qd = np.gradient(q, dt, axis=0)  # (K + 1, n) [rad/s]
        self.goal = q[-1]

    @property
    def duration(self) -> float:
        return self.dt * (len(self.q) - 1)

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [rad] and velocity [rad/s] at ``t`` [s] (linear between samples, clamped to the ends)."""
        u = min(max(t / self.dt, 0.0), len(self.q) - 1.0)
        k = min(int(u), len(self.q) - 2)
        w = u - k
        q = (1 - w) * self.q[k] + w * self.q[k + 1]
        qd = (1 - w) * self.qd[k] + w * self.qd[k + 1]
        return q, qd, np.zeros_like(q)

    def slope(self, t: float) -> np.ndarray:
        """[rad/s] the velocity of the straight segment between samples that ``sample`` interpolates at ``t`` [s]."""
        k = min(max(int(t / self.dt), 0), len(self.q) - 2)
        return (self.q[k + 1] - self.q[k]) / self.dt


def smoothstep(u: float) -> float:
    """0 -> 1 with zero slope at both ends, u in [0, 1]."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


def track_heights(config: ExpertConfig, layout: CellLayout, dt: float) -> np.ndarray:
    """Cup heights [m], one per control period ``dt`` [s] from the meeting, while following a box: from
    ``approach_gap`` over its top down onto it (``press`` into it), held while the seal forms, then up
    until the box's bottom is ``track_lift_gap`` over the belt."""
    top = layout.belt_top_z + layout.box_size
    z_over, z_on, z_up = top + config.approach_gap, top - config.press, top + config.track_lift_gap
    t1 = config.track_descend_time
    t2 = t1 + config.track_hold_time
    t3 = t2 + config.track_lift_time
    tau = dt * np.arange(int(np.ceil(t3 / dt)) + 1)
    down = z_over + (z_on - z_over) * np.array([smoothstep(u) for u in tau / t1])
    up = z_on + (z_up - z_on) * np.array([smoothstep(u) for u in (tau - t2) / (t3 - t2)])
    return np.where(tau <= t1, down, up)


def carry_height(config: ExpertConfig, layout: CellLayout) -> float:
    """[m] the cup's height where the carry to the bin takes over: ``track_carry_at`` of the way up the lift, on
    ``track_heights``' curve."""
    top = layout.belt_top_z + layout.box_size
    return top - config.press + (config.track_lift_gap + config.press) * smoothstep(config.track_carry_at)


class TrackingExpert(Expert):
    """Sorts boxes from a belt that never stops; see the module docstring. Args: as ``base.Expert``
    (``make_expert`` returns one for a tracking task).

    Attributes:
        let_go: boxes of a bin colour it could not meet in time and let ride off the belt.
        window: (lowest, highest) x [m] over the belt centre line where the cup reaches a box.
    """

    START = TrackingPhase.MOVE_TO_WAIT
    CLEAR = TrackingPhase.CLEAR
    OVER_BIN = TrackingPhase.MOVE_OVER_BIN
    current: Sighting | None  # the box being picked (or, after a take-over, carried)

    def handlers(self) -> dict[Enum, Handler]:
        return {TrackingPhase.MOVE_TO_WAIT: self._move_to_wait, TrackingPhase.WAIT_FOR_BOX: self._wait_for_box,
                TrackingPhase.INTERCEPT: self._intercept, TrackingPhase.TRACK: self._track,
                TrackingPhase.MOVE_OVER_BIN: self._move_over_bin, TrackingPhase.RELEASE: self._release,
                TrackingPhase.CLEAR: self._clear}

    def take_over(self, obs: dict, view: TakeOver = NOTHING_HELD) -> None:
        """``Expert.take_over``; the boxes past the ray, which it would have known from its photos, join the queue
        as if seen now (their pose from ``view``), to be met where they still can be."""
        super().take_over(obs, view)
        travel = float(np.asarray(obs["belt_travel"]).ravel()[0])
        if self.carrying is not None:  # no box to meet: the held one goes to its bin after the lift
            self.current = Sighting(self.carrying, float("nan"), float("nan"), self.cup_yaw, travel)
        for box in view.past_the_ray:
            cycle = Cycle(box.color, self.time, target_bin=box.color if box.color in BIN_COLORS else None)
            self.cycles.append(cycle)
            if cycle.target_bin is None:
                cycle.done_at = self.time  # it rides on, as any box without a bin
                continue
            turn = wrap_quarter_turn(box.yaw) if self.config.turn_to_box else 0.0
            self.queue.append(Sighting(cycle, box.x, box.y, self.cup_yaw + turn, travel))

    def drop_seed(self) -> np.ndarray:
        """Home: from the wait pose over the far end of the belt, IK for the far bins lands in other branches."""
        return self.home

    def wait_point(self) -> tuple[float, float, float]:
        """Over the belt centre line 1 cm upstream of the reach window (where the arm still reaches), at the
        height the cup meets a box: a box is met as it enters the window, so the interception starts from
        rest behind it and runs the way the belt does instead of turning back to match its speed."""
        L = self.layout
        return (self.window[1] + 0.01, L.belt_y, L.belt_top_z + L.box_size + self.config.approach_gap)

    def slot_cost(self, point: tuple[float, float], q: np.ndarray) -> float:
        """[s] the least time the arm could take between the wait pose, where boxes are met, and the release
        point ``q`` [rad], its slowest joint at its datasheet speed: the quickest slots first, which shortens
        both the carry and the way back to the next box."""
        return float(np.max(np.abs(q - self.q_wait) / np.asarray(self.calibration.max_velocity, float)))

    @cached_property
    def window(self) -> tuple[float, float]:
        """The stretch of the belt centre line [m] where the cup reaches over, onto and the lift height of a
        box, 2 cm inside its ends: grown both ways from the point nearest the home pose's cup, each IK
        warm-started from its neighbour's."""
        L = self.layout
        near = float(np.clip(self.ik.cup_pose(self.home)[0][0], L.belt_end_x + L.box_size, L.belt_start_x))
        for start in near + np.array([0.0, -0.05, 0.05, -0.1, 0.1]):
            q0 = self._reaches(start, self.home)
            if q0 is not None:
                break
        else:
            raise UnreachableWaypoint(f"The arm reaches the belt nowhere near x = {near:.2f} m to pick moving boxes")
        ends = []
        for step in (0.02, -0.02):
            x, q = start, q0
            while L.belt_end_x < x + step < L.belt_start_x:
                q_next = self._reaches(x + step, q)
                if q_next is None:
                    break
                x, q = x + step, q_next
            ends.append(x)
        hi, lo = ends
        return max(lo + 0.02, L.belt_end_x + L.box_size), hi - 0.02

    def _reaches(self, x: float, q: np.ndarray) -> np.ndarray | None:
        """Joint angles [rad] over a box at ``x`` [m] on the belt centre line, if the cup also reaches onto it
        and the height it lifts it to there; else None."""
        L, cfg = self.layout, self.config
        top = L.belt_top_z + L.box_size
        try:
            for z in (top + cfg.track_lift_gap, top - cfg.press, top + cfg.approach_gap):
                q = self.ik.solve(Waypoint("reach", (x, L.belt_y, z), self.cup_yaw), q)
        except UnreachableWaypoint:
            return None
        return q

    @cached_property
    def carry_from(self) -> float:
        """[s] into a track path: where the carry to the bin takes over, ``track_carry_at`` of the way up."""
        c = self.config
        return c.track_descend_time + c.track_hold_time + c.track_carry_at * c.track_lift_time

    def reset(self, obs: dict | None = None) -> None:
        super().reset(obs)
        self._track_plan: DensePath | None = None
        self.queue: list[Sighting] = []
        self.let_go = 0
        self.travel = 0.0  # [m] the belt encoder
        self.belt_speed = 0.0  # [m/s] from the encoder
        self._last_travel: float | None = None
        self._ray_was_blocked = False
        self.current: Sighting | None = None  # the box being picked

    def act(self, obs: dict) -> np.ndarray:
        travel = float(np.asarray(obs["belt_travel"]).ravel()[0])
        if self._last_travel is not None:
            self.belt_speed = (travel - self._last_travel) / self.dt
        self.travel, self._last_travel = travel, travel
        blocked = ray_blocked(obs)
        if blocked and not self._ray_was_blocked:
            self._sight(obs)
        self._ray_was_blocked = blocked
        return super().act(obs)

    def _sight(self, obs: dict) -> None:
        """One photo as the ray fires: a box of a bin colour joins the queue; any other rides on."""
        t, cycle = self._look(obs)
        if t is not None and cycle.target_bin is not None:
            x, y = float(t.center[0]), float(t.center[1])
            self.queue.append(Sighting(cycle, x, y, self.cup_yaw + self.turn(t), self.travel))
        else:
            cycle.done_at = self.time  # let through: nothing to do

    @property
    def seen_color(self) -> str | None:
        return self.current.cycle.seen_color if self.current is not None else None

    def _current_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The commanded reference now: position [rad], velocity [rad/s], acceleration [rad/s^2]."""
        if self.motion is None:
            return self._q_cmd, np.zeros_like(self._q_cmd), np.zeros_like(self._q_cmd)
        return self.motion.sample(self.time)

    def _box_x(self, s: Sighting, t: float) -> float:
        """[m] the box's predicted x at expert time ``t``, from the photo and the encoder."""
        return s.x - (self.travel - s.travel) - self.belt_speed * (t - self.time)

    # 1, 2. to the wait pose and wait, meeting the next box as soon as one can be met
    def _move_to_wait(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if not self._intercept_next() and self._arrived(q):
            self._enter(TrackingPhase.WAIT_FOR_BOX)

    def _wait_for_box(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        self._intercept_next()

    def _intercept_next(self) -> bool:
        """Start meeting the first queued box that can still be met; let go those that cannot."""
        while self.queue and self.belt_speed > 0.0:
            s = self.queue[0]
            plan = self._plan_intercept(s)
            if plan is not None:
                self.queue.pop(0)
                self.current = s
                approach, self._track_plan = plan
                self._follow(approach, np.inf)
                self._enter(TrackingPhase.INTERCEPT)
                return True
            self.queue.pop(0)
            s.cycle.target_bin, s.cycle.done_at = None, self.time
            self.let_go += 1
        return False

    def _plan_intercept(self, s: Sighting) -> tuple[JointTrajectory, DensePath] | None:
        """(approach, track) for box ``s``, or None when it can no longer be met within reach.

        The approach (ruckig, from the reference now) ends over the box, ``approach_gap`` above its
        top, moving with it; if the box is not yet within reach by then, it ends as the box enters
        the reach window. The track follows it down, holds while the seal forms, and lifts it, at the
        belt's velocity, and must end before the window does.
        """
        cfg, v, now = self.config, self.belt_speed, self.time
        track_time = cfg.track_descend_time + cfg.track_hold_time + cfg.track_lift_time
        x_lo, x_hi = self.window[0] + v * track_time, self.window[1]
        start = self._current_state()
        t_meet, x = now, None
        for _ in range(12):  # fixed point: where the box is when the motion that meets it there ends
            x_then = self._box_x(s, t_meet)
            if x_then < x_lo:
                return None
            entering = x_then > x_hi  # not in reach yet: meet it as it enters
            x = x_hi if entering else x_then
            if x < x_lo:  # the window is too short to follow it down and up
                return None
            wait = (self._box_x(s, now) - x_hi) / v if entering else None
            try:
                q_over, qd_over = self._over_box(s, x, v)
            except UnreachableWaypoint:  # off the centre line the window is shorter: meet it further on
                x_hi, t_meet = x - 0.02, now + (self._box_x(s, now) - (x - 0.02)) / v
                continue
            approach = plan_motion(start[0], q_over, self.limits, start_velocity=start[1],
                                   start_acceleration=start[2], goal_velocity=qd_over, minimum_duration=wait)
            arrive = now + approach.duration
            if abs(self._box_x(s, arrive) - x) < 0.002:  # [m]
                try:
                    return approach, self._track_path(s, x, v, q_over)
                except UnreachableWaypoint:
                    return None
            t_meet = arrive
        return None

    def _over_box(self, s: Sighting, x: float, v: float) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles [rad] with the cup 4 cm over the box at ``x`` [m], and joint velocities [rad/s]
        that move it along with the belt at ``v`` [m/s] (from IK 1 cm downstream)."""
        z = self.layout.belt_top_z + self.layout.box_size + self.config.approach_gap
        q = self.ik.solve(Waypoint("over moving box", (x, s.y, z), s.yaw), self.q_wait)
        q_next = self.ik.solve(Waypoint("over moving box", (x - 0.01, s.y, z), s.yaw), q)
        return q, (q_next - q) * (v / 0.01)

    def _track_path(self, s: Sighting, x0: float, v: float, q0: np.ndarray) -> DensePath:
        """Down onto the box, hold, and up off the belt (``track_heights``), moving with it from ``x0`` [m]
        at ``v`` [m/s]."""
        path, q = [q0], q0
        for k, z in enumerate(track_heights(self.config, self.layout, self.dt)[1:], start=1):
            q = self.ik.solve(Waypoint("tracking the box", (x0 - v * k * self.dt, s.y, z), s.yaw), q)
            path.append(q)
        return DensePath(np.array(path), self.dt)

    # 3. meet the box, then follow it down, seal and lift
    def _intercept(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self._track_plan is not None, "INTERCEPT follows a planned interception"
        if self.motion.done(self.time + self.dt):  # it ends before the next command: the track follows on at once
            self.suction = True
            self._follow(self._track_plan, np.inf, started=self.motion.end)
            self._enter(TrackingPhase.TRACK)

    def _track(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self.current is not None, "TRACK follows an interception"
        path = self.motion.trajectory
        assert isinstance(path, DensePath), "TRACK follows the box along a dense path"
        leave_at = self.motion.started + self.carry_from  # [s] expert time
        if self.time + self.dt < leave_at:  # the next command is still the track's
            return
        if sealed(obs):  # 5, 6: on to the bin, from the moving state, the box still rising
            color = self.current.cycle.target_bin
            assert color is not None, "only a box with a bin is met"
            q, _, _ = path.sample(self.carry_from)
            trajectory = plan_motion(q, self._next_drop(color), self.limits, start_velocity=path.slope(self.carry_from))
            self._follow(trajectory, self.config.drop_tolerance, started=leave_at)
            self._enter(TrackingPhase.MOVE_OVER_BIN)
        else:  # no seal: the box rides on
            self.suction = False
            self.current.cycle.target_bin, self.current.cycle.done_at = None, self.time
            self.current = None
            self.let_go += 1
            self._start_from_here(self.q_wait, self.config.wait_tolerance)
            self._enter(TrackingPhase.MOVE_TO_WAIT)

    def _move_over_bin(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            self.suction = False
            if self.config.release_time > 0.0:
                self._enter(TrackingPhase.RELEASE)
            else:  # the seal breaks in the coming physics step: the cup leaves at once, the box falls free
                self._leave_bin(goal)

    def _release(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._released(obs):
            self._leave_bin(goal)

    def _leave_bin(self, goal: np.ndarray) -> None:
        assert self.current is not None, "a box was carried to the bin"
        self.current.cycle.done_at = self.time
        self.current = None
        if self._intercept_next():  # straight to the next box when one can be met
            return
        if self.config.wait_over_bin:
            self._enter(TrackingPhase.WAIT_FOR_BOX)
        else:
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(TrackingPhase.MOVE_TO_WAIT)

    def _start_from_here(self, goal: np.ndarray, tolerance: float) -> None:
        ref, vel, acc = self._current_state()
        trajectory = plan_motion(ref, goal, self.limits, start_velocity=vel,
                                 start_acceleration=acc)
        self._follow(trajectory, tolerance)
