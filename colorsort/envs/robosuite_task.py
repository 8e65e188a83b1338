"""The ColorSort task: a robot sorts coloured boxes off a conveyor into the bins of their colour.

Its specification (action, observations, ``info``, reward, success, bad actions, events, determinism,
configuration) is written once, in ``docs/task.md``. ``get_sim_state()`` returns everything that makes an instant
replayable as one float64 vector (layout: ``sim_state.py``); ``set_sim_state`` restores it, after which stepping
the same actions retraces the episode bit for bit.

This class is robosuite glue: the model, the observables, the step, the reward, and what the cell does not own
(the clock, the seeded generator, robosuite's controllers, held-out shifts); the cell itself is ``plant.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import mujoco
import numpy as np
from robosuite.controllers import load_composite_controller_config
from robosuite.environments.manipulation.manipulation_env import ManipulationEnv
from robosuite.models.tasks import ManipulationTask
from robosuite.utils.observables import Observable, sensor

from colorsort.cell import cameras
from colorsort.cell.boxes import Box
from colorsort.cell.conveyor import Placement
from colorsort.cell.models.arena import ConveyorArena
from colorsort.cell.plant import Grip, Plant
from colorsort.cell.referee import BoxEvent, Tally
from colorsort.cell.rendering import check_gl
from colorsort.cell.sim_state import CellState, SimStateLayout, rng_from_words, rng_to_words
from colorsort.cell.suction import add_welds
from colorsort.config import CellLayout, Lighting, TaskConfig, layout_for, make_config
from colorsort.envs.servo import Servo, servo_period
from colorsort.errors import ConfigError, checked_action
from colorsort.paths import asset_path
from colorsort.robots import ROBOTS, RobotSpec, checked_robot
from colorsort.shifts.episode import CellShifts


class ColorSort(ManipulationEnv):
    """Conveyor colour sorting with a suction cup; see the module docstring for the spec sheet.

    Args:
        robots: "IRB140", "Panda" or "UR5e".
        preset: name of a ``TaskConfig`` preset ("default", "seed").
        config: a full ``TaskConfig``; overrides ``preset``.
        layout: the cell's geometry.
        camera_names: any of "scene", "sensor", "wrist", "snapshot" (the sensor's photo taken when the
            ray last fired, held: ``snapshot.py``); by default the first three.
        control_freq: policy rate [Hz].
        servo_freq: rate [Hz] at which the arm controller recomputes joint torques, held in between (a drive's
            servo period); a divisor of the 500 Hz physics rate.
        use_object_obs: add the ``next_box`` observation (``Plant.next_box_state``), part of robosuite's
            ``object-state`` (what ``GymWrapper`` feeds a policy by default).
        reward_scale: multiplies every reward (None: unscaled), as in robosuite's tasks.
        reward_shaping: add the dense staged reward (``staged_rewards``) to the sparse one.
        shift: held-out shifts of every episode (docs/shifts.md), ``NAME:LEVEL`` texts, e.g. ``"camera-pose:2"``;
            ``env.shifts.record``: each episode's draws, for the evaluator (no policy reads it).
        **overrides: ``TaskConfig`` fields, e.g. ``belt_speed=0.1``.
        Other arguments are robosuite's.
    """

    plant: Plant  # the cell's parts, built with the model (``_setup_references``)
    sim: Any  # robosuite's MjSim; None once closed

    def __init__(
        self, robots: str | list[str] = "IRB140", preset: str = "default", config: TaskConfig | None = None,
        layout: CellLayout | None = None, env_configuration: str = "default",
        controller_configs: dict | None = None, gripper_types: str = "SuctionGripper",
        initialization_noise: dict | None = None, use_camera_obs: bool = False, use_object_obs: bool = True,
        has_renderer: bool = False, has_offscreen_renderer: bool = True, render_camera: str = "scene",
        render_collision_mesh: bool = False, render_visual_mesh: bool = True, render_gpu_device_id: int = -1,
        control_freq: float = 20, servo_freq: float = 100, lite_physics: bool = True, horizon: int | None = None,
        ignore_done: bool = False, hard_reset: bool = False,
        camera_names: str | list[str] | tuple[str, ...] = cameras.PHYSICAL_CAMERAS,
        camera_heights: int | list[int] = 128, camera_widths: int | list[int] = 128,
        camera_depths: bool | list[bool] = False, camera_segmentations: Any = None, renderer: str = "mjviewer",
        renderer_config: dict | None = None, seed: int | None = None, reward_scale: float | None = 1.0,
        reward_shaping: bool = False, shift: str | Iterable[str] | None = None, **overrides: Any,
    ):
        robot_list = [checked_robot(robots, gripper_types)]
        self.config = config if config is not None else make_config(preset, **overrides)
        if config is not None and overrides:
            raise ConfigError("Pass either config or field overrides, not both")
        self.layout = layout or layout_for(self.config)
        self.robot_spec: RobotSpec = ROBOTS[robot_list[0]]
        cams = [camera_names] if isinstance(camera_names, str) else list(camera_names)
        cameras.check_cameras(cams)
        if controller_configs is None:
            controller_configs = load_composite_controller_config(
                controller=asset_path("controllers", "joint_position_absolute.json")
            )
        if has_offscreen_renderer:
            check_gl()
        if horizon is None:
            horizon = int(np.ceil(self.config.time_limit * control_freq))

        self._servo_period = servo_period(servo_freq)  # physics steps per torque update
        self._substep = 0
        self._obs_dt = 0.0
        self._cameras = cameras.CameraRenderer()
        self._arm_action = np.zeros(0)
        self._step_reward = 0.0
        self.reward_scale = reward_scale
        self.use_object_obs = bool(use_object_obs)
        self.reward_shaping = bool(reward_shaping)
        self.shifts = CellShifts(shift)

        super().__init__(
            robots=robot_list, env_configuration=env_configuration, controller_configs=controller_configs,
            base_types="NullMount", gripper_types=gripper_types, initialization_noise=initialization_noise,
            use_camera_obs=use_camera_obs, has_renderer=has_renderer, has_offscreen_renderer=has_offscreen_renderer,
            render_camera=cameras.mjcf_name(render_camera), render_collision_mesh=render_collision_mesh,
            render_visual_mesh=render_visual_mesh, render_gpu_device_id=render_gpu_device_id,
            control_freq=control_freq, lite_physics=lite_physics, horizon=horizon, ignore_done=ignore_done,
            hard_reset=hard_reset, camera_names=[cameras.mjcf_name(c) for c in cams], camera_heights=camera_heights,
            camera_widths=camera_widths, camera_depths=camera_depths, camera_segmentations=camera_segmentations,
            renderer=renderer, renderer_config=renderer_config, seed=seed,
        )
        # robosuite hides its visualisation sites in reset(): an env rendered before its first reset would show them
        self.visualize(vis_settings={vis: False for vis in self._visualizations})

    def _load_model(self) -> None:
        super()._load_model()
        robot_model = self.robots[0].robot_model
        robot_model.set_base_xpos(self.robot_spec.base)
        self.robots[0].init_qpos = np.array(self.robot_spec.home)
        arena = ConveyorArena(self.layout, self.config.pool_size, self.config.box_mass)
        arena.set_origin([0, 0, 0])
        self.model = ManipulationTask(mujoco_arena=arena, mujoco_robots=[robot_model])
        add_welds(self.model, self.robots[0].gripper["right"].correct_naming("cup"), arena.box_names)
        # robosuite's merge drops <custom>; keep the robot's (joint speed limits live there).
        custom = robot_model.root.find("custom")
        if custom is not None:
            self.model.root.append(custom)
        cameras.tune_visual(self.model.root)

    def _setup_references(self) -> None:
        super()._setup_references()  # robosuite calls this on every reset: the plant lives as long as its model
        self._servo = Servo(self.robots[0])
        if getattr(self, "plant", None) is None or self.plant.model is not self.mj_model:
            gripper = self.robots[0].gripper["right"]
            self.plant = Plant(self.mj_model, self.mj_data, self.layout, self.config, cup=gripper.correct_naming("cup"),
                               pad=gripper.correct_naming("cup_pad"), suction=gripper.correct_naming("suction"))

    @property
    def mj_model(self) -> mujoco.MjModel:
        """The compiled MuJoCo model (robosuite's ``sim.model`` wraps it)."""
        return self.sim.model._model

    @property
    def mj_data(self) -> mujoco.MjData:
        """The MuJoCo data (robosuite's ``sim.data`` wraps it)."""
        return self.sim.data._data

    @property
    def boxes(self) -> list[Box]:
        """Every pooled box, in pool order."""
        return self.plant.pool.boxes

    def boxes_in_play(self) -> list[Box]:
        """Boxes on the belt, in the cup or in the air."""
        return self.plant.pool.in_play()

    def box_pos(self, box: Box) -> np.ndarray:
        """World position of a box's centre [m]."""
        return self.plant.pool.pos(box)

    def put_box(self, color: str, x: float, y: float, yaw: float = 0.0) -> Box:
        """Set a box from the pool down on the belt at (x, y) [m], turned ``yaw`` [rad] (tests, benchmarks; the
        spawner does this in play). ValueError: unknown colour; RuntimeError: the pool is empty."""
        box = self.plant.put_box(color, x, y, yaw)
        self.sim.forward()
        return box

    def remove_box(self, box: Box) -> None:
        """Return a box to the pool at once (the cup lets go of it first); no outcome is recorded."""
        self.plant.remove_box(box)

    @property
    def box_detected(self) -> bool:
        """The ray sensor sees a box."""
        return self.plant.belt.box_detected

    @property
    def belt_running(self) -> bool:
        return self.plant.belt.running

    @property
    def suction_sealed(self) -> bool:
        """The cup's vacuum switch: a box is sealed to the cup."""
        return self.plant.seal.held is not None

    @property
    def events(self) -> list[BoxEvent]:
        """Every box that left play this episode, in order (``referee.BoxEvent``)."""
        return self.plant.referee.events

    @property
    def placements(self) -> list[Placement]:
        """Every box set down on the belt this episode, in order: serial, colour, offset, yaw (``Placement``)."""
        return self.plant.spawner.placed

    @property
    def grips(self) -> list[Grip]:
        """Every seal this episode, in order: which box, how far off the cup's axis, how turned (``Grip``)."""
        return self.plant.grips

    @property
    def tally(self) -> Tally:
        """This episode's counters (``referee.Tally``)."""
        return self.plant.referee.tally

    @property
    def render_seconds(self) -> float:
        """[s] wall time spent rendering camera images, for benchmarks."""
        return self._cameras.seconds

    def observe(self) -> dict[str, Any]:
        """Sample every observation now (re-rendering the cameras), e.g. after lights changed."""
        return self._get_observations(force_update=True)

    def action_names(self) -> list[str]:
        """One name per action element: the arm joints' targets, then ``suction``, ``belt_pass``."""
        prefix = self.robots[0].robot_model.naming_prefix
        return [f"{j.removeprefix(prefix)}.target" for j in self.robots[0].robot_joints] + ["suction", "belt_pass"]

    def _create_camera_sensors(self, cam_name, cam_w, cam_h, cam_d, cam_segs, modality="image"):
        """Camera sensors named by their ColorSort alias, images flipped right side up for OpenCV."""
        if cam_segs is not None:
            raise ConfigError("ColorSort cameras do not provide segmentation")
        return cameras.camera_sensors(self.camera_image, cam_name, cam_w, cam_h, cam_d, modality)

    def camera_image(self, camera: str, width: int, height: int, depth: bool = False):
        """Render camera ``camera`` ("scene", "sensor", "wrist") now: (H, W, 3) uint8 RGB, right side up;
        "snapshot" gives the sensor's photo held since the ray last fired (``snapshot.py``).

        With ``depth``, also the depth image (H, W, 1) [m]. Time spent adds to ``render_seconds``.
        """
        return self._cameras.image(self.sim, camera, width, height, depth)

    def _setup_observables(self) -> dict[str, Observable]:
        observables = super()._setup_observables()

        flags = {"box_detected": lambda: self.box_detected, "belt_running": lambda: self.belt_running,
                 "suction_sealed": lambda: self.suction_sealed, "belt_travel": lambda: self.plant.belt.travel}
        sensors = [sensor(modality="object")(_named(name, lambda cache, f=f: np.array([float(f())])))
                   for name, f in flags.items()]
        if self.use_object_obs:
            sensors.append(sensor(modality="object")(_named("next_box", lambda cache: self.plant.next_box_state())))
        for s in sensors:
            observables[s.__name__] = Observable(name=s.__name__, sensor=s, sampling_rate=self.control_freq)
        return observables

    def _destroy_sim(self) -> None:
        """robosuite's, less its full ``gc.collect()`` (0.23 s a close, torch and LeRobot loaded): ``free_context``."""
        if self.sim is not None:
            cameras.free_context(self.sim)
            self.sim = None

    def reset(self, seed: int | None = None, lighting: Callable[[np.random.Generator], Lighting] | None = None):
        """Reset; ``seed`` reseeds the env's generator first, ``lighting`` then draws the episode's lights from it."""
        if seed is not None:
            self.seed, self.rng = seed, np.random.default_rng(seed)
        obs = super().reset()
        if lighting is not None:
            before = self.plant.lighting
            self.plant.set_lighting(lighting(self.rng))
            if self.use_camera_obs and self.plant.lighting != before:
                obs = self.observe()  # re-render under the new lights
        return obs

    def set_shift(self, shift: str | Iterable[str] | None) -> None:
        """Held-out shifts from the next reset on (``shift`` as the constructor's); the cell is put back as built."""
        self.shifts.undo(self)
        self.shifts, self._cameras.effect = CellShifts(shift), None

    def _reset_internal(self) -> None:
        super()._reset_internal()
        if self.has_offscreen_renderer:
            self._cameras.hide_rangefinder(self.sim)
        if self.shifts:  # after robosuite placed the arm, before the first box: draws nothing from self.rng
            self._cameras.effect = self.shifts.begin(self).image
        self.plant.reset(self.cur_time, self.rng)
        self._cameras.snapshot.clear()
        self._step_reward = 0.0
        self.sim.forward()

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
            action = self.shifts.action(checked_action(action, self.action_dim, self.action_names))
            self._substep = 0
            self._arm_action = action[:-1]
            self.plant.belt.belt_pass = bool(action[-1] > 0.0)
        if self._substep % self._servo_period == 0:  # robosuite's controller, or between policy steps its torque law
            self._servo.control(self._arm_action, policy_step)  # writes ctrl (servo.py)
        self._substep += 1
        self.plant.physics_step()

    def _update_observables(self, force: bool = False) -> None:
        """Sample every observable once per policy step, at its very end (``_post_action``), not as robosuite does
        at the start of each period from kinematics a physics step old: an observation shows exactly the state
        ``get_sim_state`` returns (and a replay re-renders it). The task uses no observable delays or corrupters."""
        self._obs_dt += self.model_timestep
        if force:
            self._sample_observables()

    def _sample_observables(self) -> None:
        if self.has_offscreen_renderer:  # before the cameras: a snapshot taken now shows in this observation
            self._cameras.observe_ray(self.sim, self.box_detected)
        for observable in self._observables.values():
            observable.update(timestep=self._obs_dt, obs_cache=self._obs_cache, force=True)
        self._obs_dt = 0.0

    def _post_action(self, action):
        self._step_reward = self.plant.control_step(self.cur_time, self.rng)
        mujoco.mj_forward(self.mj_model, self.mj_data)  # mj_step leaves kinematics a substep old
        self._sample_observables()
        reward, done, info = super()._post_action(action)
        info.update(self.task_info())
        if not self.ignore_done and (info["is_success"] or self.tally.failed):
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
        """Dense progress on the next box that has a bin, by stage (``Referee.staged_rewards``)."""
        return self.plant.staged_rewards()

    def _check_success(self) -> bool:
        return self.tally.success(self.config.boxes_to_sort)

    def task_info(self) -> dict[str, Any]:
        """The task's counters, as reported in ``info`` by ``step``."""
        return self.plant.info(self.config.boxes_to_sort)

    @property
    def sim_state_layout(self) -> SimStateLayout:
        """Where each part of ``get_sim_state()``'s vector lies (``sim_state.py``)."""
        return SimStateLayout.of(self.mj_model, len(self.boxes))

    @property
    def sim_state_size(self) -> int:
        """Length of ``get_sim_state()``'s vector."""
        return self.sim_state_layout.size

    def get_sim_state(self) -> np.ndarray:
        """Everything that makes this instant replayable, as one float64 vector (``sim_state.py``)."""
        state = CellState(self.plant.get_state(), self.cur_time, rng_to_words(self.rng))
        return state.pack(self.sim_state_layout)

    def set_sim_state(self, state: np.ndarray) -> None:
        """Restore an instant saved by ``get_sim_state`` (same robot, layout and pool size); the episode's
        counters and events are not part of the state: they keep counting from their current values."""
        s = CellState.unpack(state, self.sim_state_layout)
        self.plant.set_state(s.plant)
        self.cur_time, self.rng = s.clock, rng_from_words(s.rng)
        self.timestep = int(round(self.cur_time / self.control_timestep))
        for controller in self.robots[0].part_controllers.values():
            controller.update(force=True)  # robosuite caches joint states and the mass matrix between steps


def _named(name: str, fn: Callable) -> Callable:
    fn.__name__ = name  # robosuite names an observable after its sensor function
    return fn
