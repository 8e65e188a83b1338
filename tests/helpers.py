"""Test helpers: small envs, and a small damped-least-squares IK and motion driver for the arm.

The expert's planner (mink + ruckig) is the product's IK; these helpers only put the cup where
a physics test needs it, with as little machinery as possible. In a test, take envs from the
``make_env`` fixture (``conftest.py``), which closes them; ``new_env`` is for module fixtures.
"""

from __future__ import annotations

import io
import logging
import os
import runpy
import subprocess
import sys
from collections.abc import Callable
from contextlib import redirect_stderr, redirect_stdout
from importlib.metadata import entry_points
from pathlib import Path

import mujoco
import numpy as np
import robosuite as suite

from colorsort.config import BoxStyle
from colorsort.envs.robosuite_task import ColorSort

TINY = dict(episodes=2, image_size=(64, 64), cameras=("scene", "wrist"))  # two one-box episodes


def new_env(robot: str = "IRB140", **kwargs) -> ColorSort:
    """A ColorSort env without cameras unless asked for; episodes never end on their own. The caller closes it."""
    kwargs.setdefault("has_offscreen_renderer", False)
    kwargs.setdefault("use_camera_obs", False)
    kwargs.setdefault("ignore_done", True)
    kwargs.setdefault("seed", 0)
    return suite.make("ColorSort", robots=robot, **kwargs)


CUP_DOWN = np.array([0.0, 0.0, -1.0])  # world direction of the cup's approach axis when picking


def arm_joint_ids(env: ColorSort) -> tuple[np.ndarray, np.ndarray]:
    """(qpos addresses, dof addresses) of the arm's joints."""
    robot = env.robots[0]
    return np.array(robot._ref_joint_pos_indexes), np.array(robot._ref_joint_vel_indexes)


def cup_site(env: ColorSort) -> int:
    return env.sim.model.site_name2id("gripper0_right_grip_site")


def solve_cup_ik(env: ColorSort, target: np.ndarray, q_init: np.ndarray | None = None, iters: int = 300) -> np.ndarray:
    """Joint angles [rad] that put the cup pad's centre at ``target`` [m], cup facing down."""
    m = env.mj_model
    d = mujoco.MjData(m)
    d.qpos[:] = env.sim.data.qpos
    qadr, dadr = arm_joint_ids(env)
    if q_init is not None:
        d.qpos[qadr] = q_init
    site = cup_site(env)
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for _ in range(iters):
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        pos_err = target - d.site_xpos[site]
        z_axis = d.site_xmat[site].reshape(3, 3)[:, 2]
        rot_err = np.cross(z_axis, CUP_DOWN)
        err = np.concatenate([pos_err, rot_err])
        if np.linalg.norm(pos_err) < 1e-5 and np.linalg.norm(rot_err) < 1e-5:
            break
        mujoco.mj_jacSite(m, d, jacp, jacr, site)
        J = np.vstack([jacp[:, dadr], jacr[:, dadr]])
        dq = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(6), err)
        d.qpos[qadr] += dq
        for k, j in enumerate(env.robots[0].robot_model.joints):
            jid = m.joint(j).id
            d.qpos[qadr[k]] = np.clip(d.qpos[qadr[k]], *m.jnt_range[jid])
    assert np.linalg.norm(pos_err) < 1e-3, f"IK did not reach {target}: error {pos_err}"
    return d.qpos[qadr].copy()


def move_to(env: ColorSort, q_goal: np.ndarray, suction: float, duration: float, settle: float = 0.3, on_step=None):
    """Drive the arm to ``q_goal`` [rad] along a linear joint path over ``duration`` [s], then settle."""
    qadr, _ = arm_joint_ids(env)
    q_start = env.sim.data.qpos[qadr].copy()
    n_move = max(1, int(round(duration * env.control_freq)))
    n_settle = int(round(settle * env.control_freq))
    obs = info = None
    for k in range(1, n_move + n_settle + 1):
        s = min(1.0, k / n_move)
        s = 3 * s**2 - 2 * s**3  # smooth start and stop
        obs, _, _, info = env.step(np.concatenate([q_start + s * (q_goal - q_start), [suction, -1.0]]))
        if on_step is not None:
            on_step(env)
    return obs, info


def wait_for_box_at_sensor(env: ColorSort, timeout: float = 20.0):
    """Step with the arm still until the ray sensor sees a box; return that box."""
    qadr, _ = arm_joint_ids(env)
    hold = np.concatenate([env.sim.data.qpos[qadr], [-1.0, -1.0]])
    for _ in range(int(timeout * env.control_freq)):
        _, _, _, info = env.step(hold)
        if info["box_detected"]:
            return min(env.boxes_in_play(), key=lambda b: env.box_pos(b)[0])
    raise AssertionError("no box reached the sensor")


def exit_status(main, argv: list[str]) -> int:
    """A console script's exit status for ``argv``: what ``main`` returns, or argparse's ``SystemExit`` code."""
    try:
        return main(argv)
    except SystemExit as stop:
        return stop.code


def in_this_process(main: Callable[[], int | None], argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``main()`` run as a program would run with command line ``argv`` in ``cwd``, reported as ``subprocess.run``
    reports a process (exit status, stdout, stderr), here: the same code path without a new interpreter (LeRobot's
    imports alone take 10 to 15 s here). Its logging set-up (LeRobot's replaces the root logger's handlers),
    ``sys.argv`` and the working directory are put back afterwards."""
    root = logging.getLogger()
    handlers, level, argv0, here = root.handlers[:], root.level, sys.argv, os.getcwd()
    out, err = io.StringIO(), io.StringIO()
    sys.argv = list(argv)
    try:
        os.chdir(cwd)
        with redirect_stdout(out), redirect_stderr(err):
            try:
                status = main() or 0
            except SystemExit as stop:
                status = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    finally:
        os.chdir(here)
        sys.argv = argv0
        root.handlers[:] = handlers
        root.setLevel(level)
    return subprocess.CompletedProcess(list(argv), status, out.getvalue(), err.getvalue())


def console_script(program: str, argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """The console script ``program`` (ColorSort's ``colorsort-*``, LeRobot's ``lerobot-*``) with ``argv``, in
    ``cwd``, by the entry point the script calls, in this process (``in_this_process``). README's own commands run
    as real processes."""
    (entry,) = entry_points(group="console_scripts", name=program)
    return in_this_process(entry.load(), [program, *argv], cwd)


def python_script(path: Path, argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``python path argv...`` in this process (``in_this_process``): the file run as ``__main__``, as python runs
    it (``runpy.run_path``)."""
    def main() -> None:  # a script that returns without sys.exit exits 0
        runpy.run_path(str(path), run_name="__main__")

    return in_this_process(main, [str(path), *argv], cwd)


# the boxes a touch-off must find the top of without being told it: cubes of 5 to 15 cm and a puck
TOUCH_STYLES = {f"cube {round(100 * h)} cm": BoxStyle("box", h, h) for h in (0.05, 0.07, 0.10, 0.13, 0.15)}
TOUCH_STYLES["puck 12 x 6 cm"] = BoxStyle("cylinder", 0.12, 0.06)
