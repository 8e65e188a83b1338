"""How fast each joint of the arm can accelerate: what its actuator's torque limit gives it.

Most makers publish joint speeds, not accelerations; the arm's MJCF gives what sets them, each
actuator's torque limit [N m] and the links' masses and inertias. At a pose ``q``, at rest, a joint
driven at its torque limit while the others hold still accelerates at (torque limit - torque holding
the arm against gravity - the joint's dry friction) / its diagonal entry of the joint-space inertia
matrix M(q) (armature included); faster if the others give way.
``torque_limited_accelerations`` takes the least of that over the poses an expert moves between and
keeps ``TORQUE_SHARE`` of it: the rest of the torque is left to the position controller's feedback
and to the other joints' coupling.
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np

from colorsort.errors import ConfigError

TORQUE_SHARE = 0.8  # of each joint's torque-limited acceleration that motions are planned at


def torque_limited_accelerations(model: mujoco.MjModel, poses: Iterable[np.ndarray],
                                 share: float = TORQUE_SHARE) -> np.ndarray:
    """[rad/s^2] per arm joint: ``share`` of the least, over ``poses`` (joint angles [rad] of the first n
    joints, each (n,)), of (actuator torque limit - |gravity torque| - friction loss) / M_jj, the arm at rest.

    ``model``: the arm alone (``Calibration.kinematics``), whose first n actuators drive its n joints.
    """
    poses = [np.asarray(q, float) for q in poses]
    n = len(poses[0])
    if list(model.actuator_trnid[:n, 0]) != list(range(n)):
        raise ConfigError(f"the model's first {n} actuators do not drive its first {n} joints in order")
    torque = np.abs(model.actuator_ctrlrange[:n, 1] * model.actuator_gear[:n, 0]) - model.dof_frictionloss[:n]  # [N m]
    data = mujoco.MjData(model)
    inertia = np.zeros((model.nv, model.nv))
    least = np.full(n, np.inf)
    for q in poses:
        data.qpos[:n], data.qvel[:] = q, 0.0
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, inertia, data.qM)
        least = np.minimum(least, (torque - np.abs(data.qfrc_bias[:n])) / np.diag(inertia)[:n])
    if np.any(least <= 0.0):
        raise ConfigError(f"joints {np.flatnonzero(least <= 0.0).tolist()} cannot hold the arm up at some pose: "
                         f"their torque limits less friction, {torque.tolist()} N m, are below gravity's")
    return share * least
