"""The ColorSort task: a robot sorts coloured boxes off a conveyor into the bins of their colour.

Spec sheet
----------
Action (8,) for the IRB 140: absolute joint position targets for the arm's six joints [rad],
    suction in [-1, 1] (> 0 is on), then belt pass in [-1, 1] (> 0 runs the belt even while
    the ray sensor sees a box: how a box with no bin is let through). Other
    ``controller_configs`` change the arm part as in robosuite; Panda has 7 joints, so 9.
    NaN or infinite elements raise ``ValueError`` (naming them) before anything moves. Finite
    values outside ``action_spec`` are clipped by robosuite's controller to its input range
    ([-7, 7] rad); a target beyond a joint's limit drives the joint to its limit and no further.
    Suction and belt pass act on their sign only: any positive value is on.
Observations: robosuite proprioception (``robot0_joint_pos``, ``robot0_eef_pos``, ...);
    ``box_detected``, ``belt_running`` and ``suction_sealed`` (the cup's vacuum switch) as 1.0
    or 0.0; with ``use_camera_obs`` the images
    ``scene_image``, ``sensor_image``, ``wrist_image`` (H, W, 3) uint8, right side up.
Belt: carries boxes toward the arm at ``belt_speed`` [m/s]; stops while the ray is blocked,
    unless the belt-pass command is on.
Spawner: a box from the pool every ``spawn_period`` [s] at the belt's upstream end, colour
    drawn from ``box_colors`` by the env's seeded generator, optional lateral and yaw jitter;
    waits while the pool is empty or the spawn point is occupied.
Events: ``env.events`` lists every box that left play (``BoxEvent``: time, serial, colour,
    outcome, bin), for harnesses that score per box.
Bins: a box resting inside a bin's walls is placed; at ``bin_capacity`` boxes the bin is
    emptied (its boxes go back to the pool) and logged.
Reward: +1 per box placed in the bin of its colour, -1 per box misplaced or dropped, times
    ``reward_scale``; ``reward_shaping=True`` adds a dense staged reward (reach the box, seal
    it, carry it toward its bin, hold or drop it over the bin: see ``staged_rewards``).
Success: ``boxes_to_sort`` boxes placed correctly, none misplaced or dropped.
Termination: success, failure (a box misplaced or dropped), or ``time_limit`` (the horizon).
Randomisation: only through ``seed`` (the env's own ``numpy.random.Generator``).
State: ``get_sim_state()`` returns everything that makes an instant replayable (MuJoCo state,
    boxes, seal, belt, clock, generator) as one float64 vector; ``set_sim_state`` restores it,
    after which stepping the same actions retraces the episode bit for bit.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from robosuite import macros
from robosuite.controllers import load_composite_controller_config
from robosuite.environments.manipulation.manipulation_env import ManipulationEnv
from robosuite.models.tasks import ManipulationTask
from robosuite.utils.mjcf_utils import new_element
from robosuite.utils.observables import Observable, sensor

from colorsort.config import BIN_COLORS, COLORS, GRIPPERS, ROBOT_BASES, ROBOT_HOMES, ROBOTS, CellLayout, TaskConfig, make_config
from colorsort.models.arena import ConveyorArena, park_position
from colorsort.paths import asset_path
from colorsort.rendering import check_gl
from colorsort.suction import VacuumSeal

logger = logging.getLogger("colorsort")

CAMERAS: tuple[str, ...] = ("scene", "sensor", "wrist")


def parse_cameras(text: str) -> tuple[str, ...]:
    """Camera names from a command line's comma-separated list; "none" (or nothing) for no cameras."""
    if text.strip() == "none":
        return ()
    return tuple(c.strip() for c in text.split(",") if c.strip())
WRIST_CAMERA_MJCF = "gripper0_right_wrist"  # robosuite prefixes the gripper's camera name
SETTLED_SPEED = 0.05  # [m/s] a box slower than this inside a bin counts as resting there
# The parts of MuJoCo's state that ColorSort changes while it runs (see ``get_sim_state``).
MJ_STATE_SPEC = (mujoco.mjtState.mjSTATE_FULLPHYSICS | mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_EQ_ACTIVE
                 | mujoco.mjtState.mjSTATE_MOCAP_POS | mujoco.mjtState.mjSTATE_MOCAP_QUAT
                 | mujoco.mjtState.mjSTATE_WARMSTART)


RNG_STATE_SIZE = 10  # a PCG64 generator's state and increment (4 x 32 bits each), then its uint32 buffer


def rng_to_words(rng: np.random.Generator) -> np.ndarray:
    """A PCG64 generator's full state as 32-bit words (exact in float64)."""
    st = rng.bit_generator.state
    if st["bit_generator"] != "PCG64":
        raise ValueError(f"Only PCG64 generators can be saved, not {st['bit_generator']}")
    words = [(v >> (32 * k)) & 0xFFFFFFFF for v in (st["state"]["state"], st["state"]["inc"]) for k in range(4)]
    return np.array(words + [st["has_uint32"], st["uinteger"]], dtype=np.float64)


