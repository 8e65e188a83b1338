"""N worlds of the ColorSort cell on MuJoCo Warp, stepped together on one device.

The model is the CPU cell's, compiled by robosuite on the host (``spec.CellSpec``); the rules are
``kernels.py``'s twins of the CPU cell's parts; each world's boxes come from its seed
(``schedule.episode_draws``). A control step is what ``ColorSort.step`` does: for each of its physics
steps, MuJoCo's first half-step (``step1``), the joint servo at its own rate, the suction valve, the
belt and the seal, then the second half-step (``step2``); then the referee, the spawner, a forward pass
and the observations. The whole control step is captured once as a graph (a CUDA graph on a GPU, Warp's CPU
graph on its CPU device) and launched per step: without it, Python's launch of each of the step's thousands of
kernels costs more than the kernels do.

Each world's scene lights follow its episode's ``Lighting`` (``lighting.LightRig``); the headlight is the
same in every world (Warp's renderer compiles it in), at the cell's own dim setting.

Observations and actions are torch tensors on the cell's device (``observation.state`` and
``observation.environment_state``, as the LeRobot datasets name them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp

from colorsort.batched import arrays as A
from colorsort.batched import kernels as K
from colorsort.batched.cameras import BatchedCameras, warp_matids
from colorsort.batched.observe import observation_layout, observe
from colorsort.batched.schedule import episode_draws
from colorsort.batched.spec import CellSpec, air_park_position, copy_model
from colorsort.cell.observation import BOX_STATE, StateLayout
from colorsort.cell.referee import SETTLED_SPEED
from colorsort.cell.suction import SEAL_ANGLE_DEG
from colorsort.config import COLORS, CellLayout
from colorsort.errors import ActionError, ConfigError
from colorsort.variants import Variant

CONTACTS_PER_WORLD = 48  # the cell has about 13 contacts with a box in the cup; room for a pile in a bin
CONSTRAINTS_PER_WORLD = 256


@dataclass(frozen=True)
class StepResult:
    """What a control step returns, one row per world: torch tensors on the cell's device that view the cell's
    buffers (the next step or reset overwrites them: clone what you keep)."""

    state: Any  # torch (N, state size) float32: observation.state
    env_state: Any  # torch (N, 13) float32: observation.environment_state
    reward: Any  # torch (N,) float32: the sparse reward of the step
    images: dict  # camera -> (N, H, W, 3) uint8 RGB, right side up; empty without cameras


def layout_struct(L: CellLayout) -> K.Layout:
    """The cell's geometry and the referee's threshold as the kernels take them."""
    lay = K.Layout()
    lay.belt_end_x, lay.belt_y, lay.belt_width, lay.belt_top_z = L.belt_end_x, L.belt_y, L.belt_width, L.belt_top_z
    lay.box_size, lay.spawn_x = L.box_size, L.spawn_x
    lay.sensor_range = float(L.sensor_range)
    lay.bin_x, lay.bin_y0, lay.bin_spacing = L.bin_x, L.bin_y0, L.bin_spacing
    lay.bin_half_x, lay.bin_half_y = L.bin_size[0] / 2 - L.bin_wall, L.bin_size[1] / 2 - L.bin_wall
    lay.bin_height, lay.settled_speed = L.bin_size[2], SETTLED_SPEED
    return lay


def check_device(device: str) -> None:
    """ConfigError, in one line, unless Warp can run on ``device``: "cpu", or "cuda"/"cuda:N" with that GPU visible
    (without one, torch's and Warp's own errors speak of drivers, not of the flag)."""
    if device == "cpu":
        return
    if device != "cuda" and not (device.startswith("cuda:") and device[5:].isdigit()):
        raise ConfigError(f"device {device!r}: give cpu (Warp's CPU device) or cuda:N (a GPU)")
    index = int(device[5:]) if device.startswith("cuda:") else 0
    visible = wp.get_cuda_device_count()
    if index >= visible:
        seen = f"{visible} CUDA device{'s' * (visible != 1)} visible" if visible else "no CUDA device is visible"
        raise ConfigError(f"--device {device}: {seen} to Warp on this machine; --device cpu runs Warp's CPU device "
                          "(the same cell, slower)")


class BatchedCell:
    """``worlds`` copies of one variant's cell on a Warp device ("cpu" or "cuda:0").

    Args:
        spec: the cell (``CellSpec.from_env`` or ``CellSpec.load``).
        variant: the benchmark variant the spec was built for (its draws and boxes).
        worlds: how many cells step together.
        device: Warp's device name.
        max_boxes: boxes per episode whose draws are prepared and whose events are kept.
        cameras: cameras rendered into every observation (``cameras.BatchedCameras``); none by default.
        image_size: their (height, width) [px].
        use_graph: capture the control step as one graph (CUDA's, or Warp's on its CPU device), launched per
            step; False launches every kernel from Python each step.
    """

    def __init__(self, spec: CellSpec, variant: Variant, worlds: int, device: str = "cpu", max_boxes: int = 64,
                 cameras: tuple[str, ...] = (), image_size: tuple[int, int] = (64, 64), use_graph: bool = True):
        import torch

        self.spec, self.variant, self.worlds, self.max_boxes = spec, variant, worlds, max_boxes
        check_device(device)
        self.device = wp.get_device(device)
        self.torch_device = torch.device("cpu" if self.device.is_cpu else f"cuda:{self.device.ordinal}")
        m = copy_model(spec.model)
        m.geom_matid[:] = warp_matids(m)  # colours where Warp's renderer reads them (``cameras.py``)
        self.substeps = spec.substeps
        self.control_dt = 1.0 / spec.control_freq
        self.layout = layout_struct(spec.layout)
        with wp.ScopedDevice(self.device):
            self._put_model(m, worlds)
            self._index_arrays(m)
            self._world_arrays(m, worlds)
            self.pool, self.boxes, self.bodies, self.event_log, self.draws = self._structs()
            self.controls, self.rig = self._drives()
            self.cameras = BatchedCameras(m, worlds, tuple(cameras), image_size) if cameras else None
        self.images: dict = {}
        self._graph = None
        self.use_graph = use_graph
        self.seeds = np.full(worlds, -1, np.int64)

    def _put_model(self, m: mujoco.MjModel, n: int) -> None:
        """MuJoCo Warp's model and data of ``n`` worlds, reset to the spec's state; the model fields the cell changes
        per world (welds, gravity compensation, colours, lights) given one row per world."""
        import torch

        data0 = mujoco.MjData(m)
        data0.qpos[:] = self.spec.qpos0
        mujoco.mj_forward(m, data0)
        self.m = mjw.put_model(m)
        self.d = mjw.put_data(m, data0, nworld=n, nconmax=CONTACTS_PER_WORLD, njmax=CONSTRAINTS_PER_WORLD)
        self.m.eq_data = wp.array(np.repeat(m.eq_data[None].astype(np.float32), n, 0), dtype=K.vec11)
        self.m.body_gravcomp = wp.array(np.repeat(m.body_gravcomp[None].astype(np.float32), n, 0), dtype=float)
        self.m.geom_rgba = wp.array(np.repeat(m.geom_rgba[None].astype(np.float32), n, 0), dtype=wp.vec4)
        self._lights: dict[str, Any] = {}  # the scene lights as built; a world's scaled by its episode's lights
        for name in ("light_diffuse", "light_ambient", "light_specular"):
            base = getattr(m, name).astype(np.float32)
            setattr(self.m, name, wp.array(np.repeat(base[None], n, 0), dtype=wp.vec3))
            self._lights[name] = torch.as_tensor(base, device=self.torch_device)

    def _index_arrays(self, m: mujoco.MjModel) -> None:
        """The spec's addresses (the arm's joints and actuators, the boxes' bodies, geoms, joints and welds), its
        gains and torque limits, where parked boxes wait and the palette: the same for every world."""
        s, P = self.spec, self.spec.pool_size
        i32 = lambda a: wp.array(np.asarray(a, np.int32), dtype=int)  # noqa: E731
        f32 = lambda a: wp.array(np.asarray(a, np.float32), dtype=float)  # noqa: E731
        self.arm_qpos, self.arm_dof, self.arm_act = i32(s.arm_qpos), i32(s.arm_dof), i32(s.arm_actuators)
        self.kp, self.kd, self.t_low, self.t_high = f32(s.kp), f32(s.kd), f32(s.torque_low), f32(s.torque_high)
        self.box_body, self.box_geom, self.box_qpos = i32(s.box_body), i32(s.box_geom), i32(s.box_qpos)
        self.box_dof, self.box_weld = i32(s.box_dof), i32(s.box_weld)
        of_geom = np.full(m.ngeom, -1, np.int32)
        of_geom[s.box_geom] = np.arange(P)
        self.box_of_geom = i32(of_geom)
        self.park_pos = wp.array(np.array([air_park_position(i) for i in range(P)], np.float32), dtype=wp.vec3)
        self.palette = wp.array(np.array(list(COLORS.values()), np.float32), dtype=wp.vec4)

    def _world_arrays(self, m: mujoco.MjModel, n: int) -> None:
        """Each world's state beyond MuJoCo's: commands, belt, boxes, events, draws, observations, one row a world."""
        s, P, E = self.spec, self.spec.pool_size, self.max_boxes
        zi = lambda *shape: wp.zeros(shape, dtype=int)  # noqa: E731
        self.qpos0 = wp.array(np.repeat(s.qpos0[None].astype(np.float32), n, 0), dtype=float)
        self.goal = wp.zeros((n, s.n_joints), dtype=float)
        self.suction_cmd, self.belt_pass, self.held = zi(n), zi(n), wp.full(n, -1, dtype=int)
        self.detected, self.running = zi(n), wp.ones(n, dtype=int)
        self.travel = wp.zeros(n, dtype=wp.float64)
        self.candidate = wp.full(n, P, dtype=int)
        self.vec = wp.zeros((n, m.nv), dtype=float)
        self.res = wp.zeros((n, m.nv), dtype=float)
        self.status, self.color = zi(n, P), zi(n, P)
        self.bin_of, self.serial = wp.full((n, P), -1, dtype=int), wp.full((n, P), -1, dtype=int)
        self.now, self.next_time = wp.zeros(n, dtype=wp.float64), wp.zeros(n, dtype=wp.float64)
        self.steps, self.next_serial, self.spawned, self.bins_emptied = zi(n), zi(n), zi(n), zi(n)
        self.n_events = zi(n)
        self.ev_time = wp.zeros((n, E), dtype=wp.float64)
        self.ev_serial, self.ev_color, self.ev_outcome, self.ev_bin = zi(n, E), zi(n, E), zi(n, E), zi(n, E)
        self.grips = wp.full((n, E, 2), float("nan"), dtype=float)
        self.draw_color = zi(n, E)
        self.draw_offset, self.draw_yaw = wp.zeros((n, E), dtype=float), wp.zeros((n, E), dtype=float)
        self.reward = wp.zeros(n, dtype=float)
        self.action = wp.zeros((n, s.n_joints + 2), dtype=float)
        state_layout = StateLayout(s.n_joints, s.config.tracking)
        self.observation_layout = observation_layout(state_layout, BOX_STATE)
        self.state = wp.zeros((n, state_layout.size), dtype=float)
        self.env_state = wp.zeros((n, BOX_STATE.size), dtype=float)

    def _structs(self) -> tuple[A.Pool, A.Boxes, A.Bodies, A.Events, A.Draws]:
        """The per-box and per-world arrays grouped as the kernels take them (each holds the arrays above, which are
        written in place, never replaced: a captured graph keeps their addresses)."""
        pool, boxes, bodies, events, draws = A.Pool(), A.Boxes(), A.Bodies(), A.Events(), A.Draws()
        pool.size, pool.qpos, pool.dof, pool.body = self.spec.pool_size, self.box_qpos, self.box_dof, self.box_body
        pool.geom, pool.weld, pool.park = self.box_geom, self.box_weld, self.park_pos
        boxes.status, boxes.color, boxes.bin, boxes.serial = self.status, self.color, self.bin_of, self.serial
        bodies.xpos, bodies.qpos, bodies.qvel = self.d.xpos, self.d.qpos, self.d.qvel
        bodies.gravcomp, bodies.eq_active = self.m.body_gravcomp, self.d.eq_active
        events.count, events.time, events.serial = self.n_events, self.ev_time, self.ev_serial
        events.color, events.outcome, events.bin = self.ev_color, self.ev_outcome, self.ev_bin
        draws.color, draws.offset, draws.yaw = self.draw_color, self.draw_offset, self.draw_yaw
        return pool, boxes, bodies, events, draws

    def _drives(self) -> tuple[A.Controls, A.Rig]:
        """Every world's commands and reports (the arrays above, in place), and the cell's drives as constants."""
        s, io, rig = self.spec, A.Controls(), A.Rig()
        io.suction_cmd, io.belt_pass, io.held = self.suction_cmd, self.belt_pass, self.held
        io.detected, io.running, io.travel = self.detected, self.running, self.travel
        rig.ray, rig.tracking, rig.speed = int(s.ray), int(s.config.tracking), float(s.config.belt_speed)
        rig.dt, rig.suction = float(s.model.opt.timestep), int(s.suction)
        rig.suction_off, rig.suction_on = float(s.suction_off), float(s.suction_on)
        rig.belt_qpos, rig.belt_dof = int(s.belt_qpos), int(s.belt_dof)
        return io, rig

    # ------------------------------------------------------------------ episodes
    def reset(self, seeds: list[int] | np.ndarray, worlds: np.ndarray | None = None) -> StepResult:
        """Start the episodes of ``seeds`` in ``worlds`` (default: all, in order); the other worlds run on.

        Each world restarts as the CPU cell does: the arm at home, every box parked, the belt running,
        counters cleared, and its first box spawned at time 0 from its seed's draws.
        """
        import torch

        idx = np.arange(self.worlds) if worlds is None else np.asarray(worlds, int)
        seeds = np.asarray(seeds, np.int64)
        if len(seeds) != len(idx):
            raise ConfigError(f"{len(seeds)} seeds for {len(idx)} worlds")
        self.seeds[idx] = seeds
        t = {name: wp.to_torch(getattr(self, name)) for name in (
            "status", "color", "bin_of", "serial", "now", "next_time", "steps", "next_serial", "spawned",
            "bins_emptied", "n_events", "held", "suction_cmd", "belt_pass", "travel", "running", "detected",
            "draw_color", "draw_offset", "draw_yaw", "grips", "goal")}
        colors, offsets, yaws = (np.zeros((len(idx), self.max_boxes), dt) for dt in (np.int32, np.float32, np.float32))
        light_scale = np.ones((len(idx), 3), np.float32)
        for row, seed in enumerate(seeds):
            draws = episode_draws(self.variant, int(seed), self.max_boxes)
            colors[row], offsets[row], yaws[row] = draws.color, draws.offset, draws.yaw
            light_scale[row] = draws.lighting.brightness * np.asarray(draws.lighting.tint)
        dev = self.torch_device
        at = torch.as_tensor(idx, device=dev)
        t["draw_color"][at] = torch.as_tensor(colors, device=dev)
        t["draw_offset"][at] = torch.as_tensor(offsets, device=dev)
        t["draw_yaw"][at] = torch.as_tensor(yaws, device=dev)
        for name in ("status", "color", "now", "next_time", "steps", "next_serial", "spawned", "bins_emptied",
                     "n_events", "suction_cmd", "belt_pass", "travel", "detected"):
            t[name][at] = 0
        for name in ("bin_of", "serial", "held"):
            t[name][at] = -1
        t["running"][at] = 1
        t["grips"][at] = float("nan")
        mask = np.zeros(self.worlds, bool)
        mask[idx] = True
        self._sync()
        with wp.ScopedDevice(self.device):
            wmask = wp.array(mask, dtype=bool)
            mjw.reset_data(self.m, self.d, reset=wmask)
            q, q0 = wp.to_torch(self.d.qpos), wp.to_torch(self.qpos0)
            q[at] = q0[at]
            wp.to_torch(self.d.eq_active)[at] = False
            scale = torch.as_tensor(light_scale, device=dev)[:, None, :]  # lighting.LightRig.apply, per world
            for name, base in self._lights.items():
                wp.to_torch(getattr(self.m, name))[at] = base[None] * scale
            gc = wp.to_torch(self.m.body_gravcomp)
            gc[at[:, None], torch.as_tensor(self.spec.box_body, device=dev)[None]] = 1.0
            t["goal"][at] = torch.as_tensor(self.spec.qpos0[self.spec.arm_qpos], dtype=torch.float32, device=dev)
            self._sync()
            self._launch_spawn()
            mjw.forward(self.m, self.d)
            self._launch_observe()
            self._sync()
            if self.cameras is not None:
                self.cameras.clear(at)
                self._render()
        return self._result()

    def step(self, action) -> StepResult:
        """One control step of every world with ``action`` (N, n_joints + 2): joint targets [rad],
        suction (> 0: on), belt pass (> 0: on), as ``ColorSort.step`` takes them."""
        import torch

        action = torch.as_tensor(action, dtype=torch.float32, device=self.torch_device)
        if action.shape != (self.worlds, self.spec.n_joints + 2):
            raise ActionError(f"expected actions of shape ({self.worlds}, {self.spec.n_joints + 2}), "
                             f"got {tuple(action.shape)}")
        if not torch.isfinite(action).all():
            raise ActionError("actions must be finite")
        wp.to_torch(self.action).copy_(action)
        self._sync()
        if self.use_graph:
            if self._graph is None:
                with wp.ScopedDevice(self.device), wp.ScopedCapture() as capture:
                    self._control_step()
                self._graph = capture.graph
            wp.capture_launch(self._graph)
            self._sync()
        else:
            with wp.ScopedDevice(self.device):
                self._control_step()
        if self.cameras is not None:
            with wp.ScopedDevice(self.device):
                self._render()
        return self._result()

    def _sync(self) -> None:
        """Wait for Warp's and torch's work on the device: they run on different CUDA streams."""
        import torch

        wp.synchronize_device(self.device)
        if self.device.is_cuda:
            torch.cuda.synchronize(self.torch_device)

    def _render(self) -> None:
        assert self.cameras is not None, "a cell without cameras renders nothing"
        self.images = self.cameras.render(self.m, self.d, wp.to_torch(self.detected) != 0)

    # ------------------------------------------------------------------ the control step
    def _control_step(self) -> None:
        s, m, d, n = self.spec, self.m, self.d, self.worlds
        wp.launch(K.apply_action, dim=n, inputs=[self.action, s.n_joints, self.goal, self.suction_cmd, self.belt_pass])
        cos_seal = float(np.cos(np.deg2rad(SEAL_ANGLE_DEG)))
        for sub in range(self.substeps):
            mjw.step1(m, d)
            if sub % s.servo_period == 0:
                wp.launch(K.servo_error, dim=(n, s.n_joints),
                          inputs=[self.goal, d.qpos, d.qvel, self.arm_qpos, self.arm_dof, self.kp, self.kd, self.vec])
                mjw.mul_m(m, d, self.res, self.vec)
                wp.launch(K.servo_torque, dim=(n, s.n_joints),
                          inputs=[self.res, d.qfrc_bias, self.arm_dof, self.arm_act, self.t_low, self.t_high, d.ctrl])
            wp.launch(K.drive, dim=n, inputs=[self.controls, self.rig, self.layout, self.pool, self.bodies,
                                              d.sensordata, d.ctrl])
            wp.launch(K.seal_find, dim=d.naconmax, inputs=[
                d.nacon, d.contact.geom, d.contact.frame, d.contact.worldid, s.pad_geom, self.box_of_geom, s.cup_body,
                d.xmat, self.suction_cmd, self.held, cos_seal, self.candidate])
            wp.launch(K.seal_make, dim=n, inputs=[self.candidate, self.pool, self.boxes, s.cup_body, self.bodies,
                                                  d.xquat, d.xmat, m.eq_data, self.held, self.grips])
            mjw.step2(m, d)
        wp.launch(K.advance_clock, dim=n, inputs=[self.now, wp.float64(self.control_dt), self.steps])
        wp.launch(K.referee, dim=n, inputs=[self.now, self.layout, int(s.config.bin_capacity), self.pool, self.bodies,
                                            self.boxes, self.held, self.event_log, self.reward, self.bins_emptied])
        self._launch_spawn()
        mjw.forward(m, d)
        self._launch_observe()

    def _launch_spawn(self) -> None:
        wp.launch(K.spawn, dim=self.worlds, inputs=[
            self.now, self.next_time, float(self.spec.config.spawn_period), self.layout, self.draws, self.palette,
            self.pool, self.bodies, self.m.geom_rgba, self.boxes, self.next_serial, self.spawned])

    def _launch_observe(self) -> None:
        s, d = self.spec, self.d
        wp.launch(observe, dim=self.worlds, inputs=[
            d.qpos, d.qvel, d.site_xpos, d.xquat, self.arm_qpos, self.arm_dof, s.eef_site, s.eef_body,
            self.controls, self.pool, self.boxes, self.observation_layout, self.state, self.env_state])

    def _result(self) -> StepResult:
        return StepResult(wp.to_torch(self.state), wp.to_torch(self.env_state), wp.to_torch(self.reward), self.images)

    # ------------------------------------------------------------------ reading worlds
    def record(self) -> Record:
        """Every world's episode so far, copied to the host in one go."""
        return Record(self.seeds.copy(), self.n_events.numpy(), self.ev_time.numpy(), self.ev_serial.numpy(),
                      self.ev_color.numpy(), self.ev_outcome.numpy(), self.ev_bin.numpy(), self.grips.numpy(),
                      self.draw_offset.numpy(), self.draw_yaw.numpy())

    def events(self, world: int) -> list[tuple[float, int, int, int, int]]:
        """World ``world``'s boxes that left play this episode (``Record.events``)."""
        return self.record().events(world)


@dataclass(frozen=True)
class Record:
    """The worlds' episodes on the host (numpy, a row per world): seeds, boxes that left play (time [s], serial,
    colour, outcome and bin indices, in order), each serial's grip (offset [m], yaw [deg]; NaN if never sealed)
    and draws (offset [m], yaw [rad])."""

    seeds: np.ndarray
    n_events: np.ndarray
    time: np.ndarray
    serial: np.ndarray
    color: np.ndarray
    outcome: np.ndarray
    bin: np.ndarray
    grips: np.ndarray
    offset: np.ndarray
    yaw: np.ndarray

    def events(self, world: int) -> list[tuple[float, int, int, int, int]]:
        """World ``world``'s boxes that left play, in order: (time [s], serial, colour index, outcome index,
        bin index or -1)."""
        k = min(int(self.n_events[world]), self.time.shape[1])
        rows = (self.time, self.serial, self.color, self.outcome, self.bin)
        return [(float(t), int(s), int(c), int(o), int(b)) for t, s, c, o, b in zip(*(r[world, :k] for r in rows),
                                                                                      strict=True)]
