"""What the batched cell takes from the CPU cell: its compiled model and where each part of the cell lies in it.

``CellSpec.from_env`` reads a built ``ColorSort`` env (robosuite composes the model on the host, once);
``save``/``load`` keep it as ``cell.mjb`` (MuJoCo's binary model) and ``cell.json``, so that a machine
with MuJoCo Warp but no robosuite can run the cell. Nothing here imports warp.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from colorsort.config import CellLayout, Lighting, TaskConfig

# Parked boxes wait here on the batched cell [m]: MuJoCo Warp's collision filters (contype) are shared by
# every world, so a parked box stays collidable; in the air, spaced out and far from the cell, it touches
# nothing (the CPU cell parks them below the floor with collisions off).
PARK_ORIGIN = (10.0, 10.0, 5.0)
PARK_SPACING = 0.5


def air_park_position(index: int) -> tuple[float, float, float]:
    """Where pooled box ``index`` waits while parked on the batched cell [m]."""
    x, y, z = PARK_ORIGIN
    return (x + PARK_SPACING * index, y, z)


@dataclass(frozen=True)
class CellSpec:
    """The cell's compiled model and the addresses of its parts (indices into MuJoCo's arrays).

    Attributes:
        model: the compiled model, with every box collidable (see ``PARK_ORIGIN``).
        qpos0, qvel0: the state after a reset, every box parked [rad, m; rad/s, m/s].
        layout, config: the cell's geometry and the task's parameters.
        control_freq: policy rate [Hz]; servo_period: physics steps per torque update.
        arm_qpos, arm_dof, arm_actuators: the arm joints' qpos and dof addresses and actuators.
        kp, kd: the joint controller's gains [N m/rad, N m s/rad]; robosuite's
            ``JointPositionController`` with torque compensation: tau = M (kp e - kd qdot) + bias.
        torque_low, torque_high: the arm actuators' ranges [N m].
        suction: the suction actuator; suction_off, suction_on: its ctrl values.
        belt_qpos, belt_dof: the belt's slide joint; ray: the ray sensor's address in ``sensordata``.
        cup_body, pad_geom: the cup and its pad; eef_site, eef_body: robosuite's ``eef_pos`` site and
            ``eef_quat`` body.
        box_body, box_geom, box_qpos, box_dof, box_weld: per pooled box.
        action_low, action_high: the action's bounds (joint targets, suction, belt pass).
    """

    model: mujoco.MjModel
    qpos0: np.ndarray
    qvel0: np.ndarray
    layout: CellLayout
    config: TaskConfig
    control_freq: float
    servo_period: int
    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    arm_actuators: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    torque_low: np.ndarray
    torque_high: np.ndarray
    suction: int
    suction_off: float
    suction_on: float
    belt_qpos: int
    belt_dof: int
    ray: int
    cup_body: int
    pad_geom: int
    eef_site: int
    eef_body: int
    box_body: np.ndarray
    box_geom: np.ndarray
    box_qpos: np.ndarray
    box_dof: np.ndarray
    box_weld: np.ndarray
    action_low: np.ndarray
    action_high: np.ndarray

    @property
    def n_joints(self) -> int:
        return len(self.arm_qpos)

    @property
    def pool_size(self) -> int:
        return len(self.box_body)

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return int(round(1.0 / (self.control_freq * self.model.opt.timestep)))

    @classmethod
    def from_env(cls, env) -> CellSpec:
        """The spec of a built (and reset) ``ColorSort`` env; copies its model."""
        model = copy_model(env.mj_model)
        env.plant.lights.apply(Lighting(), model)  # the cell's own lights: each world scales them (cell.py)
        robot = env.robots[0]
        arm = robot.part_controllers["right"]
        gripper = robot.part_controllers["right_gripper"]
        plant = env.plant
        pool = plant.pool
        for body, geom in zip(pool.body, pool.geom, strict=True):
            model.geom_contype[geom] = model.geom_conaffinity[geom] = 1
            model.body_contype[body] = model.body_conaffinity[body] = 1
            model.body_gravcomp[body] = 1.0
        qpos0 = env.mj_data.qpos.copy()
        qvel0 = np.zeros(model.nv)
        for i, qa in enumerate(pool.qpos):
            qpos0[qa : qa + 7] = (*air_park_position(i), 1.0, 0.0, 0.0, 0.0)
        qpos0[plant.belt.qpos] = 0.0
        arm_act = np.asarray(robot._ref_actuators_indexes_dict["right"], int)
        grip_act = int(robot._ref_actuators_indexes_dict["right_gripper"][0])
        return cls(
            model=model, qpos0=qpos0, qvel0=qvel0, layout=env.layout, config=env.config,
            control_freq=float(env.control_freq), servo_period=int(env._servo_period),
            arm_qpos=np.asarray(robot._ref_joint_pos_indexes, int),
            arm_dof=np.asarray(robot._ref_joint_vel_indexes, int),
            arm_actuators=arm_act, kp=np.asarray(arm.kp, float), kd=np.asarray(arm.kd, float),
            torque_low=env.mj_model.actuator_ctrlrange[arm_act, 0].copy(),
            torque_high=env.mj_model.actuator_ctrlrange[arm_act, 1].copy(),
            suction=grip_act, suction_off=float(np.ravel(gripper.actuator_min)[0]),
            suction_on=float(np.ravel(gripper.actuator_max)[0]),
            belt_qpos=int(plant.belt.qpos), belt_dof=int(plant.belt.qvel), ray=int(plant.belt.ray),
            cup_body=int(plant.seal.cup), pad_geom=int(plant.seal.pad),
            eef_site=int(robot.eef_site_id["right"]),
            eef_body=int(model.body(robot.robot_model.eef_name["right"]).id),
            box_body=np.asarray(pool.body, int), box_geom=np.asarray(pool.geom, int),
            box_qpos=np.asarray(pool.qpos, int),
            box_dof=np.asarray(pool.qvel, int), box_weld=np.asarray(plant.seal.welds, int),
            action_low=np.asarray(env.action_spec[0], float), action_high=np.asarray(env.action_spec[1], float),
        )

    def save(self, folder: str | Path) -> Path:
        """Write ``cell.mjb`` and ``cell.json`` into ``folder``; returns the folder."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        mujoco.mj_saveModel(self.model, str(folder / "cell.mjb"))
        fields: dict[str, Any] = {"layout": dataclasses.asdict(self.layout), "config": dataclasses.asdict(self.config)}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name not in ("model", "layout", "config"):
                fields[f.name] = value.tolist() if isinstance(value, np.ndarray) else value
        (folder / "cell.json").write_text(json.dumps(fields, indent=1))
        return folder

    @classmethod
    def load(cls, folder: str | Path) -> CellSpec:
        """The spec ``save`` wrote."""
        folder = Path(folder)
        raw: dict[str, Any] = json.loads((folder / "cell.json").read_text())
        model = mujoco.MjModel.from_binary_path(str(folder / "cell.mjb"))
        layout = CellLayout(**_tuples(raw.pop("layout")))
        config = TaskConfig(**_tuples(raw.pop("config")))
        values: dict[str, Any] = {k: np.asarray(v) if isinstance(v, list) else v for k, v in raw.items()}
        return cls(model=model, layout=layout, config=config, **values)


def _tuples(fields: dict[str, Any]) -> dict[str, Any]:
    """A dataclass's fields read back from JSON: its lists were tuples."""
    return {k: tuple(v) if isinstance(v, list) else v for k, v in fields.items()}


def copy_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A deep copy of a compiled model (through MuJoCo's binary format)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "m.mjb")
        mujoco.mj_saveModel(model, path)
        return mujoco.MjModel.from_binary_path(path)


def spec_for_variant(variant_name: str) -> CellSpec:
    """Build the CPU cell of a benchmark variant (robosuite) and read its spec."""
    from colorsort.envs.gym_env import ColorSortGymEnv

    env = ColorSortGymEnv(variant_name, cameras=(), render_mode=None)
    env.reset(seed=0)
    try:
        return CellSpec.from_env(env.env)
    finally:
        env.close()