def rng_from_words(words: np.ndarray) -> np.random.Generator:
    """The generator ``rng_to_words`` saved."""
    w = [int(x) for x in words]
    state, inc = (sum(w[i + k] << (32 * k) for k in range(4)) for i in (0, 4))
    gen = np.random.Generator(np.random.PCG64())
    gen.bit_generator.state = {"bit_generator": "PCG64", "state": {"state": state, "inc": inc},
                               "has_uint32": w[8], "uinteger": w[9]}
    return gen


def action_bounds(robot: str) -> tuple[np.ndarray, np.ndarray]:
    """``ColorSort(robots=robot).action_spec`` with the default controller, without building the env.

    Joint targets [rad] within the controller's input range, then suction and belt pass in [-1, 1].
    robosuite's controller clips joint targets to that range; the joints' own limits stop the arm
    short of a target beyond them.
    """
    if robot not in ROBOTS:
        raise ValueError(f"Unknown robot {robot!r}. Valid robots: {list(ROBOTS)}")
    arm = json.loads(Path(asset_path("controllers", "joint_position_absolute.json")).read_text())
    arm = arm["body_parts"]["arms"]["right"]
    n = len(ROBOT_HOMES[robot])
    low = np.concatenate([np.full(n, arm["input_min"], float), [-1.0, -1.0]])
    high = np.concatenate([np.full(n, arm["input_max"], float), [1.0, 1.0]])
    return low, high


class BoxStatus(Enum):
    PARKED = "parked"
    IN_PLAY = "in_play"
    PLACED = "placed"


@dataclass
class Box:
    """Bookkeeping for one pooled box."""

    index: int
    status: BoxStatus = BoxStatus.PARKED
    color: str = "red"
    bin: str | None = None
    serial: int = -1  # 0, 1, 2, ... in order of appearance this episode; -1 while parked


@dataclass(frozen=True)
class BoxEvent:
    """A box leaving play: ``outcome`` is "placed" (its colour's bin), "misplaced", "dropped" or "rejected"."""

    time: float  # [s] sim time
    serial: int
    color: str
    outcome: str
    bin: str | None


@dataclass
class Tally:
    """Episode counters reported in ``info``."""

    placed: dict[str, int] = field(default_factory=lambda: {c: 0 for c in BIN_COLORS})
    misplaced: int = 0
    dropped: int = 0
    rejected: int = 0
    spawned: int = 0
    bins_emptied: int = 0


