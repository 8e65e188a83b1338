"""The IRB 140 model against its datasheet, and the suction gripper on robosuite's arms."""

import mujoco
import numpy as np
import pytest
from helpers import arm_joint_ids

from colorsort.cell.models.irb140 import HOME_QPOS, JOINT_LIMITS_DEG, dh_forward_kinematics

DATASHEET_SPEEDS_DEG_S = (200, 200, 260, 360, 360, 450)  # ABB IRB 140 product specification


@pytest.mark.parametrize("seed", range(4))
def test_forward_kinematics_matches_dh_table(env, seed):
    m, d = env.mj_model, mujoco.MjData(env.mj_model)
    qadr, _ = arm_joint_ids(env)
    hand = m.body("robot0_right_hand").id
    q = np.zeros(6) if seed == 0 else np.random.default_rng(seed).uniform(-1.5, 1.5, 6)
    d.qpos[qadr] = q
    mujoco.mj_kinematics(m, d)
    T = dh_forward_kinematics(q)
    assert np.linalg.norm(d.xpos[hand] - T[:3, 3]) < 1e-3  # within 1 mm
    assert np.allclose(d.xmat[hand].reshape(3, 3), T[:3, :3], atol=1e-3)


def test_zero_pose_is_abb_calibration_pose():
    # ABB product specification: flange centre at x = 515 mm, z = 712 mm in the calibration pose.
    assert np.allclose(dh_forward_kinematics(np.zeros(6))[:3, 3], [0.515, 0.0, 0.712], atol=1e-6)


def test_joint_and_speed_limits_are_in_the_model(env):
    m = env.mj_model
    joints = env.robots[0].robot_model.joints
    ranges = np.array([m.jnt_range[m.joint(j).id] for j in joints])
    assert np.allclose(np.rad2deg(ranges), JOINT_LIMITS_DEG, atol=0.01)
    assert all(m.jnt_limited[m.joint(j).id] for j in joints)
    speeds = m.numeric("robot0_joint_velocity_limits").data
    assert np.allclose(np.rad2deg(speeds), DATASHEET_SPEEDS_DEG_S, atol=0.01)


def test_visual_and_collision_geoms_are_separate(env):
    m = env.mj_model
    robot_geoms = [i for i in range(m.ngeom) if m.geom(i).name.startswith("robot0_")]
    visual = [g for g in robot_geoms if m.geom_group[g] == 1]
    collision = [g for g in robot_geoms if m.geom_group[g] == 0]
    assert len(visual) >= 6 and len(collision) >= 6
    assert all(m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0 for g in visual)
    assert all(m.geom_contype[g] == 1 for g in collision)


def test_masses_are_plausible(env):
    m = env.mj_model
    bodies = [m.body(b).id for b in env.robots[0].robot_model.bodies]
    total = sum(m.body_mass[b] for b in bodies)
    assert 80 < total < 110  # datasheet: 98 kg
    for b in bodies:
        if m.body_mass[b] > 0:
            assert np.all(m.body_inertia[b] > 0)


def test_home_pose_holds_still_under_gravity(env):
    qadr, dadr = arm_joint_ids(env)
    assert np.allclose(env.sim.data.qpos[qadr], HOME_QPOS)
    hold = np.concatenate([HOME_QPOS, [-1.0, -1.0]])
    for _ in range(40):  # 2 s
        env.step(hold)
    assert np.abs(env.sim.data.qpos[qadr] - HOME_QPOS).max() < 1e-3
    assert np.abs(env.sim.data.qvel[dadr]).max() < 1e-3


@pytest.mark.parametrize("robot", ["Panda", "UR5e"])
def test_suction_gripper_mounts_on_robosuite_arms(robot, make_env):
    env = make_env(robot)
    obs = env.reset()
    assert env.action_dim == (9 if robot == "Panda" else 8)  # joints + suction + belt pass
    assert type(env.robots[0].gripper["right"]).__name__ == "SuctionGripper"
    q = obs["robot0_joint_pos"]
    for _ in range(20):
        obs, _, _, info = env.step(np.concatenate([q, [1.0, -1.0]]))
    assert np.abs(obs["robot0_joint_pos"] - q).max() < 0.01


@pytest.mark.parametrize("xml", [("irb140", "robot.xml"), ("suction_gripper", "suction_gripper.xml")])
def test_mjcf_geoms_take_the_visual_or_collision_default_class(xml):
    import xml.etree.ElementTree as ET

    from colorsort.paths import asset_path

    root = ET.parse(asset_path(*xml)).getroot()
    geoms = root.find("worldbody").iter("geom")
    assert all(g.get("class") in ("visual", "collision") and g.get("group") is None for g in geoms)
    model = mujoco.MjModel.from_xml_path(asset_path(*xml))  # MuJoCo itself resolves the classes
    visual = [g for g in range(model.ngeom) if model.geom(g).name.endswith("_vis")]
    assert visual and all(model.geom_group[g] == 1 and model.geom_contype[g] == 0 for g in visual)


def test_home_keyframe_is_the_pose_episodes_start_in(env):
    from colorsort.paths import asset_path
    from colorsort.robots import ROBOTS

    model = mujoco.MjModel.from_xml_path(asset_path("irb140", "robot.xml"))
    assert np.array_equal(model.key("home").qpos, ROBOTS["IRB140"].home)
    qadr, _ = arm_joint_ids(env)
    assert np.array_equal(env.sim.data.qpos[qadr], model.key("home").qpos)
