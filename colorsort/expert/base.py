"""What every scripted expert shares: the cell as it knows it, a motion follower, the look, the drop slots.

An expert is a phase machine over the cell's sensors only (the ray, the colour camera, the arm's
joints, the vacuum switch, on a tracking belt the encoder): each subclass names its own phases
(an ``Enum``) and a handler per phase; ``act`` runs the current phase's handler, then samples the
motion being followed into joint targets. The stopping belt's expert is ``sorter.SortingExpert``,
the tracking belt's ``tracking.TrackingExpert``; ``factory.make_expert`` picks one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from functools import cached_property

import numpy as np

from colorsort.cell.privileged import NOTHING_HELD, TakeOver
from colorsort.config import BIN_COLORS
from colorsort.expert.calibration import Calibration
from colorsort.expert.config import ExpertConfig
from colorsort.expert.limits import torque_limited_accelerations
from colorsort.expert.perception import ColorSensor, Detection, bin_for
from colorsort.expert.planning import (
    CupIK,
    JointLimits,
    Trajectory,
    UnreachableWaypoint,
    Waypoint,
    plan_motion,
    site_yaw,
)
from colorsort.expert.touch import Descent

Handler = Callable[[dict, np.ndarray, np.ndarray], None]  # (observation, joints now [rad], motion goal [rad])


@dataclass
class Cycle:
    """One box handled by the expert: what it saw and when [s, sim time]."""

    seen_color: str
    detected_at: float
    done_at: float | None = None
    target_bin: str | None = None  # None: let through


@dataclass
class Motion:
    """A trajectory being followed since expert time ``started`` [s]."""

    trajectory: Trajectory
    started: float
    tolerance: float  # [rad] max joint error that counts as arrived

    @property
    def end(self) -> float:
        """[s] expert time at which its trajectory ends."""
        return self.started + self.trajectory.duration

    def done(self, now: float) -> bool:
        """Its time is up (whether or not the joints are there)."""
        return now - self.started >= self.trajectory.duration - 1e-9

    def arrived(self, q: np.ndarray, now: float) -> bool:
        """Its time is up and the joints ``q`` [rad] are within ``tolerance`` of its goal."""
        return (now - self.started >= self.trajectory.duration
                and float(np.max(np.abs(q - self.trajectory.goal))) < self.tolerance)

    def sample(self, now: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [rad], velocity [rad/s], acceleration [rad/s^2] at expert time ``now`` [s]."""
        return self.trajectory.sample(now - self.started)


def sealed(obs: dict) -> bool:
    """The cup's vacuum switch."""
    return float(obs["suction_sealed"]) > 0.5


def ray_blocked(obs: dict) -> bool:
    """The ray sensor sees a box."""
    return float(obs["box_detected"]) > 0.5


