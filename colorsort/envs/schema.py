"""ColorSort episodes as LeRobot v3.0 frames: the feature schema, one frame, the task text.

Features of a ColorSort dataset (``IRB140``: 6 joints, so ``n = 6``):

================================  =========  ==========  =================================================
key                               dtype      shape       what
================================  =========  ==========  =================================================
``observation.images.<camera>``   video      (H, W, 3)   camera ``scene``, ``sensor`` or ``wrist``, RGB
``observation.state``             float32    (2n + 11,)  joint positions [rad] and velocities [rad/s], cup
                                                         position [m] and quaternion (x, y, z, w), suction
                                                         commanded, vacuum sealed, ray blocked, belt running;
                                                         on a tracking belt (2n + 12,): then the belt's
                                                         encoder [m]
``observation.environment_state`` float32    (13,)       the next box to sort (lowest serial in play): colour
                                                         one-hot over ``config.COLORS``, position [m],
                                                         quaternion (w, x, y, z), 1 if there is one
``action``                        float32    (n + 2,)    exactly what the env consumed: joint targets [rad],
                                                         suction, belt pass (both in [-1, 1], > 0 is on)
``sim_state``                     float64    (S,)        ``ColorSort.get_sim_state()``: replays the frame
                                                         (layout: ``cell/sim_state.py``)
================================  =========  ==========  =================================================

``sim_state`` does not start with ``observation.``, so LeRobot policies do not take it as an
input. Frame ``t`` pairs the observation after ``t`` steps with the action
taken from it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.cell.observation import BOX_STATE, StateLayout
from colorsort.config import BIN_COLORS
from colorsort.envs.robosuite_task import ColorSort

STATE = "observation.state"
ENV_STATE = "observation.environment_state"
ACTION = "action"
SIM_STATE = "sim_state"


def image_key(camera: str) -> str:
    """The feature that stores camera ``camera``'s frames."""
    return f"observation.images.{camera}"


def joint_names(env: ColorSort) -> list[str]:
    """The arm's joint names without robosuite's prefix, e.g. ``joint1``."""
    prefix = env.robots[0].robot_model.naming_prefix
    return [j.removeprefix(prefix) for j in env.robots[0].robot_joints]


def state_layout(env: ColorSort) -> StateLayout:
    """Where each quantity lies in ``env``'s ``observation.state`` (``cell.observation``). The encoder only on a
    tracking belt: on a stopping one it adds nothing a policy needs, and the policies trained on stopping-belt data
    keep their input."""
    return StateLayout(len(joint_names(env)), env.config.tracking)


def state_names(env: ColorSort) -> list[str]:
    """The names of ``observation.state``'s elements."""
    return state_layout(env).names(joint_names(env))


def state_size(n_joints: int, tracking: bool = False) -> int:
    """Length of ``observation.state`` for an arm with ``n_joints`` joints, on a tracking belt or not."""
    return StateLayout(n_joints, tracking).size


def env_state_names() -> list[str]:
    """The names of ``observation.environment_state``'s elements."""
    return BOX_STATE.names()


ENV_STATE_SIZE = BOX_STATE.size  # = len(Plant.next_box_state())


def action_names(env: ColorSort) -> list[str]:
    return env.action_names()


def features(env: ColorSort, cameras: tuple[str, ...], image_size: tuple[int, int]) -> dict[str, dict]:
    """LeRobot feature definitions for a dataset recorded from ``env`` with these cameras.

    Args:
        env: the env the frames come from (for joint names and state sizes).
        cameras: camera names, each stored as ``observation.images.<camera>``.
        image_size: (height, width) of every camera [px].
    """
    h, w = image_size
    out: dict[str, dict] = {
        image_key(c): {"dtype": "video", "shape": (h, w, 3), "names": ["height", "width", "channels"]}
        for c in cameras
    }
    for key, names, dtype in ((STATE, state_names(env), "float32"), (ENV_STATE, env_state_names(), "float32"),
                              (ACTION, action_names(env), "float32")):
        out[key] = {"dtype": dtype, "shape": (len(names),), "names": names}
    out[SIM_STATE] = {"dtype": "float64", "shape": (env.sim_state_size,), "names": None}
    return out


def robot_state(env: ColorSort, obs: dict[str, Any]) -> np.ndarray:
    """``observation.state`` from an observation of ``env`` (see the module docstring)."""
    flags = (float(env.plant.seal.commanded), float(env.suction_sealed), float(env.box_detected),
             float(env.belt_running))
    return state_layout(env).pack(obs["robot0_joint_pos"], obs["robot0_joint_vel"], obs["robot0_eef_pos"],
                                  obs["robot0_eef_quat"], flags, env.plant.belt.travel if env.config.tracking else None)


def box_state(env: ColorSort) -> np.ndarray:
    """``observation.environment_state``: the in-play box with the lowest serial, or zeros."""
    return env.plant.next_box_state()


def frame(env: ColorSort, obs: dict[str, Any], action: np.ndarray, cameras: tuple[str, ...],
          task: str) -> dict[str, Any]:
    """One LeRobot frame: the observation ``obs`` (just returned by ``env``) and the action taken from it."""
    out: dict[str, Any] = {image_key(c): obs[f"{c}_image"] for c in cameras}
    out[STATE] = robot_state(env, obs)
    out[ENV_STATE] = box_state(env)
    out[ACTION] = np.asarray(action, np.float32)
    out[SIM_STATE] = env.get_sim_state()
    out["task"] = task
    return out


def task_text(first_color: str, boxes: int) -> str:
    """The instruction for an episode of ``boxes`` boxes, the first of which is ``first_color``."""
    if boxes == 1:
        c = first_color
        if c in BIN_COLORS:
            return f"Pick the {c} box from the conveyor and place it in the {c} bin."
        return f"Let the {c} box pass on the conveyor: it has no bin."
    return f"Sort the next {boxes} boxes from the conveyor into the bins of their colours."
