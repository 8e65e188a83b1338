"""Motion planning for the cup: mink inverse kinematics for waypoints, ruckig joint trajectories.

``CupIK`` turns a waypoint (cup position, pointing down, turned ``yaw`` about world z) into joint
angles with mink: a frame task on the cup's grip site, a posture task that keeps the arm near its
home configuration, and the joint limits. A waypoint it cannot reach within 1 mm and 1 deg is an
``UnreachableWaypoint`` error naming it.

``plan_motion`` connects two joint configurations with a time-optimal, jerk-limited trajectory
(ruckig), within ``JointLimits``: the robot's datasheet joint speeds scaled by
``MotionConfig.speed_factor``, and the configured acceleration and jerk limits (or each joint's own
torque-limited acceleration, ``limits.torque_limited_accelerations``), as the original cell's Reflexxes
call did.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import mink
import mujoco
import numpy as np
import ruckig

from colorsort.config import check_range
from colorsort.errors import ConfigError, PlanningError

GRIP_SITE = "gripper0_right_grip_site"
POSITION_TOLERANCE = 1e-3  # [m] a waypoint is reached within this
ANGLE_TOLERANCE = np.deg2rad(1.0)  # [rad]


@dataclass(frozen=True)
class MotionConfig:
    """Limits of the arm's joint motion.

    Attributes:
        speed_factor: fraction of the datasheet joint speeds used, in (0, 1].
        acceleration: max joint acceleration [rad/s^2], every joint; None: each joint's own, what its
            actuator's torque limit gives it (``limits.torque_limited_accelerations``).
        jerk: max joint jerk [rad/s^3], every joint.
    """

    speed_factor: float = 1.0
    acceleration: float | None = 15.0
    jerk: float = 150.0

    def __post_init__(self) -> None:
        check_range("speed_factor", self.speed_factor, 0.0, 1.0, low_inclusive=False)
        if self.acceleration is not None:
            check_range("acceleration", self.acceleration, 0.0, 100.0, low_inclusive=False)  # [rad/s^2]
        check_range("jerk", self.jerk, 0.0, 5000.0, low_inclusive=False)  # [rad/s^3]


@dataclass(frozen=True)
class JointLimits:
    """What a planned motion keeps to, per joint: speed [rad/s], acceleration [rad/s^2], jerk [rad/s^3]."""

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    @classmethod
    def of(cls, max_velocity: np.ndarray, config: MotionConfig,
           accelerations: np.ndarray | None = None) -> JointLimits:
        """The limits ``config`` sets for joints of datasheet speeds ``max_velocity`` [rad/s]; ``accelerations``
        [rad/s^2], per joint, are the joints' own where ``config.acceleration`` is None (and are then needed)."""
        velocity = np.asarray(max_velocity, float) * config.speed_factor
        acceleration: np.ndarray
        if config.acceleration is not None:
            acceleration = np.full(len(velocity), config.acceleration)
        elif accelerations is None:
            raise ConfigError("MotionConfig(acceleration=None) plans at each joint's own acceleration: "
                             "give accelerations")
        else:
            acceleration = np.asarray(accelerations, float)
        return cls(velocity, acceleration, np.full(len(velocity), config.jerk))


@dataclass(frozen=True)
class Waypoint:
    """A cup pose: the pad's centre at ``position`` [m] (world), cup pointing down, turned ``yaw`` [rad] about z."""

    name: str
    position: tuple[float, float, float]
    yaw: float = 0.0


class UnreachableWaypoint(ValueError):
    """Raised when IK cannot put the cup on a waypoint within tolerance."""


