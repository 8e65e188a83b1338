"""The tracking expert: it picks boxes from a belt that never stops (conveyor tracking).

When the ray fires it takes one photo, whatever it is doing; the box's pose then follows from the
photo and the belt's encoder alone: ``x = x_photo - (travel - travel_photo)``, y and yaw as seen
(the encoder's speed, travel per control period, predicts ahead). For each box it can meet, it
plans an interception: where and when the cup is over the box moving with it (ruckig plans to a
target velocity as well as a position) clear of the tallest box the cell accepts, then comes down
onto it guarded, moving with it, until the vacuum switch reports a seal (the touch-off, ``touch.py``),
and lifts it (dense IK paths at the belt's velocity), and carries it off from partway up the lift
(``track_carry_at``) to sort it as the stopping-belt expert does. Each leg starts where and when the one
before ends. A box it can no longer meet within the arm's reach before the belt's end it lets go: it rides off the end
(``rejected`` if it has no bin, ``dropped`` otherwise); ``let_go`` counts them.

Phases: ``MOVE_TO_WAIT`` (just upstream of the reach window), ``WAIT_FOR_BOX``,
``INTERCEPT``, ``TRACK`` (suction on, down until the seal, moving with the belt; none before the floor
or the end of the reach: the box is let go, the reason kept in ``misses``), ``LIFT`` (up, moving with the
belt), ``MOVE_OVER_BIN``, ``RELEASE``; after a release it goes straight to the next box it can meet, and
when none can be met yet it waits over the bin (``wait_over_bin``: the way to the next box is then one
motion from rest to the box) or at the wait pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from functools import cached_property

import numpy as np

from colorsort.cell.privileged import NOTHING_HELD, TakeOver
from colorsort.config import BIN_COLORS
from colorsort.expert.base import Cycle, Expert, Handler, ray_blocked, sealed
from colorsort.expert.config import ExpertConfig
from colorsort.expert.perception import wrap_quarter_turn
from colorsort.expert.planning import DensePath, JointTrajectory, UnreachableWaypoint, Waypoint, plan_motion
from colorsort.expert.touch import straight_path


class TrackingPhase(Enum):
    """The tracking expert's phases."""

    MOVE_TO_WAIT = "move to wait pose"
    WAIT_FOR_BOX = "wait for box"
    INTERCEPT = "intercept box"  # over the moving box, moving with it
    TRACK = "track box"  # down onto the moving box until it seals, moving with it
    LIFT = "lift box"  # up off the belt, moving with it
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


