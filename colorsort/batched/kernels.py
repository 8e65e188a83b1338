"""The cell's rules as Warp kernels, one thread per world (or per contact), for ``BatchedCell``.

Each kernel is the twin of a Python part of the CPU cell, named in its docstring; ``tests/test_twins.py``
holds the rule functions (``@wp.func``) to their Python twins on the same inputs. Box status, outcome and
bin codes are the CPU cell's enum orders (``boxes.BoxStatus``, ``referee.Outcome``, ``config.BIN_COLORS``).
"""

from __future__ import annotations

import typing

import mujoco_warp
import warp as wp

from colorsort.batched.arrays import Bodies, Boxes, Controls, Draws, Events, Pool, Rig
from colorsort.cell.boxes import SPAWN_CLEAR, SPAWN_GAP, BoxStatus
from colorsort.cell.referee import FLOOR_MARGIN, Outcome
from colorsort.config import BIN_COLORS

wp.set_module_options({"enable_backward": False})  # nothing differentiates the cell: half the compile

# The CPU cell's enums and rule constants, derived here, never restated: a change there is a change here.
STATUSES = list(BoxStatus)  # the box status codes (the sim state's order)
PARKED, IN_PLAY, IN_BIN = (wp.constant(STATUSES.index(s)) for s in
                           (BoxStatus.PARKED, BoxStatus.IN_PLAY, BoxStatus.IN_BIN))
NONE = wp.constant(-1)  # no outcome yet / no bin
OUTCOMES = list(Outcome)  # the outcome codes, on the host
PLACED, MISPLACED, DROPPED, REJECTED = (wp.constant(OUTCOMES.index(o)) for o in
                                        (Outcome.PLACED, Outcome.MISPLACED, Outcome.DROPPED, Outcome.REJECTED))
N_BIN_COLORS = wp.constant(len(BIN_COLORS))  # colours 0..2 (red, green, blue) have bins; the others do not
FLOOR = wp.constant(FLOOR_MARGIN)  # [m] referee: how close to the floor a fallen box's centre is
# the type of an equality's data in MuJoCo Warp, read off its public Model (its module of types is private)
vec11 = typing.get_type_hints(mujoco_warp.Model)["eq_data"].dtype


@wp.func
def quat_inv(q: wp.quat) -> wp.quat:
    """The inverse of a unit quaternion in MuJoCo's order (w, x, y, z), as ``mju_negQuat``."""
    return wp.quat(q[0], -q[1], -q[2], -q[3])


@wp.func
def mul_quat(u: wp.quat, v: wp.quat) -> wp.quat:
    """The product of two quaternions in MuJoCo's order (w, x, y, z), as ``mju_mulQuat``."""
    return wp.quat(u[0] * v[0] - u[1] * v[1] - u[2] * v[2] - u[3] * v[3],
                   u[0] * v[1] + u[1] * v[0] + u[2] * v[3] - u[3] * v[2],
                   u[0] * v[2] - u[1] * v[3] + u[2] * v[0] + u[3] * v[1],
                   u[0] * v[3] + u[1] * v[2] - u[2] * v[1] + u[3] * v[0])


@wp.func
def quat_yaw(q: wp.quat) -> float:
    """[rad] the heading of the rotation's x axis about z, ``atan2(R[1, 0], R[0, 0])`` of ``mju_quat2Mat(q)``,
    q in MuJoCo's order (w, x, y, z)."""
    r00 = q[0] * q[0] + q[1] * q[1] - q[2] * q[2] - q[3] * q[3]
    r10 = 2.0 * (q[1] * q[2] + q[0] * q[3])
    return wp.atan2(r10, r00)
GAP = wp.constant(SPAWN_GAP)  # [m] spawner: a box set down this far above the belt
CLEAR = wp.constant(SPAWN_CLEAR)  # spawner: box sizes the spawn point must be clear of boxes in play


@wp.struct
class Layout:
    """``config.CellLayout`` and the referee's thresholds [m, m/s]."""

    belt_end_x: float
    belt_y: float
    belt_width: float
    belt_top_z: float
    box_size: float
    spawn_x: float
    sensor_range: float
    bin_x: float
    bin_y0: float
    bin_spacing: float
    bin_half_x: float  # inner half-size of a bin's footprint
    bin_half_y: float
    bin_height: float
    settled_speed: float


@wp.func
def belt_runs(distance: float, sensor_range: float, tracking: int, belt_pass: int) -> int:
    """``conveyor.Belt.drive``: the belt runs unless the ray sees a box (a tracking belt always runs)."""
    detected = distance >= 0.0 and distance <= sensor_range
    if tracking != 0 or belt_pass != 0 or not detected:
        return 1
    return 0