def cup_down_rotation(yaw: float) -> np.ndarray:
    """Rotation (3, 3) of the grip site, its z axis (the cup's approach) pointing down, its x axis at ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def site_yaw(rotation: np.ndarray) -> float:
    """Yaw [rad] of a grip-site rotation (3, 3): the heading of its x axis about world z."""
    return float(np.arctan2(rotation[1, 0], rotation[0, 0]))


class CupIK:
    """Inverse kinematics of the cup with mink, on a model of the robot alone.

    Args:
        model: the robot with its gripper (``robot_model.get_model(mode="mujoco")``), base at the
            world origin as in the cell; its first ``n`` joints are the arm.
        posture: comfortable joint configuration [rad], (n,), the posture task's target.
        posture_cost: weight of the posture task relative to the cup task (small: it only
            resolves redundancy and keeps the solution near home).
    """

    def __init__(self, model: mujoco.MjModel, posture: np.ndarray, posture_cost: float = 1e-3):
        self.model = model
        self.n = len(posture)
        self.configuration = mink.Configuration(model)
        self.frame_task = mink.FrameTask(GRIP_SITE, "site", position_cost=1.0, orientation_cost=1.0, lm_damping=1e-6)
        self.posture_task = mink.PostureTask(model, cost=posture_cost)
        q_posture = model.qpos0.copy()
        q_posture[: self.n] = posture
        self.posture_task.set_target(q_posture)
        self.limits = [mink.ConfigurationLimit(model)]
        self.posture = np.asarray(posture, float)
        self._q = model.qpos0.copy()

    def cup_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Grip-site position [m] (3,) and rotation (3, 3) at joint angles ``q`` [rad]."""
        self._q[: self.n] = q
        self.configuration.update(self._q)
        data = self.configuration.data
        site = data.site(GRIP_SITE)
        return site.xpos.copy(), site.xmat.reshape(3, 3).copy()

    def solve(self, waypoint: Waypoint, q_init: np.ndarray, max_iters: int = 200, dt: float = 0.1) -> np.ndarray:
        """Joint angles [rad] (n,) that put the cup on ``waypoint``, starting the search at ``q_init``.

        A search that ends in a local minimum is restarted from the posture (home) configuration.

        Raises:
            UnreachableWaypoint: the best solution misses by more than 1 mm or 1 deg.
        """
        try:
            return self._solve_from(waypoint, q_init, max_iters, dt)
        except UnreachableWaypoint:
            return self._solve_from(waypoint, self.posture, max_iters, dt)

    def _solve_from(self, waypoint: Waypoint, q_init: np.ndarray, max_iters: int, dt: float) -> np.ndarray:
        self._q[: self.n] = q_init
        self.configuration.update(self._q)
        target = mink.SE3.from_rotation_and_translation(
            mink.SO3.from_matrix(cup_down_rotation(waypoint.yaw)), np.asarray(waypoint.position, float)
        )
        self.frame_task.set_target(target)
        tasks = [self.frame_task, self.posture_task]
        for _ in range(max_iters):
            velocity = mink.solve_ik(self.configuration, tasks, dt, solver="daqp", damping=1e-6, limits=self.limits)
            self.configuration.integrate_inplace(velocity, dt)
            err = self.frame_task.compute_error(self.configuration)  # (6,): position [m], rotation [rad]
            if np.linalg.norm(err[:3]) < 1e-5 and np.linalg.norm(err[3:]) < 1e-4:
                break
        q = self.configuration.q[: self.n].copy()
        pos, rot = self.cup_pose(q)
        pos_err = float(np.linalg.norm(pos - target.translation()))
        ang_err = float(np.linalg.norm(mink.SO3.from_matrix(rot.T @ cup_down_rotation(waypoint.yaw)).log()))
        if pos_err > POSITION_TOLERANCE or ang_err > ANGLE_TOLERANCE:
            raise UnreachableWaypoint(
                f"Waypoint {waypoint.name!r} at {np.round(waypoint.position, 3).tolist()} m, yaw "
                f"{np.rad2deg(waypoint.yaw):.1f} deg is out of reach: the closest pose misses by "
                f"{1000 * pos_err:.1f} mm and {np.rad2deg(ang_err):.2f} deg (tolerance 1 mm, 1 deg)"
            )
        return q


class Trajectory(Protocol):
    """A joint motion sampled by time: a ``JointTrajectory`` or a dense path (the tracking expert's)."""

    goal: np.ndarray  # [rad] the joints at the end

    @property
    def duration(self) -> float: ...

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


class JointTrajectory:
    """A jerk-limited joint trajectory (ruckig), sampled by time."""

    def __init__(self, trajectory: ruckig.Trajectory, start: np.ndarray, goal: np.ndarray):
        self._trajectory = trajectory
        self.start = start
        self.goal = goal

    @property
    def duration(self) -> float:
        """[s]"""
        return float(self._trajectory.duration)

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [rad], velocity [rad/s] and acceleration [rad/s^2] at time ``t`` [s] (clamped to the ends)."""
        t = min(max(t, 0.0), self.duration)
        pos, vel, acc = self._trajectory.at_time(t)
        return np.array(pos), np.array(vel), np.array(acc)


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


def plan_motion(start: np.ndarray, goal: np.ndarray, limits: JointLimits,
                start_velocity: np.ndarray | None = None, start_acceleration: np.ndarray | None = None,
                goal_velocity: np.ndarray | None = None, minimum_duration: float | None = None) -> JointTrajectory:
    """Time-optimal jerk-limited motion from ``start`` to ``goal`` [rad], (n,): from rest to rest unless
    ``start_velocity`` [rad/s], ``start_acceleration`` [rad/s^2] or ``goal_velocity`` [rad/s] say otherwise
    (ruckig plans to a target velocity as well as a position), taking at least ``minimum_duration`` [s],
    within ``limits``."""
    n = len(start)
    zeros = [0.0] * n
    inp = ruckig.InputParameter(n)
    inp.current_position = list(map(float, start))
    inp.current_velocity = zeros if start_velocity is None else list(map(float, start_velocity))
    inp.current_acceleration = zeros if start_acceleration is None else list(map(float, start_acceleration))
    inp.target_position = list(map(float, goal))
    inp.target_velocity = zeros if goal_velocity is None else list(map(float, goal_velocity))
    inp.target_acceleration = zeros
    inp.max_velocity = list(map(float, limits.velocity))
    inp.max_acceleration = list(map(float, limits.acceleration))
    inp.max_jerk = list(map(float, limits.jerk))
    if minimum_duration is not None:
        inp.minimum_duration = float(minimum_duration)
    trajectory = ruckig.Trajectory(n)
    result = ruckig.Ruckig(n).calculate(inp, trajectory)
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise PlanningError(f"ruckig could not plan from {np.round(start, 3)} to {np.round(goal, 3)}: {result}")
    return JointTrajectory(trajectory, np.asarray(start, float), np.asarray(goal, float))