def smoothstep(u: float) -> float:
    """0 -> 1 with zero slope at both ends, u in [0, 1]."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


def lift_heights(config: ExpertConfig, dt: float) -> np.ndarray:
    """Cup heights [m] over where it touched, one per control period ``dt`` [s] from the seal: on down ``press``
    at ``touch_speed``, held ``track_hold_time``, then up until the box's bottom is ``track_lift_gap`` over the
    belt (the touch was on its top: the cup rises that gap over it)."""
    t1 = config.press / config.touch_speed
    t2 = t1 + config.track_hold_time
    t3 = t2 + config.track_lift_time
    tau = dt * np.arange(int(np.ceil(t3 / dt - 1e-9)) + 1)
    down = -config.touch_speed * np.minimum(tau, t1)
    rise = np.array([smoothstep(u) for u in (tau - t2) / (t3 - t2)])
    up = -config.press + (config.track_lift_gap + config.press) * rise
    return np.where(tau <= t2, down, up)


def carry_height(config: ExpertConfig) -> float:
    """[m] the cup over where it touched when the carry to the bin takes over: ``track_carry_at`` of the way up
    the lift, on ``lift_heights``' curve."""
    return -config.press + (config.track_lift_gap + config.press) * smoothstep(config.track_carry_at)


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
                TrackingPhase.LIFT: self._lift,
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
        return (self.window[1] + 0.01, L.belt_y, self.descent.start)

    def slot_cost(self, point: tuple[float, float], q: np.ndarray) -> float:
        """[s] the least time the arm could take between the wait pose, where boxes are met, and the release
        point ``q`` [rad], its slowest joint at its datasheet speed: the quickest slots first, which shortens
        both the carry and the way back to the next box."""
        return float(np.max(np.abs(q - self.q_wait) / np.asarray(self.calibration.max_velocity, float)))

    @cached_property
    def window(self) -> tuple[float, float]:
        """The stretch of the belt centre line [m] where the cup reaches the touch-off's start and floor and the
        height it lifts the tallest box to, 2 cm inside its ends: grown both ways from the point nearest the home
        pose's cup, each IK
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
        """Joint angles [rad] at the touch-off's start over ``x`` [m] on the belt centre line, if the cup also
        reaches its floor and the height it lifts the tallest box to there; else None."""
        L, cfg, d = self.layout, self.config, self.descent
        try:
            for z in (L.belt_top_z + L.tallest_box + cfg.track_lift_gap, d.floor, d.start):
                q = self.ik.solve(Waypoint("reach", (x, L.belt_y, z), self.cup_yaw), q)
        except UnreachableWaypoint:
            return None
        return q

    @cached_property
    def carry_from(self) -> float:
        """[s] after the seal: where the carry to the bin takes over, ``track_carry_at`` of the way up the lift."""
        c = self.config
        return c.press / c.touch_speed + c.track_hold_time + c.track_carry_at * c.track_lift_time

    def reset(self, obs: dict | None = None) -> None:
        super().reset(obs)
        self._track_plan: DensePath | None = None
        self._leave_at = 0.0  # [s] expert time: the carry takes over from the lift
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
        """(approach, descent) for box ``s``, or None when it can no longer be met within reach.

        The approach (ruckig, from the reference now) ends over the box at the touch-off's start, moving with it
        and on its way down; if the box is not yet within reach by then, it ends as the box enters the reach
        window. The descent follows it down to the floor or to where the lift still ends within the window,
        whichever comes first, and must reach the top of the tallest box the cell accepts.
        """
        cfg, v, now = self.config, self.belt_speed, self.time
        x_end = self.window[0] + v * self.carry_from  # the box's x [m] at the seal, at the latest
        x_lo, x_hi = x_end + v * cfg.touch_clearance / cfg.touch_speed, self.window[1]
        start = self._current_state()
        t_meet, x = now, None
        for _ in range(12):  # fixed point: where the box is when the motion that meets it there ends
            x_then = self._box_x(s, t_meet)
            if x_then < x_lo:
                return None
            entering = x_then > x_hi  # not in reach yet: meet it as it enters
            x = x_hi if entering else x_then
            if x < x_lo:  # the window is too short to come down onto the tallest box
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
                duration = min(self.descent.duration(cfg.touch_speed), (x - x_end) / v)
                try:
                    return approach, straight_path(self.ik, (x, s.y, self.descent.start), self._touch_velocity(v),
                                                   s.yaw, duration, self.dt, q_over)
                except UnreachableWaypoint:
                    return None
            t_meet = arrive
        return None

    def _touch_velocity(self, v: float) -> tuple[float, float, float]:
        """[m/s] the cup's while it comes down onto a box riding the belt at ``v`` [m/s]."""
        return (-v, 0.0, -self.config.touch_speed)

    def _over_box(self, s: Sighting, x: float, v: float) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles [rad] with the cup at the touch-off's start over the box at ``x`` [m], and joint velocities
        [rad/s] that move it on down with the belt at ``v`` [m/s] (from IK 1 cm along that way)."""
        z = self.descent.start
        velocity = np.array(self._touch_velocity(v))
        speed = float(np.linalg.norm(velocity))
        q = self.ik.solve(Waypoint("over moving box", (x, s.y, z), s.yaw), self.q_wait)
        ahead = np.array([x, s.y, z]) + 0.01 * velocity / speed
        q_next = self.ik.solve(Waypoint("over moving box", tuple(ahead), s.yaw), q)
        return q, (q_next - q) * (speed / 0.01)

    def _lift_path(self, s: Sighting, v: float) -> DensePath:
        """From the reference now, where the cup touched, up off the belt (``lift_heights``), moving with the box
        at ``v`` [m/s]."""
        q0 = self._current_state()[0]
        p0 = self.ik.cup_pose(q0)[0]
        path, q = [q0], q0
        for k, dz in enumerate(lift_heights(self.config, self.dt)[1:], start=1):
            q = self.ik.solve(Waypoint("lifting the box", (p0[0] - v * k * self.dt, p0[1], p0[2] + dz), s.yaw), q)
            path.append(q)
        return DensePath(np.array(path), self.dt)

    # 3. meet the box, then come down onto it until it seals, and lift it, moving with it
    def _intercept(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self._track_plan is not None, "INTERCEPT follows a planned interception"
        if self.motion.done(self.time + self.dt):  # it ends before the next command: the descent follows on at once
            self.suction = True
            self._follow(self._track_plan, np.inf, started=self.motion.end)
            self._enter(TrackingPhase.TRACK)

    def _track(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self.current is not None, "TRACK follows an interception"
        if sealed(obs):
            self._follow(self._lift_path(self.current, self.belt_speed), np.inf)
            self._leave_at = self.time + self.carry_from
            self._enter(TrackingPhase.LIFT)
        elif self.motion.done(self.time):
            self._miss(f"no seal down to {self.ik.cup_pose(self._current_state()[0])[0][2]:.3f} m "
                       "before the floor or the end of the reach")

    def _lift(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self.current is not None, "LIFT follows a seal"
        path = self.motion.trajectory
        assert isinstance(path, DensePath), "LIFT follows the box along a dense path"
        if self.time + self.dt < self._leave_at:  # the next command is still the lift's
            return
        if sealed(obs):  # 5, 6: on to the bin, from the moving state, the box still rising
            color = self.current.cycle.target_bin
            assert color is not None, "only a box with a bin is met"
            at = self._leave_at - self.motion.started
            trajectory = plan_motion(path.sample(at)[0], self._next_drop(color), self.limits,
                                     start_velocity=path.slope(at))
            self._follow(trajectory, self.config.drop_tolerance, started=self._leave_at)
            self._enter(TrackingPhase.MOVE_OVER_BIN)
        else:
            self._miss("the seal was lost in the lift")

    def _miss(self, why: str) -> None:
        """No box on the cup: suction off, the box rides on, back to the wait pose."""
        assert self.current is not None, "a box was being picked"
        self.misses.append((self.time, why))
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