@wp.func
def bin_under(x: float, y: float, L: Layout) -> int:
    """``referee.Referee.bin_under``: the bin whose inner footprint holds (x, y), or -1."""
    for k in range(3):
        bx = L.bin_x
        by = L.bin_y0 + float(k) * L.bin_spacing
        if wp.abs(x - bx) < L.bin_half_x and wp.abs(y - by) < L.bin_half_y:
            return k
    return -1


@wp.func
def outcome_of(color: int, pos: wp.vec3, speed: float, L: Layout) -> wp.vec2i:
    """``referee.Referee.outcome``: (outcome, bin) of a box of ``color`` at ``pos`` moving at ``speed``;
    (-1, -1) while it is still in play."""
    half = L.box_size / 2.0
    b = bin_under(pos[0], pos[1], L)
    if b >= 0 and pos[2] < L.bin_height and speed < L.settled_speed:
        if color == b:
            return wp.vec2i(PLACED, b)
        return wp.vec2i(MISPLACED, b)
    on_floor = pos[2] < half + FLOOR and b < 0
    past_end = pos[0] < L.belt_end_x and wp.abs(pos[1] - L.belt_y) < L.belt_width and pos[2] < L.belt_top_z + half
    if on_floor or past_end:
        if color < N_BIN_COLORS:
            return wp.vec2i(DROPPED, -1)
        return wp.vec2i(REJECTED, -1)
    return wp.vec2i(NONE, NONE)


@wp.kernel
def apply_action(action: wp.array2d(dtype=float), n_joints: int, goal: wp.array2d(dtype=float),
                 suction_cmd: wp.array(dtype=int), belt_pass: wp.array(dtype=int)):
    """``ColorSort._pre_action`` at a policy step: joint targets, suction on when > 0, belt pass when > 0."""
    w = wp.tid()
    for j in range(n_joints):
        goal[w, j] = action[w, j]
    suction_cmd[w] = wp.where(action[w, n_joints] > 0.0, 1, 0)
    belt_pass[w] = wp.where(action[w, n_joints + 1] > 0.0, 1, 0)


@wp.kernel
def servo_error(goal: wp.array2d(dtype=float), qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float),
                arm_qpos: wp.array(dtype=int), arm_dof: wp.array(dtype=int), kp: wp.array(dtype=float),
                kd: wp.array(dtype=float), vec: wp.array2d(dtype=float)):
    """robosuite's ``JointPositionController``, first half: kp (goal - q) - kd qdot on the arm's dofs."""
    w, j = wp.tid()
    v = arm_dof[j]
    vec[w, v] = kp[j] * (goal[w, j] - qpos[w, arm_qpos[j]]) - kd[j] * qvel[w, v]


@wp.kernel
def servo_torque(res: wp.array2d(dtype=float), qfrc_bias: wp.array2d(dtype=float), arm_dof: wp.array(dtype=int),
                 arm_act: wp.array(dtype=int), low: wp.array(dtype=float), high: wp.array(dtype=float),
                 ctrl: wp.array2d(dtype=float)):
    """Second half: M (kp e - kd qdot) + bias, clipped to the actuators' ranges (robosuite's ``Robot.control``)."""
    w, j = wp.tid()
    v = arm_dof[j]
    ctrl[w, arm_act[j]] = wp.clamp(res[w, v] + qfrc_bias[w, v], low[j], high[j])


@wp.kernel
def drive(io: Controls, rig: Rig, L: Layout, pool: Pool, sim: Bodies, sensordata: wp.array2d(dtype=float),
          ctrl: wp.array2d(dtype=float)):
    """Before each physics step: the suction valve (``SuctionGripper``), the belt and its ray
    (``conveyor.Belt.drive``), and the seal's release (``suction.VacuumSeal.update``)."""
    w = wp.tid()
    ctrl[w, rig.suction] = wp.where(io.suction_cmd[w] != 0, rig.suction_on, rig.suction_off)
    distance = sensordata[w, rig.ray]
    io.detected[w] = wp.where(distance >= 0.0 and distance <= L.sensor_range, 1, 0)
    run = belt_runs(distance, L.sensor_range, rig.tracking, io.belt_pass[w])
    io.running[w] = run
    sim.qpos[w, rig.belt_qpos] = 0.0
    sim.qvel[w, rig.belt_dof] = wp.where(run != 0, -rig.speed, 0.0)
    if run != 0:
        io.travel[w] = io.travel[w] + wp.float64(rig.speed) * wp.float64(rig.dt)
    if io.suction_cmd[w] == 0 and io.held[w] >= 0:
        sim.eq_active[w, pool.weld[io.held[w]]] = False
        io.held[w] = -1