class ColorSort(ManipulationEnv):
    """Conveyor colour sorting with a suction cup; see the module docstring for the spec sheet.

    Args:
        robots: "IRB140", "Panda" or "UR5e".
        preset: name of a ``TaskConfig`` preset ("default", "seed").
        config: a full ``TaskConfig``; overrides ``preset``.
        layout: the cell's geometry.
        camera_names: any of "scene", "sensor", "wrist".
        control_freq: policy rate [Hz].
        servo_freq: rate [Hz] at which the arm controller recomputes joint torques, held in
            between (a drive's servo period); a divisor of the 500 Hz physics rate.
        use_object_obs: add the ``next_box`` observation (``next_box_state``), part of robosuite's
            ``object-state`` (what ``GymWrapper`` feeds a policy by default).
        reward_scale: multiplies every reward (None: unscaled), as in robosuite's tasks.
        reward_shaping: add the dense staged reward (``staged_rewards``) to the sparse one.
        **overrides: ``TaskConfig`` fields, e.g. ``belt_speed=0.1``.
        Other arguments are robosuite's.
    """

    def __init__(
        self,
        robots: str | list[str] = "IRB140",
        preset: str = "default",
        config: TaskConfig | None = None,
        layout: CellLayout | None = None,
        env_configuration: str = "default",
        controller_configs: dict | None = None,
        gripper_types: str = "SuctionGripper",
        initialization_noise: dict | None = None,
        use_camera_obs: bool = False,
        use_object_obs: bool = True,
        has_renderer: bool = False,
        has_offscreen_renderer: bool = True,
        render_camera: str = "scene",
        render_collision_mesh: bool = False,
        render_visual_mesh: bool = True,
        render_gpu_device_id: int = -1,
        control_freq: float = 20,
        servo_freq: float = 100,
        lite_physics: bool = True,
        horizon: int | None = None,
        ignore_done: bool = False,
        hard_reset: bool = False,
        camera_names: str | list[str] = CAMERAS,
        camera_heights: int | list[int] = 128,
        camera_widths: int | list[int] = 128,
        camera_depths: bool | list[bool] = False,
        camera_segmentations: Any = None,
        renderer: str = "mjviewer",
        renderer_config: dict | None = None,
        seed: int | None = None,
        reward_scale: float | None = 1.0,
        reward_shaping: bool = False,
        **overrides: Any,
    ):
        robot_list = [robots] if isinstance(robots, str) else list(robots)
        if len(robot_list) != 1 or robot_list[0] not in ROBOTS:
            raise ValueError(f"ColorSort takes one robot; got {robots!r}. Valid robots: {list(ROBOTS)}")
        if gripper_types not in GRIPPERS:
            raise ValueError(f"Unknown gripper {gripper_types!r}. Valid grippers: {list(GRIPPERS)}")
        if gripper_types == "default" and robot_list[0] != "IRB140":
            raise ValueError(f"{robot_list[0]}'s default gripper cannot pick 0.1 m boxes; use 'SuctionGripper'")
        self.config = config if config is not None else make_config(preset, **overrides)
        if config is not None and overrides:
            raise ValueError("Pass either config or field overrides, not both")
        self.layout = layout or CellLayout()
        cams = [camera_names] if isinstance(camera_names, str) else list(camera_names)
        unknown = [c for c in cams if c not in CAMERAS]
        if unknown:
            raise ValueError(f"Unknown camera(s) {unknown}. Valid cameras: {list(CAMERAS)}")
        self._camera_aliases = {WRIST_CAMERA_MJCF: "wrist"}
        mjcf_cams = [WRIST_CAMERA_MJCF if c == "wrist" else c for c in cams]
        if render_camera == "wrist":
            render_camera = WRIST_CAMERA_MJCF
        if controller_configs is None:
            controller_configs = load_composite_controller_config(
                controller=asset_path("controllers", "joint_position_absolute.json")
            )
        if has_offscreen_renderer:
            check_gl()
        if horizon is None:
            horizon = int(np.ceil(self.config.time_limit * control_freq))

        physics_hz = 1.0 / macros.SIMULATION_TIMESTEP
        if servo_freq <= 0 or abs(physics_hz / servo_freq - round(physics_hz / servo_freq)) > 1e-9:
            raise ValueError(f"servo_freq={servo_freq} must divide the {physics_hz:.0f} Hz physics rate, e.g. 100, 250, 500")
        self._servo_period = int(round(physics_hz / servo_freq))  # physics steps per torque update
        self._substep = 0
        self._obs_dt = 0.0
        self.boxes = [Box(i) for i in range(self.config.pool_size)]
        self.tally = Tally()
        self.events: list[BoxEvent] = []
        self._next_serial = 0
        self.belt_running = True
        self.box_detected = False
        self.belt_pass = False
        self._arm_action = np.zeros(0)
        self._next_spawn_time = 0.0
        self._step_reward = 0.0
        self.reward_scale = reward_scale
        self.use_object_obs = bool(use_object_obs)
        self.reward_shaping = bool(reward_shaping)
        self.render_seconds = 0.0  # [s] wall time spent rendering camera observations, for benchmarks

        super().__init__(
            robots=robot_list,
            env_configuration=env_configuration,
            controller_configs=controller_configs,
            base_types="NullMount",
            gripper_types=gripper_types,
            initialization_noise=initialization_noise,
            use_camera_obs=use_camera_obs,
            has_renderer=has_renderer,
            has_offscreen_renderer=has_offscreen_renderer,
            render_camera=render_camera,
            render_collision_mesh=render_collision_mesh,
            render_visual_mesh=render_visual_mesh,
            render_gpu_device_id=render_gpu_device_id,
            control_freq=control_freq,
            lite_physics=lite_physics,
            horizon=horizon,
            ignore_done=ignore_done,
            hard_reset=hard_reset,
            camera_names=mjcf_cams,
            camera_heights=camera_heights,
            camera_widths=camera_widths,
            camera_depths=camera_depths,
            camera_segmentations=camera_segmentations,
            renderer=renderer,
            renderer_config=renderer_config,
            seed=seed,
        )
        # robosuite hides its visualisation sites (the gripper's green grip line) in reset(), not when
        # it builds the env: an env rendered before its first reset (a replay) would show them.
        self.visualize(vis_settings={vis: False for vis in self._visualizations})

    # ------------------------------------------------------------------ model
    def _load_model(self) -> None:
        super()._load_model()
        robot_model = self.robots[0].robot_model
        robot_model.set_base_xpos(ROBOT_BASES[self.robots[0].name])
        self.robots[0].init_qpos = np.array(ROBOT_HOMES[self.robots[0].name])
        arena = ConveyorArena(self.layout, self.config.pool_size, self.config.box_mass)
        arena.set_origin([0, 0, 0])
        self.model = ManipulationTask(mujoco_arena=arena, mujoco_robots=[robot_model])
        gripper = self.robots[0].gripper["right"]
        for name in arena.box_names:
            self.model.equality.append(
                new_element("weld", f"suction_{name}", body1=gripper.correct_naming("cup"), body2=name,
                            active="false", solref="0.01 1")
            )
        # robosuite's merge drops <custom>; keep the robot's (joint speed limits live there).
        custom = robot_model.root.find("custom")
        if custom is not None:
            self.model.root.append(custom)
        # No multisampling off screen: 3x faster on a CPU, and images stay crisp at 128 px.
        visual = self.model.root.find("visual")
        quality = visual.find("quality")
        if quality is None:
            quality = visual.makeelement("quality", {})
            visual.append(quality)
        quality.set("offsamples", "0")
        # A dim headlight without glare: MuJoCo's default (diffuse 0.4, specular 0.5) shines
        # straight down the sensor camera's axis and washes box colours out to pastel.
        headlight = visual.find("headlight")
        if headlight is None:
            headlight = visual.makeelement("headlight", {})
            visual.append(headlight)
        headlight.attrib.update(ambient="0.15 0.15 0.15", diffuse="0.15 0.15 0.15", specular="0 0 0")

    def _setup_references(self) -> None:
        super()._setup_references()
        m = self.sim.model
        self._data = self.sim.data._data  # raw MjData: no wrapper overhead on the per-step path
        self._belt_qpos = m.get_joint_qpos_addr("belt_slide")
        self._belt_qvel = m.get_joint_qvel_addr("belt_slide")
        self._ray_adr = m.sensor_adr[m.sensor_name2id("ray")]
        self._box_body = [m.body_name2id(f"box{i}") for i in range(self.config.pool_size)]
        self._box_geom = [m.geom_name2id(f"box{i}_geom") for i in range(self.config.pool_size)]
        self._box_qpos = [m.get_joint_qpos_addr(f"box{i}_joint")[0] for i in range(self.config.pool_size)]
        self._box_qvel = [m.get_joint_qvel_addr(f"box{i}_joint")[0] for i in range(self.config.pool_size)]
        gripper = self.robots[0].gripper["right"]
        names = [f"box{i}" for i in range(self.config.pool_size)]
        self.seal = VacuumSeal(
            m._model, self.sim.data._data, cup_body=gripper.correct_naming("cup"),
            pad_geom=gripper.correct_naming("cup_pad"), actuator=gripper.correct_naming("suction"),
            box_bodies=names, box_geoms=[f"{n}_geom" for n in names], welds=[f"suction_{n}" for n in names],
        )

    # ------------------------------------------------------------------ observations
    def _create_camera_sensors(self, cam_name, cam_w, cam_h, cam_d, cam_segs, modality="image"):
        """Camera sensors named by their ColorSort alias, images flipped right side up for OpenCV."""
        alias = self._camera_aliases.get(cam_name, cam_name)
        if cam_segs is not None:
            raise ValueError("ColorSort cameras do not provide segmentation")

        @sensor(modality=modality)
        def camera_rgb(obs_cache):
            if cam_d:
                rgb, depth = self.camera_image(alias, cam_w, cam_h, depth=True)
                obs_cache[f"{alias}_depth"] = depth
                return rgb
            return self.camera_image(alias, cam_w, cam_h)

        sensors, names = [camera_rgb], [f"{alias}_image"]
        if cam_d:

            @sensor(modality=modality)
            def camera_depth(obs_cache):
                return obs_cache.get(f"{alias}_depth", np.zeros((cam_h, cam_w, 1)))

            sensors.append(camera_depth)
            names.append(f"{alias}_depth")
        return sensors, names

    def _hide_rangefinder(self) -> None:
        # The rangefinder's drawn ray would show up in the cameras' images.
        self.sim._render_context_offscreen.vopt.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = 0

    def camera_image(self, camera: str, width: int, height: int, depth: bool = False):
        """Render camera ``camera`` ("scene", "sensor", "wrist") now: (H, W, 3) uint8 RGB, right side up.

        With ``depth``, also the depth image (H, W, 1) [m]. Time spent adds to ``render_seconds``.
        """
        if camera not in CAMERAS:
            raise ValueError(f"Unknown camera {camera!r}. Valid cameras: {list(CAMERAS)}")
        start = time.perf_counter()
        name = WRIST_CAMERA_MJCF if camera == "wrist" else camera
        if self.sim._render_context_offscreen is None:  # created by the first render
            self.sim.render(camera_name=name, width=width, height=height)
            self._hide_rangefinder()
        img = self.sim.render(camera_name=name, width=width, height=height, depth=depth)
        self.render_seconds += time.perf_counter() - start
        if depth:
            rgb, d = img
            return np.ascontiguousarray(rgb[::-1]), np.ascontiguousarray(d[::-1, :, None])
        return np.ascontiguousarray(img[::-1])

    def _setup_observables(self) -> dict[str, Observable]:
        observables = super()._setup_observables()

        @sensor(modality="object")
        def box_detected(obs_cache):
            return np.array([float(self.box_detected)])

        @sensor(modality="object")
        def belt_running(obs_cache):
            return np.array([float(self.belt_running)])

        @sensor(modality="object")
        def suction_sealed(obs_cache):
            return np.array([float(self.seal.held is not None)])

        sensors = [box_detected, belt_running, suction_sealed]
        if self.use_object_obs:

            @sensor(modality="object")
            def next_box(obs_cache):
                return self.next_box_state()

            sensors.append(next_box)
        for s in sensors:
            observables[s.__name__] = Observable(name=s.__name__, sensor=s, sampling_rate=self.control_freq)
        return observables

    # ------------------------------------------------------------------ reset
    def reset(self, seed: int | None = None):
        """Reset the episode; ``seed`` reseeds the env's generator first."""
        if seed is not None:
            self.seed = seed
            self.rng = np.random.default_rng(seed)
        return super().reset()

    def _reset_internal(self) -> None:
        super()._reset_internal()
        if self.has_offscreen_renderer and self.sim._render_context_offscreen is not None:
            self._hide_rangefinder()
        self.tally = Tally()
        self.events = []
        self._next_serial = 0
        for box in self.boxes:
            self._park(box)
        self.sim.data.qpos[self._belt_qpos] = 0.0
        self.sim.data.qvel[self._belt_qvel] = 0.0
        self.belt_running = True
        self.box_detected = False
        self.belt_pass = False
        self._next_spawn_time = 0.0
        self._step_reward = 0.0
        self._spawn_if_due()
        self.sim.forward()

    # ------------------------------------------------------------------ public handles
    @property
    def mj_model(self) -> mujoco.MjModel:
        """The compiled MuJoCo model (robosuite's ``sim.model`` wraps it)."""
        return self.sim.model._model

    @property
    def mj_data(self) -> mujoco.MjData:
        """The MuJoCo data (robosuite's ``sim.data`` wraps it)."""
        return self._data

    def observe(self) -> dict[str, Any]:
        """Sample every observation now (re-rendering the cameras), e.g. after lights changed."""
        return self._get_observations(force_update=True)

    def action_names(self) -> list[str]:
        """One name per action element: the arm joints' targets, then ``suction``, ``belt_pass``."""
        prefix = self.robots[0].robot_model.naming_prefix
        return [f"{j.removeprefix(prefix)}.target" for j in self.robots[0].robot_joints] + ["suction", "belt_pass"]

    # ------------------------------------------------------------------ physics step
    @property
    def action_dim(self) -> int:
        """The robot's action (arm controller, then suction) plus the belt-pass command."""
        return self._action_dim + 1

    @property
    def action_spec(self) -> tuple[np.ndarray, np.ndarray]:
        low, high = super().action_spec
        return np.append(low, -1.0), np.append(high, 1.0)

    def _pre_action(self, action, policy_step=False):
        if policy_step:
            action = np.asarray(action, dtype=float)
            if action.shape != (self.action_dim,):
                raise ValueError(f"Expected an action of shape ({self.action_dim},), got {action.shape}")
            bad = np.flatnonzero(~np.isfinite(action))
            if bad.size:
                names = self.action_names()
                raise ValueError("Action elements must be finite; got "
                                 + ", ".join(f"{names[i]} (index {i}) = {action[i]}" for i in bad))
            self._substep = 0
            self._arm_action = action[:-1]
            self.belt_pass = bool(action[-1] > 0.0)
        if self._substep % self._servo_period == 0:
            self.robots[0].control(self._arm_action, policy_step=policy_step)  # robosuite's controller writes ctrl
        self._substep += 1
        self._drive_belt()
        self.seal.update()

    def _update_observables(self, force: bool = False) -> None:
        """Sample every observable once per policy step, at its very end (see ``_post_action``).

        robosuite calls this after each physics step and samples at the start of each policy
        period, from kinematics one physics step old. ColorSort samples once, after the step's
        boxes were spawned or parked and the kinematics recomputed, so that an observation shows
        exactly the state ``get_sim_state`` returns (and a replay of that state re-renders it).
        Observable delays and corrupters are not used by the task.
        """
        self._obs_dt += self.model_timestep
        if force:
            self._sample_observables()

    def _sample_observables(self) -> None:
        for observable in self._observables.values():
            observable.update(timestep=self._obs_dt, obs_cache=self._obs_cache, force=True)
        self._obs_dt = 0.0

    def _drive_belt(self) -> None:
        """Run or stop the belt from the ray sensor (and the belt-pass command), once per physics step.

        The belt joint's velocity is the surface speed; its position is held at 0, so the
        belt never travels (see ``models/arena.py``).
        """
        d = self._data
        distance = d.sensordata[self._ray_adr]
        self.box_detected = bool(0.0 <= distance <= self.layout.sensor_range)
        self.belt_running = self.belt_pass or not self.box_detected
        d.qpos[self._belt_qpos] = 0.0
        d.qvel[self._belt_qvel] = -self.config.belt_speed if self.belt_running else 0.0

    def _post_action(self, action):
        self._step_reward = self._update_boxes()
        self._spawn_if_due()
        mujoco.mj_forward(self.sim.model._model, self._data)  # mj_step leaves kinematics a substep old
        self._sample_observables()
        reward, done, info = super()._post_action(action)
        info.update(self.task_info())
        failed = self.tally.misplaced > 0 or self.tally.dropped > 0
        if not self.ignore_done and (info["is_success"] or failed):
            self.done = done = True
        return reward, done, info

    def reward(self, action=None) -> float:
        """This step's reward, times ``reward_scale``.

        Sparse (the default): +1 per box placed in its colour's bin this step, -1 per box
        misplaced or dropped. With ``reward_shaping``, plus every step
        ``(boxes placed correctly so far + staged_rewards()["progress"]) / boxes_to_sort``:
        in [0, 1] until ``boxes_to_sort`` boxes are placed, rising through the stages of the
        box being sorted, and never falling when a box is placed (its share moves to the count).
        """
        reward = self._step_reward
        if self.reward_shaping:
            reward += (sum(self.tally.placed.values()) + self.staged_rewards()["progress"]) / self.config.boxes_to_sort
        return reward * self.reward_scale if self.reward_scale is not None else reward

    def staged_rewards(self) -> dict[str, float]:
        """Dense progress on the next box that has a bin (lowest serial in play), by stage.

        ``reach`` in [0, 0.25]: 0.25 (1 - tanh(10 d)), d [m] from the cup pad to the box's top face;
        ``seal``: 0.5 while the cup holds the box; ``carry`` in [0.5, 0.75] while it holds it:
        0.5 + 0.25 (1 - tanh(5 e)), e [m] the box's horizontal distance to its bin's centre;
        ``place``: 1 while the box, held or falling, is over the inside of its own bin.
        ``progress`` is the largest; all are 0 when no box with a bin is in play. Boxes with no
        bin (let through on the belt) earn nothing here.
        """
        stages = {"reach": 0.0, "seal": 0.0, "carry": 0.0, "place": 0.0}
        targets = [b for b in self.boxes_in_play() if b.color in BIN_COLORS]
        if targets:
            box = min(targets, key=lambda b: b.serial)
            L = self.layout
            x, y, z = self.box_pos(box)
            pad = self.sim.data.geom_xpos[self.seal.pad]
            stages["reach"] = 0.25 * (1 - np.tanh(10 * np.linalg.norm(pad - (x, y, z + L.box_size / 2))))
            held = self.seal.held == box.index
            if held:
                bx, by = L.bin_center(BIN_COLORS.index(box.color))
                stages["seal"] = 0.5
                stages["carry"] = 0.5 + 0.25 * (1 - np.tanh(5 * np.hypot(x - bx, y - by)))
            if self._bin_under(x, y) == box.color:
                stages["place"] = 1.0
        return {**{k: float(v) for k, v in stages.items()}, "progress": float(max(stages.values()))}

    def _check_success(self) -> bool:
        t = self.tally
        return sum(t.placed.values()) >= self.config.boxes_to_sort and t.misplaced == 0 and t.dropped == 0

    def task_info(self) -> dict[str, Any]:
        """The task's counters, as reported in ``info`` by ``step``."""
        t = self.tally
        bins = {
            color: [b.color == color for b in self.boxes if b.status is BoxStatus.PLACED and b.bin == color]
            for color in BIN_COLORS
        }
        return {
            "belt_running": self.belt_running,
            "box_detected": self.box_detected,
            "placed": dict(t.placed),
            "misplaced": t.misplaced,
            "dropped": t.dropped,
            "rejected": t.rejected,
            "bins_emptied": t.bins_emptied,
            "spawned": t.spawned,
            "bins": {c: {"count": len(m), "matches": m} for c, m in bins.items()},
            "suction_sealed": self.seal.held is not None,
            "is_success": self._check_success(),
        }

    # ------------------------------------------------------------------ state
    @property
    def sim_state_size(self) -> int:
        """Length of ``get_sim_state()``'s vector."""
        return mujoco.mj_stateSize(self.sim.model._model, MJ_STATE_SPEC) + 4 * len(self.boxes) + 1 + mujoco.mjNEQDATA + 5 + RNG_STATE_SIZE

    def get_sim_state(self) -> np.ndarray:
        """Everything that makes this instant replayable, as one float64 vector.

        MuJoCo's state (``MJ_STATE_SPEC``: time, qpos, qvel, controls, active equalities, mocap
        and the solver's warm start, so that stepping on from it is bit-exact), then per pooled
        box its colour (index in ``config.COLORS``, -1 while parked), status, bin (index in ``BIN_COLORS`` or -1)
        and serial, then the seal (held box or -1, its weld's ``eq_data``), then the belt-pass
        command, the belt and ray flags, the next spawn time [s], the next serial, the env's
        clock [s], and the env's random generator (PCG64, in 32-bit words). Applied forces (``qfrc_applied``, ``xfrc_applied``) are left out: ColorSort
        never sets them.
        """
        m, d = self.sim.model._model, self._data
        mj = np.empty(mujoco.mj_stateSize(m, MJ_STATE_SPEC))
        mujoco.mj_getState(m, d, mj, MJ_STATE_SPEC)
        colors, statuses = list(COLORS), list(BoxStatus)
        boxes = [(colors.index(b.color) if b.status is not BoxStatus.PARKED else -1, statuses.index(b.status),
                  BIN_COLORS.index(b.bin) if b.bin is not None else -1, b.serial) for b in self.boxes]
        held = self.seal.held if self.seal.held is not None else -1
        weld = m.eq_data[self.seal.welds[held]] if held >= 0 else np.zeros(mujoco.mjNEQDATA)
        tail = (float(self.belt_pass), float(self.belt_running), float(self._next_spawn_time),
                float(self._next_serial), float(self.cur_time))
        return np.concatenate([mj, np.ravel(boxes), [held], weld, tail, rng_to_words(self.rng)]).astype(np.float64)

    def set_sim_state(self, state: np.ndarray) -> None:
        """Restore an instant saved by ``get_sim_state`` (same robot, layout and pool size).

        The episode's counters and events are not part of the state: they keep counting from
        their current values.
        """
        state = np.asarray(state, dtype=np.float64)
        if state.shape != (self.sim_state_size,):
            raise ValueError(f"Expected a state of shape ({self.sim_state_size},), got {state.shape}: "
                             "was it saved with another robot or pool size?")
        m, d = self.sim.model._model, self._data
        n_mj = mujoco.mj_stateSize(m, MJ_STATE_SPEC)
        mujoco.mj_setState(m, d, state[:n_mj], MJ_STATE_SPEC)
        boxes = state[n_mj : n_mj + 4 * len(self.boxes)].reshape(-1, 4).astype(int)
        colors, statuses = list(COLORS), list(BoxStatus)
        for box, (color, status, bin_index, serial) in zip(self.boxes, boxes):
            box.status, box.serial = statuses[status], int(serial)
            box.bin = BIN_COLORS[bin_index] if bin_index >= 0 else None
            if color >= 0:  # a parked box's colour is whatever it last had: out of sight, not part of the state
                box.color = colors[color]
                m.geom_rgba[self._box_geom[box.index]] = COLORS[box.color]
            self._set_collidable(box, box.status is not BoxStatus.PARKED)
            m.body_gravcomp[self._box_body[box.index]] = float(box.status is BoxStatus.PARKED)
        rest = state[n_mj + 4 * len(self.boxes) :]
        held, weld, tail = int(rest[0]), rest[1 : 1 + mujoco.mjNEQDATA], rest[1 + mujoco.mjNEQDATA :]
        self.seal.held = held if held >= 0 else None
        if held >= 0:
            m.eq_data[self.seal.welds[held]] = weld
        self.belt_pass, self.belt_running = bool(tail[0]), bool(tail[1])
        self._next_spawn_time, self._next_serial, self.cur_time = float(tail[2]), int(tail[3]), float(tail[4])
        self.rng = rng_from_words(tail[5:])
        self.timestep = int(round(self.cur_time / self.control_timestep))
        mujoco.mj_forward(m, d)
        self.box_detected = bool(0.0 <= d.sensordata[self._ray_adr] <= self.layout.sensor_range)
        for controller in self.robots[0].part_controllers.values():
            controller.update(force=True)  # robosuite caches joint states and the mass matrix between steps

    # ------------------------------------------------------------------ boxes
    def next_box_state(self) -> np.ndarray:
        """The in-play box with the lowest serial: colour one-hot over ``config.COLORS``, pose (7,)
        (centre [m], quaternion w, x, y, z), then 1.0; zeros when no box is in play. Shape (len(COLORS) + 8,)."""
        boxes = self.boxes_in_play()
        out = np.zeros(len(COLORS) + 8, np.float32)
        if boxes:
            box = min(boxes, key=lambda b: b.serial)
            out[list(COLORS).index(box.color)] = 1.0
            out[len(COLORS) : len(COLORS) + 7] = self.box_pose(box)
            out[-1] = 1.0
        return out

    def box_pos(self, box: Box) -> np.ndarray:
        """World position of a box's centre [m]."""
        return self.sim.data.body_xpos[self._box_body[box.index]].copy()

    def box_pose(self, box: Box) -> np.ndarray:
        """A box's free-joint pose: centre [m] then quaternion (w, x, y, z), shape (7,)."""
        qa = self._box_qpos[box.index]
        return self.sim.data.qpos[qa : qa + 7].copy()

    def _update_boxes(self) -> float:
        """Classify boxes in play as placed, dropped or rejected; empty full bins. Returns the reward."""
        L = self.layout
        reward = 0.0
        half = L.box_size / 2
        for box in self.boxes:
            if box.status is not BoxStatus.IN_PLAY:
                continue
            x, y, z = self.box_pos(box)
            speed = np.linalg.norm(self.sim.data.qvel[self._box_qvel[box.index] : self._box_qvel[box.index] + 3])
            bin_color = self._bin_under(x, y)
            if bin_color is not None and z < L.bin_size[2] and speed < SETTLED_SPEED:
                box.status, box.bin = BoxStatus.PLACED, bin_color
                if box.color == bin_color:
                    self.tally.placed[bin_color] += 1
                    reward += 1.0
                else:
                    self.tally.misplaced += 1
                    reward -= 1.0
                outcome = "placed" if box.color == bin_color else "misplaced"
                self.events.append(BoxEvent(self.cur_time, box.serial, box.color, outcome, bin_color))
                logger.info("A %s box landed in the %s bin.", box.color, bin_color)
                self._empty_if_full(bin_color)
                continue
            on_floor = z < half + 0.02 and bin_color is None
            past_end = x < L.belt_end_x and abs(y - L.belt_y) < L.belt_width and z < L.belt_top_z + half
            if on_floor or past_end:
                if box.color in BIN_COLORS:
                    self.tally.dropped += 1
                    reward -= 1.0
                    logger.info("A %s box was dropped.", box.color)
                else:
                    self.tally.rejected += 1
                outcome = "dropped" if box.color in BIN_COLORS else "rejected"
                self.events.append(BoxEvent(self.cur_time, box.serial, box.color, outcome, None))
                self._park(box)
        return reward

    def _bin_under(self, x: float, y: float) -> str | None:
        """Colour of the bin whose inner footprint contains (x, y), or None."""
        L = self.layout
        inner_x = L.bin_size[0] / 2 - L.bin_wall
        inner_y = L.bin_size[1] / 2 - L.bin_wall
        for k, color in enumerate(BIN_COLORS):
            bx, by = L.bin_center(k)
            if abs(x - bx) < inner_x and abs(y - by) < inner_y:
                return color
        return None

    def _empty_if_full(self, bin_color: str) -> None:
        inside = [b for b in self.boxes if b.status is BoxStatus.PLACED and b.bin == bin_color]
        if len(inside) >= self.config.bin_capacity:
            logger.info("Emptying %s bin because it's full.", bin_color)
            for box in inside:
                self._park(box)
            self.tally.bins_emptied += 1

    def _park(self, box: Box) -> None:
        """Return a box to the pool: below the floor, collisions off, gravity compensated."""
        m, d = self.sim.model, self.sim.data
        self.seal.release(box.index)
        qa, va = self._box_qpos[box.index], self._box_qvel[box.index]
        d.qpos[qa : qa + 7] = (*park_position(box.index), 1.0, 0.0, 0.0, 0.0)
        d.qvel[va : va + 6] = 0.0
        self._set_collidable(box, False)
        m.body_gravcomp[self._box_body[box.index]] = 1.0
        box.status, box.bin, box.serial = BoxStatus.PARKED, None, -1

    def _set_collidable(self, box: Box, on: bool) -> None:
        # MuJoCo's broad phase also filters on the per-body OR of its geoms' bits: set both.
        m, flag = self.sim.model, int(on)
        for arr, idx in ((m.geom_contype, self._box_geom), (m.geom_conaffinity, self._box_geom),
                         (m.body_contype, self._box_body), (m.body_conaffinity, self._box_body)):
            arr[idx[box.index]] = flag

    def _spawn_if_due(self) -> None:
        """Put a pooled box at the belt's start if one is due, the pool has one and the spot is free."""
        if self.cur_time + 1e-9 < self._next_spawn_time:
            return
        parked = [b for b in self.boxes if b.status is BoxStatus.PARKED]
        if not parked or not self._spawn_point_clear():
            return  # wait: try again next step
        L, cfg = self.layout, self.config
        box = parked[0]
        color = str(self.rng.choice(cfg.box_colors))
        dy = self.rng.uniform(-cfg.lateral_jitter, cfg.lateral_jitter)
        yaw = np.deg2rad(self.rng.uniform(-cfg.yaw_jitter, cfg.yaw_jitter))
        self._place(box, color, L.spawn_x, L.belt_y + dy, yaw)
        self.tally.spawned += 1
        self._next_spawn_time = self.cur_time + cfg.spawn_period

    def put_box(self, color: str, x: float, y: float, yaw: float = 0.0) -> Box:
        """Take a box from the pool and set it down on the belt, centred at (x, y) [m], turned ``yaw`` [rad].

        For tests and benchmarks that need a box at a given place; the spawner does this in play.

        Raises:
            ValueError: unknown colour. RuntimeError: the pool is empty.
        """
        if color not in COLORS:
            raise ValueError(f"Unknown colour {color!r}. Valid colours: {sorted(COLORS)}")
        parked = [b for b in self.boxes if b.status is BoxStatus.PARKED]
        if not parked:
            raise RuntimeError(f"All {len(self.boxes)} boxes of the pool are in play")
        self._place(parked[0], color, x, y, yaw)
        self.sim.forward()
        return parked[0]

    def _place(self, box: Box, color: str, x: float, y: float, yaw: float) -> None:
        L = self.layout
        m, d = self.sim.model, self.sim.data
        qa, va = self._box_qpos[box.index], self._box_qvel[box.index]
        z = L.belt_top_z + L.box_size / 2 + 0.002
        d.qpos[qa : qa + 7] = (x, y, z, np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2))
        d.qvel[va : va + 6] = 0.0
        m.geom_rgba[self._box_geom[box.index]] = COLORS[color]
        self._set_collidable(box, True)
        m.body_gravcomp[self._box_body[box.index]] = 0.0
        box.color, box.status, box.bin = color, BoxStatus.IN_PLAY, None
        box.serial, self._next_serial = self._next_serial, self._next_serial + 1

    def _spawn_point_clear(self) -> bool:
        L = self.layout
        for box in self.boxes:
            if box.status is BoxStatus.IN_PLAY:
                x, y, _ = self.box_pos(box)
                if abs(x - L.spawn_x) < 1.5 * L.box_size and abs(y - L.belt_y) < L.belt_width:
                    return False
        return True

    def boxes_in_play(self) -> list[Box]:
        """Boxes currently on the belt, in the cup or in the air."""
        return [b for b in self.boxes if b.status is BoxStatus.IN_PLAY]