class Expert:
    """The machinery of a scripted expert; a subclass gives its phases and what it does in each.

    Args:
        calibration: the cell as the expert knows it (``Calibration.from_env``).
        sensor_image: the colour image for an observation (``calibration.sensor_source``).
        config: the expert's settings.

    Its motions keep to ``limits`` (``JointLimits``): the datasheet speeds, and the config's acceleration
    and jerk, or where the config leaves the acceleration to the arm each joint's own: its maker's figure,
    else what its motor's torque gives it (``limits.torque_limited_accelerations``).

    A subclass sets ``START`` (its first phase) and, where it picks a box that waits for it, ``APPROACH`` (the
    phase that moves to it), and implements ``handlers``, ``wait_point`` and ``drop_seed``; one that can take over
    a cell in any state (``take_over``) also sets ``CLEAR`` (handled by ``_clear``) and ``OVER_BIN``. Use:
    ``expert = make_expert(env)`` (``expert/factory.py``), ``expert.reset(obs)`` (or, in the middle of an episode,
    ``expert.take_over(obs, take_over_view(env.plant))``), then ``action = expert.act(obs)`` every step.
    """

    START: Enum
    APPROACH: Enum | None = None  # the phase in which the arm moves to a box that waits for it; None: no such phase
    CLEAR: Enum | None = None  # a take-over's straight lift; None: this expert starts only from its own reset
    OVER_BIN: Enum | None = None  # the phase that carries a box over a bin and releases it on arrival

    def __init__(self, calibration: Calibration, sensor_image: Callable[[dict], np.ndarray],
                 config: ExpertConfig = ExpertConfig()):
        self.calibration, self.config = calibration, config
        self.sensor_image = sensor_image
        self.layout = L = calibration.layout
        self.dt = calibration.control_period
        self.home = calibration.home
        self.ik = CupIK(calibration.kinematics, self.home)
        self.cup_yaw = site_yaw(self.ik.cup_pose(self.home)[1])  # a multiple of 90 deg: bins' axes
        self.sensor = ColorSensor(calibration.camera, L, config.perception)
        self.q_wait = self.ik.solve(Waypoint("wait", self.wait_point(), self.cup_yaw), self.home)
        self.q_drop = {color: self._drop_slots(color, k) for k, color in enumerate(BIN_COLORS)}
        own = calibration.max_acceleration  # the joints' own accelerations, where the config leaves them to the arm
        if config.motion.acceleration is None and own is None:
            poses = [self.home, self.q_wait, *(q for slots in self.q_drop.values() for q in slots)]
            own = torque_limited_accelerations(calibration.kinematics, poses)
        self.limits = JointLimits.of(calibration.max_velocity, config.motion, own)
        self._handlers: dict[Enum, Handler] = self.handlers()
        self.reset()

    # ------------------------------------------------------------------ what a subclass gives
    def handlers(self) -> dict[Enum, Handler]:
        """One handler per phase."""
        raise NotImplementedError

    def wait_point(self) -> tuple[float, float, float]:
        """Where the cup waits for a box [m]."""
        raise NotImplementedError

    def drop_seed(self) -> np.ndarray:
        """The joint angles [rad] the drop points' IK starts from."""
        raise NotImplementedError

    def slot_cost(self, point: tuple[float, float], q: np.ndarray) -> float:
        """How far a release point (x, y) [m] over a bin, reached at joint angles ``q`` [rad], is from where
        the expert picks: the slots that cost least are used. Here its distance from the robot's base (the
        world origin) [m]."""
        return float(np.hypot(*point))

    # ------------------------------------------------------------------ the loop
    def reset(self, obs: dict | None = None) -> None:
        """Start a new episode (from the arm's current joints if ``obs`` is given)."""
        self.phase = self.START
        self.time = 0.0
        self.phase_started = 0.0
        self.motion: Motion | None = None
        self.suction = False
        self.belt_pass = False
        self.drops = {c: 0 for c in BIN_COLORS}
        self.cycles: list[Cycle] = []
        self.carrying: Cycle | None = None  # a take-over's held box, until the lift ends
        self.misses: list[tuple[float, str]] = []  # (expert time [s], why) of each pick it gave up
        self._q_cmd = np.array(obs["robot0_joint_pos"], float) if obs is not None else self.home.copy()
        self._start_motion(self._q_cmd, self.q_wait, self.config.wait_tolerance)

    def take_over(self, obs: dict, view: TakeOver = NOTHING_HELD) -> None:
        """Go on from any state of the cell, as from a reset: the arm anywhere, the cup sealed to a box or not,
        boxes anywhere (what a policy left: DAgger's expert labels such states).

        The cup first rises straight up to the carry height, facing down (``CLEAR``); then a held box goes to the
        bin of its colour (one with no bin back onto the belt at the sensor, where the next look lets it through)
        and the arm to the wait pose, and the phases go on from there.

        Args:
            obs: the observation now.
            view: what no sensor of the cell shows (``cell.privileged.take_over_view(env.plant)``): the held box's
                colour (ignored when the vacuum switch reports no seal) and the boxes past the ray.

        Raises:
            NotImplementedError: this expert starts only from its own reset (``CLEAR`` is None).
        """
        if self.CLEAR is None:
            raise NotImplementedError(f"{type(self).__name__} starts only from its own reset; it cannot take over")
        self.reset(obs)
        if view.held is not None and sealed(obs):
            self.carrying = Cycle(view.held, self.time, target_bin=view.held if view.held in BIN_COLORS else None)
            self.cycles.append(self.carrying)
            self.suction = True
        self._start_motion(self._q_cmd, self._lifted(self._q_cmd), self.config.lift_tolerance)
        self._enter(self.CLEAR)

    @cached_property
    def descent(self) -> Descent:
        """The touch-off's heights [m], from the tallest and the lowest box the cell accepts."""
        return Descent.of(self.layout, self.config.touch_clearance, self.config.touch_floor)

    def _lifted(self, q: np.ndarray) -> np.ndarray:
        """Joint angles [rad] with the cup straight above where it is now at the carry height, facing down with its
        yaw kept; ``q`` itself if it is that high already or the arm cannot get there (it then moves on directly)."""
        position, rotation = self.ik.cup_pose(q)
        if position[2] >= self.config.carry_z - 0.01:
            return q
        waypoint = Waypoint("lift clear", (float(position[0]), float(position[1]), self.config.carry_z),
                            site_yaw(rotation))
        try:
            return self.ik.solve(waypoint, q)
        except UnreachableWaypoint:
            return q

    def _clear(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        """``CLEAR``: once up, a held box goes over its bin (or back to the belt), else the arm to the wait pose."""
        if not self._arrived(q):
            return
        cycle, self.carrying = self.carrying, None
        if cycle is None:
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(self.START)
            return
        assert self.OVER_BIN is not None, "an expert that takes over names its phase over the bin"
        if cycle.target_bin is not None:
            self._start_motion(goal, self._next_drop(cycle.target_bin), self.config.drop_tolerance)
        else:
            px, py, _ = self.layout.pick_point
            top = self.layout.belt_top_z + 2 * self.layout.box_size + self.config.approach_gap  # the box 4 cm up
            q_belt = self.ik.solve(Waypoint("back onto the belt", (px, py, top), self.cup_yaw), self.q_wait)
            self._start_motion(goal, q_belt, self.config.drop_tolerance)
        self._enter(self.OVER_BIN)

    @property
    def seen_color(self) -> str | None:
        """Colour of the box being handled, as the camera saw it, or None."""
        return self.cycles[-1].seen_color if self.cycles and self.cycles[-1].done_at is None else None

    @property
    def approaching(self) -> bool:
        """The arm is on its way to a waiting box (``APPROACH``): an ``act`` that turns this on starts a pick."""
        return self.APPROACH is not None and self.phase is self.APPROACH

    def act(self, obs: dict) -> np.ndarray:
        """The action for this step: joint targets [rad], suction, belt pass."""
        q = np.asarray(obs["robot0_joint_pos"], float)
        goal = self.motion.trajectory.goal if self.motion is not None else self._q_cmd
        self._handlers[self.phase](obs, q, goal)
        if self.motion is not None:
            ref, vel, acc = self.motion.trajectory.sample(self.time - self.motion.started + self.dt)
            self._q_cmd = ref + self.calibration.lead * vel
            if self.config.feed_forward_acceleration:
                self._q_cmd = self._q_cmd + self.calibration.compliance * acc
        self.time += self.dt
        return np.concatenate([self._q_cmd, [1.0 if self.suction else -1.0, 1.0 if self.belt_pass else -1.0]])

    def _enter(self, phase: Enum) -> None:
        self.phase, self.phase_started = phase, self.time

    # ------------------------------------------------------------------ the motion follower
    def _start_motion(self, start: np.ndarray, goal: np.ndarray, tolerance: float) -> None:
        """A jerk-limited motion from rest at ``start`` to rest at ``goal`` [rad], from now."""
        trajectory = plan_motion(start, goal, self.limits)
        self.motion = Motion(trajectory, self.time, tolerance)

    def _follow(self, trajectory: Trajectory, tolerance: float, started: float | None = None) -> None:
        """Follow ``trajectory`` from expert time ``started`` [s] (now by default)."""
        self.motion = Motion(trajectory, self.time if started is None else started, tolerance)

    def _current_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The commanded reference now: position [rad], velocity [rad/s], acceleration [rad/s^2]."""
        if self.motion is None:
            return self._q_cmd, np.zeros_like(self._q_cmd), np.zeros_like(self._q_cmd)
        return self.motion.sample(self.time)

    def _start_from_here(self, goal: np.ndarray, tolerance: float) -> None:
        """A jerk-limited motion to rest at ``goal`` [rad] from the reference's state now (moving or not)."""
        ref, vel, acc = self._current_state()
        self._follow(plan_motion(ref, goal, self.limits, start_velocity=vel, start_acceleration=acc), tolerance)

    def _arrived(self, q: np.ndarray) -> bool:
        return self.motion is None or self.motion.arrived(q, self.time)

    # ------------------------------------------------------------------ what both experts do alike
    def _look(self, obs: dict) -> tuple[Detection | None, Cycle]:
        """One photo of the box at the sensor; its cycle starts (``target_bin`` None: it is let through)."""
        t = self.sensor.box_at_sensor(self.sensor_image(obs))
        cycle = Cycle(t.color if t is not None else "none", self.time, target_bin=bin_for(t))
        self.cycles.append(cycle)
        return t, cycle

    def turn(self, t: Detection) -> float:
        """The cup's turn [rad] from its home yaw for box ``t``: the cube's yaw nearest the cup's, in [-45, 45) deg,
        or 0 when ``config.turn_to_box`` is off."""
        return t.yaw if self.config.turn_to_box else 0.0

    def _next_drop(self, color: str) -> np.ndarray:
        """The joint angles [rad] of the next release point over the ``color`` bin (the slots in turn)."""
        slots = self.q_drop[color]
        q = slots[self.drops[color] % len(slots)]
        self.drops[color] += 1
        return q

    def _released(self, obs: dict) -> bool:
        """In ``release``: the seal is gone and the box has had ``release_time`` to fall clear."""
        return not sealed(obs) and self.time - self.phase_started >= self.config.release_time

    def _drop_slots(self, color: str, index: int) -> list[np.ndarray]:
        """Joint angles of up to ``drop_slots`` release points over a bin, the least ``slot_cost`` first.

        Candidates lie on a grid inside the bin, far enough from its walls for the largest box the cell accepts,
        spanning ``drop_spread`` of that room about the bin's centre; those the arm cannot reach are skipped (the Panda
        reaches less far than the IRB 140).
        """
        L, cfg = self.layout, self.config
        bx, by = L.bin_center(index)
        margin = L.tallest_box / 2 + 0.01 + L.bin_wall  # the widest box the cell accepts, axis-aligned, 1 cm clear
        hx, hy = (cfg.drop_spread * (L.bin_size[k] / 2 - margin) for k in (0, 1))
        z = L.bin_size[2] + cfg.drop_clearance + L.box_size
        grid = [(bx + dx, by + dy) for dx in np.linspace(-hx, hx, 4) for dy in np.linspace(-hy, hy, 3)]
        reachable = []
        for point in grid:
            try:
                q = self.ik.solve(Waypoint(f"{color} bin drop", (*point, z), self.cup_yaw), self.drop_seed())
            except UnreachableWaypoint:
                continue
            reachable.append((self.slot_cost(point, q), q))
        if not reachable:
            raise UnreachableWaypoint(f"No drop point over the {color} bin is within the arm's reach")
        reachable.sort(key=lambda slot: slot[0])  # stable: equal costs keep the grid's order
        return [q for _, q in reachable[: cfg.drop_slots]]