@wp.kernel
def seal_find(nacon: wp.array(dtype=int), geom: wp.array(dtype=wp.vec2i), frame: wp.array(dtype=wp.mat33),
              worldid: wp.array(dtype=int), pad: int, box_of_geom: wp.array(dtype=int), cup_body: int,
              xmat: wp.array2d(dtype=wp.mat33), suction_cmd: wp.array(dtype=int), held: wp.array(dtype=int),
              cos_seal: float, candidate: wp.array(dtype=int)):
    """``suction.VacuumSeal._box_flat_on_pad``: a pad-box contact whose normal is within the seal angle of
    the cup's axis, in a world where suction is on and nothing is held; the lowest pool index wins."""
    k = wp.tid()
    if k >= nacon[0]:
        return
    w = worldid[k]
    if suction_cmd[w] == 0 or held[w] >= 0:
        return
    g = geom[k]
    other = int(-1)  # noqa: UP018  (Warp: a variable, not a constant)
    if g[0] == pad:
        other = g[1]
    elif g[1] == pad:
        other = g[0]
    if other < 0:
        return
    box = box_of_geom[other]
    if box < 0:
        return
    R = xmat[w, cup_body]
    axis = wp.vec3(R[0, 2], R[1, 2], R[2, 2])
    normal = wp.vec3(frame[k][0, 0], frame[k][0, 1], frame[k][0, 2])
    if wp.abs(wp.dot(normal, axis)) >= cos_seal:
        wp.atomic_min(candidate, w, box)


@wp.kernel
def seal_make(candidate: wp.array(dtype=int), pool: Pool, boxes: Boxes, cup_body: int, sim: Bodies,
              xquat: wp.array2d(dtype=wp.quat), xmat: wp.array2d(dtype=wp.mat33), eq_data: wp.array2d(dtype=vec11),
              held: wp.array(dtype=int), grips: wp.array3d(dtype=float)):
    """``suction.VacuumSeal._seal``: weld the candidate box to the cup at the pose they have now; record the
    grip (``VacuumSeal.grip``: offset from the cup's axis [m], turn [deg] in [-45, 45)) under its serial."""
    w = wp.tid()
    box = candidate[w]
    candidate[w] = pool.size
    if box >= pool.size:
        return
    body = pool.body[box]
    R = xmat[w, cup_body]
    rel = wp.transpose(R) @ (sim.xpos[w, body] - sim.xpos[w, cup_body])
    q = mul_quat(quat_inv(xquat[w, cup_body]), xquat[w, body])
    eq = pool.weld[box]
    data = eq_data[w, eq]
    data[0] = 0.0
    data[1] = 0.0
    data[2] = 0.0
    data[3] = rel[0]
    data[4] = rel[1]
    data[5] = rel[2]
    data[6] = q[0]
    data[7] = q[1]
    data[8] = q[2]
    data[9] = q[3]
    eq_data[w, eq] = data
    sim.eq_active[w, eq] = True
    held[w] = box
    serial = boxes.serial[w, box]
    if serial >= 0 and serial < grips.shape[1]:
        yaw = wp.degrees(quat_yaw(q))
        grips[w, serial, 0] = wp.sqrt(rel[0] * rel[0] + rel[1] * rel[1])
        grips[w, serial, 1] = wp.mod(yaw + 45.0 + 360.0, 90.0) - 45.0


@wp.func
def park(w: int, box: int, pool: Pool, sim: Bodies, boxes: Boxes, held: wp.array(dtype=int)):
    """``plant.Plant.remove_box``: the cup lets go of it, and it goes back to the pool."""
    if held[w] == box:
        sim.eq_active[w, pool.weld[box]] = False
        held[w] = -1
    qa = pool.qpos[box]
    va = pool.dof[box]
    p = pool.park[box]
    sim.qpos[w, qa + 0] = p[0]
    sim.qpos[w, qa + 1] = p[1]
    sim.qpos[w, qa + 2] = p[2]
    sim.qpos[w, qa + 3] = 1.0
    sim.qpos[w, qa + 4] = 0.0
    sim.qpos[w, qa + 5] = 0.0
    sim.qpos[w, qa + 6] = 0.0
    for i in range(6):
        sim.qvel[w, va + i] = 0.0
    sim.gravcomp[w, pool.body[box]] = 1.0
    boxes.status[w, box] = PARKED
    boxes.bin[w, box] = -1
    boxes.serial[w, box] = -1


