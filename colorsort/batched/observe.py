"""The ``observe`` kernel: ``observation.state`` and ``observation.environment_state`` of every world, written at the
offsets of the CPU cell's observation layout (``cell.observation``), handed to the kernel as one struct."""

from __future__ import annotations

import warp as wp

from colorsort.batched.arrays import Boxes, Controls, Pool
from colorsort.batched.kernels import IN_PLAY
from colorsort.cell.observation import BoxStateLayout, StateLayout

wp.set_module_options({"enable_backward": False})  # nothing differentiates the cell: half the compile


@wp.struct
class ObservationLayout:
    """``cell.observation``'s layouts as the ``observe`` kernel reads them (``observation_layout``)."""

    n_joints: int
    joint_pos: int
    joint_vel: int
    cup_pos: int
    cup_quat: int
    flags: int
    travel: int  # -1: a stopping belt, whose state has no encoder
    n_colors: int
    box_pose: int
    box_present: int
    box_size: int


def observation_layout(state: StateLayout, box: BoxStateLayout) -> ObservationLayout:
    """The kernel's copy of the CPU cell's observation layout: every offset from ``cell.observation``."""
    out = ObservationLayout()
    out.n_joints, out.joint_pos, out.joint_vel = state.n_joints, state.joint_pos, state.joint_vel
    out.cup_pos, out.cup_quat, out.flags, out.travel = state.cup_pos, state.cup_quat, state.flags, state.travel
    out.n_colors, out.box_pose, out.box_present, out.box_size = box.n_colors, box.pose, box.present, box.size
    return out


@wp.kernel
def observe(qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float), site_xpos: wp.array2d(dtype=wp.vec3),
            xquat: wp.array2d(dtype=wp.quat), arm_qpos: wp.array(dtype=int), arm_dof: wp.array(dtype=int),
            eef_site: int, eef_body: int, io: Controls, pool: Pool, boxes: Boxes, layout: ObservationLayout,
            state: wp.array2d(dtype=float), env_state: wp.array2d(dtype=float)):
    """``schema.robot_state`` and ``schema.box_state`` (``Plant.next_box_state``): ``observation.state`` and
    ``observation.environment_state`` of every world, at ``cell.observation``'s offsets."""
    w = wp.tid()
    for j in range(layout.n_joints):
        state[w, layout.joint_pos + j] = qpos[w, arm_qpos[j]]
        state[w, layout.joint_vel + j] = qvel[w, arm_dof[j]]
    p = site_xpos[w, eef_site]
    q = xquat[w, eef_body]
    for k in range(3):
        state[w, layout.cup_pos + k] = p[k]
    state[w, layout.cup_quat + 0] = q[1]  # robosuite's eef_quat is (x, y, z, w)
    state[w, layout.cup_quat + 1] = q[2]
    state[w, layout.cup_quat + 2] = q[3]
    state[w, layout.cup_quat + 3] = q[0]
    state[w, layout.flags + 0] = float(io.suction_cmd[w])
    state[w, layout.flags + 1] = wp.where(io.held[w] >= 0, 1.0, 0.0)
    state[w, layout.flags + 2] = float(io.detected[w])
    state[w, layout.flags + 3] = float(io.running[w])
    if layout.travel >= 0:
        state[w, layout.travel] = float(io.travel[w])
    best = int(-1)  # noqa: UP018
    for box in range(pool.size):
        if boxes.status[w, box] == IN_PLAY and (best < 0 or boxes.serial[w, box] < boxes.serial[w, best]):
            best = box
    for k in range(layout.box_size):
        env_state[w, k] = 0.0
    if best >= 0:
        if boxes.color[w, best] < layout.n_colors:  # a colour with no class has no one-hot (as Plant.next_box_state)
            env_state[w, boxes.color[w, best]] = 1.0
        qa = pool.qpos[best]
        for k in range(7):
            env_state[w, layout.box_pose + k] = qpos[w, qa + k]
        env_state[w, layout.box_present] = 1.0