@wp.kernel
def referee(now: wp.array(dtype=wp.float64), L: Layout, bin_capacity: int, pool: Pool, sim: Bodies, boxes: Boxes,
            held: wp.array(dtype=int), events: Events, reward: wp.array(dtype=float),
            bins_emptied: wp.array(dtype=int)):
    """``referee.Referee.update``: judge every box in play, in pool order; record each that left play;
    empty a full bin; boxes that left the belt or fell go back to the pool."""
    w = wp.tid()
    r = float(0.0)  # noqa: UP018
    for box in range(pool.size):
        if boxes.status[w, box] != IN_PLAY:
            continue
        va = pool.dof[box]
        speed = wp.length(wp.vec3(sim.qvel[w, va], sim.qvel[w, va + 1], sim.qvel[w, va + 2]))
        res = outcome_of(boxes.color[w, box], sim.xpos[w, pool.body[box]], speed, L)
        outcome = res[0]
        if outcome < 0:
            continue
        k = events.count[w]
        if k < events.time.shape[1]:
            events.time[w, k] = now[w]
            events.serial[w, k] = boxes.serial[w, box]
            events.color[w, k] = boxes.color[w, box]
            events.outcome[w, k] = outcome
            events.bin[w, k] = res[1]
        events.count[w] = k + 1
        if outcome == PLACED:
            r += 1.0
        elif outcome != REJECTED:
            r -= 1.0
        if res[1] >= 0:
            boxes.status[w, box] = IN_BIN
            boxes.bin[w, box] = res[1]
            inside = int(0)  # noqa: UP018
            for other in range(pool.size):
                if boxes.status[w, other] == IN_BIN and boxes.bin[w, other] == res[1]:
                    inside += 1
            if inside >= bin_capacity:
                for other in range(pool.size):
                    if boxes.status[w, other] == IN_BIN and boxes.bin[w, other] == res[1]:
                        park(w, other, pool, sim, boxes, held)
                bins_emptied[w] = bins_emptied[w] + 1
        else:
            park(w, box, pool, sim, boxes, held)
    reward[w] = r


@wp.kernel
def spawn(now: wp.array(dtype=wp.float64), next_time: wp.array(dtype=wp.float64), period: float, L: Layout,
          draws: Draws, palette: wp.array(dtype=wp.vec4), pool: Pool, sim: Bodies, geom_rgba: wp.array2d(dtype=wp.vec4),
          boxes: Boxes, next_serial: wp.array(dtype=int), spawned: wp.array(dtype=int)):
    """``conveyor.Spawner.spawn_if_due``: when a box is due, the pool has one and the spawn point is clear,
    set the lowest parked box down with the episode's next draw (``schedule.episode_draws``)."""
    w = wp.tid()
    if now[w] + wp.float64(1e-9) < next_time[w]:
        return
    first = int(-1)  # noqa: UP018
    clear = int(1)  # noqa: UP018
    for box in range(pool.size):
        if boxes.status[w, box] == PARKED and first < 0:
            first = box
        if boxes.status[w, box] == IN_PLAY:
            p = sim.xpos[w, pool.body[box]]
            if wp.abs(p[0] - L.spawn_x) < CLEAR * L.box_size and wp.abs(p[1] - L.belt_y) < L.belt_width:
                clear = 0
    n = next_serial[w]
    if clear == 0 or first < 0 or n >= draws.color.shape[1]:
        return
    c = draws.color[w, n]
    yaw = draws.yaw[w, n]
    qa = pool.qpos[first]
    va = pool.dof[first]
    sim.qpos[w, qa + 0] = L.spawn_x
    sim.qpos[w, qa + 1] = L.belt_y + draws.offset[w, n]
    sim.qpos[w, qa + 2] = L.belt_top_z + L.box_size / 2.0 + GAP
    sim.qpos[w, qa + 3] = wp.cos(yaw / 2.0)
    sim.qpos[w, qa + 4] = 0.0
    sim.qpos[w, qa + 5] = 0.0
    sim.qpos[w, qa + 6] = wp.sin(yaw / 2.0)
    for i in range(6):
        sim.qvel[w, va + i] = 0.0
    geom_rgba[w, pool.geom[first]] = palette[c]
    sim.gravcomp[w, pool.body[first]] = 0.0
    boxes.status[w, first] = IN_PLAY
    boxes.color[w, first] = c
    boxes.serial[w, first] = n
    next_serial[w] = n + 1
    next_time[w] = now[w] + wp.float64(period)
    spawned[w] = spawned[w] + 1


@wp.kernel
def advance_clock(now: wp.array(dtype=wp.float64), dt: wp.float64, steps: wp.array(dtype=int)):
    """``cur_time += control_timestep`` (float64, as robosuite adds it) and the step count."""
    w = wp.tid()
    now[w] = now[w] + dt
    steps[w] = steps[w] + 1
