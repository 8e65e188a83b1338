"""Every rule the batched cell's Warp kernels hold twice, against its CPU twin on synthetic states (``pytest -k twin``).

Each test draws many worlds at once (box statuses, poses, clocks, contacts, commands), runs the kernel on Warp's CPU
device over all of them, and the CPU cell's own code (``Referee.outcome``, ``Belt.drive``, ``Spawner.spawn_if_due``,
``Plant.remove_box``, ``VacuumSeal``, ``cell.observation``) on each world's numbers, and asks for the same result. No
physics runs, so each takes seconds: the slow end-to-end tests in ``test_batched.py`` hold the whole cell to the CPU
cell's expert replayed.
"""

from __future__ import annotations

from types import SimpleNamespace

import mujoco
import numpy as np
import pytest
from helpers import new_env

from colorsort.batched.schedule import COLOR_NAMES
from colorsort.cell.referee import Outcome, Referee
from colorsort.config import BIN_COLORS, CellLayout


def referee_twins(n: int = 4000) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """The referee's verdicts on ``n`` drawn boxes (positions over the bins, the belt, its end and the floor;
    speeds around the settling threshold): the kernel's, and the CPU cell's ``Referee.outcome``."""
    import warp as wp

    from colorsort.batched import kernels as K
    from colorsort.batched.cell import layout_struct

    @wp.kernel
    def judge(color: wp.array(dtype=int), pos: wp.array(dtype=wp.vec3), speed: wp.array(dtype=float), L: K.Layout,
              out: wp.array(dtype=wp.vec2i)):
        i = wp.tid()
        out[i] = K.outcome_of(color[i], pos[i], speed[i], L)

    layout, rng = CellLayout(), np.random.default_rng(0)
    pos = np.column_stack([rng.uniform(0.0, 1.4, n), rng.uniform(-0.6, 0.8, n), rng.uniform(0.0, 0.6, n)])
    pos = pos.astype(np.float32)
    speed = rng.uniform(0.0, 0.1, n).astype(np.float32)
    color = rng.integers(0, 5, n).astype(np.int32)
    with wp.ScopedDevice("cpu"):
        out = wp.zeros(n, dtype=wp.vec2i)
        wp.launch(judge, dim=n, inputs=[wp.array(color, dtype=int), wp.array(pos, dtype=wp.vec3),
                                        wp.array(speed, dtype=float), layout_struct(layout), out])
        got = out.numpy()
    referee = Referee(layout, bin_capacity=4)
    outcomes, colors = list(Outcome), list(COLOR_NAMES)
    want = []
    for c, p, s in zip(color, pos.astype(float), speed.astype(float), strict=True):
        outcome, bin_color = referee.outcome(colors[c], p, s)
        want.append((outcomes.index(outcome) if outcome else -1, BIN_COLORS.index(bin_color) if bin_color else -1))
    return got, want


def test_a_constant_changed_on_one_side_shows_in_the_twin_test(monkeypatch):
    """The twin test would catch drift: the CPU referee's floor margin moved 1 cm alone (after the kernels took
    theirs from it), verdicts differ."""
    from colorsort.batched import kernels  # noqa: F401 - their constants taken before the change
    from colorsort.cell import referee

    monkeypatch.setattr(referee, "FLOOR_MARGIN", referee.FLOOR_MARGIN + 0.01)
    got, want = referee_twins()
    assert (got != np.array(want)).any()


def observe_twins(n_joints: int, tracking: bool, seed: int = 0) -> tuple[np.ndarray, ...]:
    """The ``observe`` kernel on drawn synthetic worlds (joint angles, cup pose, flags, boxes in play or not, their
    serials and colours), and what the CPU cell's layout (``cell.observation``) packs from the same numbers:
    (kernel state, kernel box state, CPU state, CPU box state), one row per world."""
    import warp as wp

    from colorsort.batched import arrays as A
    from colorsort.batched import kernels as K
    from colorsort.batched.observe import observation_layout, observe
    from colorsort.cell.boxes import BoxStatus
    from colorsort.cell.observation import BOX_STATE, StateLayout

    rng, worlds, pool = np.random.default_rng(seed), 64, 4
    layout = StateLayout(n_joints, tracking)
    box_qpos = np.arange(pool) * 7 + n_joints + 3  # each box's free joint after the arm's and three others
    nq = int(box_qpos[-1]) + 7
    arm_qpos, arm_dof = rng.permutation(n_joints).astype(np.int32), rng.permutation(n_joints).astype(np.int32) + 2
    qpos, qvel = rng.normal(size=(worlds, nq)), rng.normal(size=(worlds, nq + 2))
    cup, quat = rng.normal(size=(worlds, 3)), rng.normal(size=(worlds, 4))  # quat as MuJoCo keeps it: w, x, y, z
    suction, held, detected, running = (rng.integers(0, 2, worlds) for _ in range(4))
    held = np.where(held > 0, rng.integers(0, pool, worlds), -1)
    travel = rng.uniform(0, 5, worlds)
    in_play, parked = K.STATUSES.index(BoxStatus.IN_PLAY), K.STATUSES.index(BoxStatus.PARKED)
    status = rng.integers(0, len(K.STATUSES), (worlds, pool))
    status[:8] = parked  # worlds with no box in play
    color = rng.integers(0, BOX_STATE.n_colors, (worlds, pool))
    serial = rng.permutation(worlds * pool).reshape(worlds, pool)
    with wp.ScopedDevice("cpu"):
        pool_struct, boxes = A.Pool(), A.Boxes()
        pool_struct.size, pool_struct.qpos = pool, wp.array(box_qpos.astype(np.int32), dtype=int)
        boxes.status, boxes.color = wp.array(status.astype(np.int32), dtype=int), wp.array(color.astype(np.int32),
                                                                                              dtype=int)
        boxes.serial = wp.array(serial.astype(np.int32), dtype=int)
        io = A.Controls()
        io.suction_cmd, io.held = wp.array(suction, dtype=int), wp.array(held, dtype=int)
        io.detected, io.running = wp.array(detected, dtype=int), wp.array(running, dtype=int)
        io.belt_pass, io.travel = wp.zeros(worlds, dtype=int), wp.array(travel, dtype=wp.float64)
        state = wp.zeros((worlds, layout.size), dtype=float)
        env_state = wp.zeros((worlds, BOX_STATE.size), dtype=float)
        wp.launch(observe, dim=worlds, inputs=[
            wp.array(qpos.astype(np.float32), dtype=float), wp.array(qvel.astype(np.float32), dtype=float),
            wp.array(cup[:, None, :].astype(np.float32), dtype=wp.vec3),
            wp.array(quat[:, None, :].astype(np.float32), dtype=wp.quat), wp.array(arm_qpos, dtype=int),
            wp.array(arm_dof, dtype=int), 0, 0, io, pool_struct, boxes, observation_layout(layout, BOX_STATE), state,
            env_state])
        got_state, got_box = state.numpy(), env_state.numpy()
    want_state, want_box = [], []
    for w in range(worlds):
        flags = (float(suction[w]), float(held[w] >= 0), float(detected[w]), float(running[w]))
        want_state.append(layout.pack(qpos[w, arm_qpos], qvel[w, arm_dof], cup[w], quat[w, [1, 2, 3, 0]], flags,
                                      travel[w] if tracking else None))
        playing = [b for b in range(pool) if status[w, b] == in_play]
        first = min(playing, key=lambda b: serial[w, b]) if playing else None
        want_box.append(BOX_STATE.pack(None if first is None else int(color[w, first]),
                                       None if first is None else qpos[w, box_qpos[first] : box_qpos[first] + 7]))
    return got_state, got_box, np.array(want_state), np.array(want_box)


@pytest.mark.parametrize(("n_joints", "tracking"), [(6, False), (6, True), (7, True)])
def test_the_observe_kernel_writes_the_cpu_cells_observation_layout(n_joints, tracking):
    """``observation.state`` and ``observation.environment_state`` as the kernel writes them, against the CPU cell's
    layout packed from the same synthetic numbers: another arm (7 joints, the Panda's) and the tracking belt's encoder
    move every offset, so a kernel that wrote at offsets of its own would differ."""
    got_state, got_box, want_state, want_box = observe_twins(n_joints, tracking)
    assert want_box[:, -1].any() and not want_box[:, -1].all()  # worlds with a box in play and without
    np.testing.assert_allclose(got_state, want_state, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(got_box, want_box, rtol=1e-6, atol=1e-6)


def test_the_rule_kernels_give_what_their_python_twins_give():
    """The referee's verdict and the belt's run/stop rule, as Warp functions, against the CPU cell's own
    ``Referee.outcome`` and ``conveyor.Belt.drive``."""
    import warp as wp

    from colorsort.batched import kernels as K

    layout = CellLayout()
    got, want = referee_twins()
    assert {tuple(w) for w in want} >= {(0, 0), (1, 1), (2, -1), (3, -1), (-1, -1)}  # every verdict was drawn
    assert (got == np.array(want)).all()

    @wp.kernel
    def belt(distance: wp.array(dtype=float), tracking: wp.array(dtype=int), belt_pass: wp.array(dtype=int),
             sensor_range: float, out: wp.array(dtype=int)):
        i = wp.tid()
        out[i] = K.belt_runs(distance[i], sensor_range, tracking[i], belt_pass[i])

    rng, n = np.random.default_rng(1), 4000
    distance = rng.choice([-1.0, 0.1, 0.26, 0.3], n).astype(np.float32)  # -1: MuJoCo's "no hit"
    tracking, belt_pass = rng.integers(0, 2, n).astype(np.int32), rng.integers(0, 2, n).astype(np.int32)
    with wp.ScopedDevice("cpu"):
        runs = wp.zeros(n, dtype=int)
        wp.launch(belt, dim=n, inputs=[wp.array(distance, dtype=float), wp.array(tracking, dtype=int),
                                       wp.array(belt_pass, dtype=int), layout.sensor_range, runs])
        got_runs = runs.numpy()
    env = new_env()  # the CPU cell's own belt, its ray reading set to each sample
    try:
        cpu_belt = env.plant.belt
        want_runs = []
        for d, t, p in zip(distance, tracking, belt_pass, strict=True):
            cpu_belt.tracking, cpu_belt.belt_pass = bool(t), bool(p)
            env.mj_data.sensordata[cpu_belt.ray] = d
            cpu_belt.drive()
            want_runs.append(int(cpu_belt.running))
    finally:
        env.close()
    np.testing.assert_array_equal(got_runs, want_runs)
    assert 0 < sum(want_runs) < n  # the belt both ran and stopped




def cpu_pool(env, worlds: int):
    """The CPU cell's pool as the kernels take it (``arrays.Pool``, parking where the CPU cell parks), and its
    MuJoCo arrays repeated over ``worlds`` as ``arrays.Bodies`` takes them (host copies, to be filled per world)."""
    import warp as wp

    from colorsort.batched import arrays as A
    from colorsort.cell.models.arena import park_position

    pool, seal, m, d = env.plant.pool, env.plant.seal, env.mj_model, env.mj_data
    P = len(pool.boxes)
    struct = A.Pool()
    struct.size = P
    struct.qpos, struct.dof = wp.array(np.int32(pool.qpos), dtype=int), wp.array(np.int32(pool.qvel), dtype=int)
    struct.body, struct.geom = wp.array(np.int32(pool.body), dtype=int), wp.array(np.int32(pool.geom), dtype=int)
    struct.weld = wp.array(np.int32(seal.welds), dtype=int)
    struct.park = wp.array(np.float32([park_position(i) for i in range(P)]), dtype=wp.vec3)
    host = SimpleNamespace(xpos=np.repeat(d.xpos[None], worlds, 0), qpos=np.repeat(d.qpos[None], worlds, 0),
                           qvel=np.zeros((worlds, m.nv)), gravcomp=np.repeat(m.body_gravcomp[None], worlds, 0),
                           eq_active=np.zeros((worlds, m.neq), bool))
    return struct, host


def bodies(host):
    """``arrays.Bodies`` on Warp's CPU device from the host copies ``cpu_pool`` made."""
    import warp as wp

    from colorsort.batched import arrays as A

    sim = A.Bodies()
    sim.xpos = wp.array(host.xpos.astype(np.float32), dtype=wp.vec3)
    sim.qpos, sim.qvel = (wp.array(getattr(host, k).astype(np.float32), dtype=float) for k in ("qpos", "qvel"))
    sim.gravcomp = wp.array(host.gravcomp.astype(np.float32), dtype=float)
    sim.eq_active = wp.array(host.eq_active, dtype=bool)
    return sim


def boxes_struct(status, color, bins, serial):
    import warp as wp

    from colorsort.batched import arrays as A

    boxes = A.Boxes()
    boxes.status, boxes.color, boxes.bin, boxes.serial = (wp.array(np.int32(a), dtype=int)
                                                          for a in (status, color, bins, serial))
    return boxes


def set_cpu_boxes(pool, status, color, bins, serial) -> None:
    """One world's bookkeeping onto the CPU cell's pool (codes as the kernels keep them)."""
    from colorsort.batched import kernels as K

    for b, box in enumerate(pool.boxes):
        box.status, box.color, box.serial = K.STATUSES[status[b]], COLOR_NAMES[color[b]], int(serial[b])
        box.bin = BIN_COLORS[bins[b]] if bins[b] >= 0 else None


def cpu_boxes(pool) -> np.ndarray:
    """The CPU pool's (status, bin, serial) per box, in the kernels' codes."""
    from colorsort.batched import kernels as K

    return np.array([(K.STATUSES.index(b.status), BIN_COLORS.index(b.bin) if b.bin else -1, b.serial)
                     for b in pool.boxes])


def drawn_boxes(rng, worlds: int, P: int):
    """Every world's bookkeeping: statuses (parked, in play, in a bin), colours, bins and serials."""
    status = rng.choice(3, (worlds, P), p=[0.4, 0.45, 0.15])
    color = rng.integers(0, len(COLOR_NAMES), (worlds, P))
    bins = np.where(status == 2, rng.integers(0, len(BIN_COLORS), (worlds, P)), -1)
    serial = np.where(status == 0, -1, rng.integers(0, 40, (worlds, P)))
    return status, color, bins, serial


def check_spawn_twins() -> None:
    """Assert that ``spawn`` does what ``Spawner.spawn_if_due`` does on 300 drawn worlds (the test below)."""
    import warp as wp

    from colorsort.batched import arrays as A
    from colorsort.batched import kernels as K
    from colorsort.batched.cell import layout_struct

    env = new_env()
    try:
        plant, m, d, L = env.plant, env.mj_model, env.mj_data, env.layout
        pool, spawner, W = plant.pool, plant.spawner, 300
        P, rng = len(pool.boxes), np.random.default_rng(3)
        struct, host = cpu_pool(env, W)
        status, color, bins, serial = drawn_boxes(rng, W, P)
        status[:30] = 1  # no parked box
        for w, b in zip(*np.nonzero(status == 1), strict=True):
            near = rng.random() < 0.3
            host.xpos[w, pool.body[b]] = (L.spawn_x + rng.uniform(-2, 2) * L.box_size * (1 if near else 5),
                                          L.belt_y + rng.uniform(-1.5, 1.5) * L.belt_width, 0.8)
        host.qvel[:] = rng.normal(size=host.qvel.shape)
        host.gravcomp[:, pool.body] = rng.integers(0, 2, (W, P))
        now = rng.uniform(0.0, 30.0, W)
        next_time = now + rng.choice([-1.0, -1e-3, 5e-10, 1e-3, 1.0], W)
        next_serial = rng.integers(0, 20, W)
        rgba0 = m.geom_rgba.copy()
        want, placed = [], np.zeros((W, 3))
        for w in range(W):
            d.qpos[:], d.qvel[:], d.xpos[:] = host.qpos[w], host.qvel[w], host.xpos[w]
            m.body_gravcomp[:], m.geom_rgba[:] = host.gravcomp[w], rgba0
            set_cpu_boxes(pool, status[w], color[w], bins[w], serial[w])
            spawner.set_state(float(next_time[w]), int(next_serial[w]))
            box = spawner.spawn_if_due(float(now[w]), np.random.default_rng(w))
            if box is not None:
                p = spawner.placed[-1]
                placed[w] = COLOR_NAMES.index(p.color), p.offset, np.deg2rad(p.yaw)
            want.append((box.index if box else -1, d.qpos.copy(), d.qvel.copy(), m.body_gravcomp.copy(),
                         m.geom_rgba.copy(), cpu_boxes(pool), [b.color for b in pool.boxes], *spawner.get_state()))
        with wp.ScopedDevice("cpu"):
            draws, E = A.Draws(), 20
            draws.color = wp.array(np.int32(np.repeat(placed[:, :1], E, 1)), dtype=int)
            draws.offset = wp.array(np.float32(np.repeat(placed[:, 1:2], E, 1)), dtype=float)
            draws.yaw = wp.array(np.float32(np.repeat(placed[:, 2:], E, 1)), dtype=float)
            sim, boxes = bodies(host), boxes_struct(status, color, bins, serial)
            rgba = wp.array(np.repeat(rgba0[None], W, 0).astype(np.float32), dtype=wp.vec4)
            palette = wp.array(np.float32([pool.palette[c] for c in COLOR_NAMES]), dtype=wp.vec4)
            clock, due = wp.array(now, dtype=wp.float64), wp.array(next_time, dtype=wp.float64)
            serials, spawned = wp.array(np.int32(next_serial), dtype=int), wp.zeros(W, dtype=int)
            wp.launch(K.spawn, dim=W, inputs=[clock, due, float(spawner.config.spawn_period), layout_struct(L), draws,
                                              palette, struct, sim, rgba, boxes, serials, spawned])
            qpos, qvel, grav = sim.qpos.numpy(), sim.qvel.numpy(), sim.gravcomp.numpy()
            got_status, got_color, got_serial = boxes.status.numpy(), boxes.color.numpy(), boxes.serial.numpy()
            got_rgba, got_next, got_serials, got_spawned = rgba.numpy(), due.numpy(), serials.numpy(), spawned.numpy()
        reasons = {"spawned": 0, "not due": 0, "no parked box": 0, "blocked": 0}
        for w, (box, q, v, g, c, kept, colors, t, n) in enumerate(want):
            assert got_spawned[w] == (box >= 0), w
            np.testing.assert_array_equal(got_status[w], kept[:, 0])
            np.testing.assert_array_equal(got_serial[w], kept[:, 2])
            np.testing.assert_allclose(qpos[w], q, atol=2e-6)
            np.testing.assert_allclose(qvel[w], v, atol=1e-6)
            np.testing.assert_array_equal(grav[w], g)
            np.testing.assert_allclose(got_rgba[w], c, atol=1e-6)
            assert got_serials[w] == n and got_next[w] == pytest.approx(t, abs=1e-6)
            if box >= 0:
                assert COLOR_NAMES[got_color[w, box]] == colors[box]
                reasons["spawned"] += 1
            elif now[w] + 1e-9 < next_time[w]:
                reasons["not due"] += 1
            elif not (status[w] == 0).any():
                reasons["no parked box"] += 1
            else:
                reasons["blocked"] += 1
        assert min(reasons.values()) >= 10, reasons  # every branch of the rule was drawn
    finally:
        env.close()



def test_the_spawn_kernel_sets_down_the_box_the_cpu_spawner_does():
    """``spawn`` against ``Spawner.spawn_if_due`` on 300 drawn worlds: due or not (across its 1e-9 s tolerance), a
    pool with and without a parked box, the spawn point clear or blocked by a box in play (within 1.5 box sizes along
    the belt, within the belt's width across it); where it spawns, the same box at the same pose, colour, serial,
    velocity and gravity, and the same next spawn time and serial. The kernel reads the CPU spawner's own draw."""
    check_spawn_twins()


@pytest.mark.parametrize(("name", "change"), [("SPAWN_GAP", 0.001), ("SPAWN_CLEAR", 0.5)])
def test_a_spawn_constant_changed_on_one_side_shows_in_the_twin_test(monkeypatch, name, change):
    """The CPU cell's spawn height above the belt (1 mm) or its clear zone (half a box size) moved alone, after the
    kernels took theirs from it: the spawn twin test fails."""
    from colorsort.batched import kernels  # noqa: F401 - their constants taken before the change
    from colorsort.cell import boxes

    monkeypatch.setattr(boxes, name, getattr(boxes, name) + change)
    with pytest.raises(AssertionError):
        check_spawn_twins()

def test_the_park_function_returns_a_box_to_the_pool_as_the_cpu_plant_does():
    """``park`` (the referee's, through a one-line kernel) against ``Plant.remove_box`` on 200 drawn worlds: the box
    held by the cup or not, in play or in a bin; the same pose, velocity, gravity, weld, bookkeeping and held box."""
    import warp as wp

    from colorsort.batched import kernels as K

    @wp.kernel
    def park_one(box: wp.array(dtype=int), pool: K.Pool, sim: K.Bodies, boxes: K.Boxes, held: wp.array(dtype=int)):
        w = wp.tid()
        K.park(w, box[w], pool, sim, boxes, held)

    env = new_env()
    try:
        plant, m, d = env.plant, env.mj_model, env.mj_data
        pool, seal, W = plant.pool, plant.seal, 200
        P, rng = len(pool.boxes), np.random.default_rng(4)
        struct, host = cpu_pool(env, W)
        status, color, bins, serial = drawn_boxes(rng, W, P)
        which = rng.integers(0, P, W)
        status[np.arange(W), which] = rng.choice([1, 2], W)
        held = np.where(rng.random(W) < 0.6, rng.integers(0, P, W), -1)
        held[:60] = which[:60]  # the cup holds the very box
        host.qpos[:] += rng.normal(scale=0.1, size=host.qpos.shape)
        host.qvel[:] = rng.normal(size=host.qvel.shape)
        host.gravcomp[:, pool.body] = rng.integers(0, 2, (W, P))
        host.eq_active[held >= 0, seal.welds[held[held >= 0]]] = True
        want = []
        for w in range(W):
            d.qpos[:], d.qvel[:], d.eq_active[:] = host.qpos[w], host.qvel[w], host.eq_active[w]
            m.body_gravcomp[:] = host.gravcomp[w]
            set_cpu_boxes(pool, status[w], color[w], bins[w], serial[w])
            seal.held = int(held[w]) if held[w] >= 0 else None
            plant.remove_box(pool.boxes[which[w]])
            want.append((d.qpos.copy(), d.qvel.copy(), m.body_gravcomp.copy(), d.eq_active.astype(bool),
                         cpu_boxes(pool), -1 if seal.held is None else seal.held))
        with wp.ScopedDevice("cpu"):
            sim, boxes = bodies(host), boxes_struct(status, color, bins, serial)
            cup = wp.array(np.int32(held), dtype=int)
            wp.launch(park_one, dim=W, inputs=[wp.array(np.int32(which), dtype=int), struct, sim, boxes, cup])
            qpos, qvel, grav, welds = sim.qpos.numpy(), sim.qvel.numpy(), sim.gravcomp.numpy(), sim.eq_active.numpy()
            kept = np.stack([boxes.status.numpy(), boxes.bin.numpy(), boxes.serial.numpy()], -1)
            got_held = cup.numpy()
        for w, (q, v, g, e, book, h) in enumerate(want):
            np.testing.assert_allclose(qpos[w], q, atol=1e-6)
            np.testing.assert_allclose(qvel[w], v, atol=1e-6)
            np.testing.assert_array_equal(grav[w], g)
            np.testing.assert_array_equal(welds[w], e)
            np.testing.assert_array_equal(kept[w], book)
            assert got_held[w] == h
        assert (got_held[:60] == -1).all() and (got_held[60:] >= 0).any()  # let go of it; kept another
    finally:
        env.close()


def random_rotations(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` uniform unit quaternions (w, x, y, z) and their rotation matrices (n, 3, 3)."""
    quat = rng.normal(size=(n, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    mats = np.zeros((n, 9))
    for q, mat in zip(quat, mats, strict=True):
        mujoco.mju_quat2Mat(mat, q)
    return quat, mats.reshape(n, 3, 3)


def test_the_seal_kernels_find_and_weld_the_box_the_cpu_vacuum_seal_does():
    """``seal_find`` and ``seal_make`` against ``VacuumSeal.update`` on 300 drawn worlds: suction on or off, a box
    held or not, contacts of the pad with a box at angles across the seal angle (either face), of the pad with
    another geom, of a box with another geom; where it seals, the same box, weld (the box's pose in the cup's frame)
    and grip (offset from the cup's axis [m], turn [deg])."""
    import warp as wp
    from mujoco_warp._src.types import vec11

    from colorsort.batched import kernels as K
    from colorsort.cell.suction import SEAL_ANGLE_DEG

    env = new_env()
    try:
        plant, m, d = env.plant, env.mj_model, env.mj_data
        pool, seal, W = plant.pool, plant.seal, 300
        P, rng, E = len(pool.boxes), np.random.default_rng(5), 40
        struct, host = cpu_pool(env, W)
        status, color, bins, serial = drawn_boxes(rng, W, P)
        serial = rng.permutation(E)[:P][None].repeat(W, 0)
        suction = rng.choice([0, 1], W, p=[0.2, 0.8])
        held = np.where(rng.random(W) < 0.2, rng.integers(0, P, W), -1)
        cup_quat, cup_mat = random_rotations(rng, W)
        box_quat, _ = random_rotations(rng, W)
        xquat = np.repeat(d.xquat[None], W, 0)
        xmat = np.repeat(d.xmat[None], W, 0).reshape(W, -1, 3, 3)
        xquat[:, seal.cup], xmat[:, seal.cup] = cup_quat, cup_mat
        host.xpos[:, seal.cup] = rng.uniform(-1, 1, (W, 3))
        floor = m.geom("floor").id
        contacts = []  # (world, geom1, geom2, normal)
        for w in range(W):
            axis = cup_mat[w][:, 2]
            for kind in rng.choice(["pad-box", "pad-other", "box-other"], rng.integers(0, 4), replace=False):
                box = int(rng.integers(0, P))
                host.xpos[w, pool.body[box]] = host.xpos[w, seal.cup] + cup_mat[w] @ rng.uniform(-0.03, 0.03, 3)
                xquat[w, pool.body[box]] = box_quat[w]
                tilt = np.deg2rad(rng.uniform(0, 2 * SEAL_ANGLE_DEG))
                side = np.cross(axis, rng.normal(size=3))
                normal = (np.cos(tilt) * axis + np.sin(tilt) * side / np.linalg.norm(side)) * rng.choice([-1, 1])
                pair = {"pad-box": (seal.pad, pool.geom[box]), "pad-other": (seal.pad, floor),
                        "box-other": (pool.geom[box], floor)}[str(kind)]
                contacts.append((w, *(pair if rng.random() < 0.5 else pair[::-1]), normal))
        lo, hi = m.actuator_ctrlrange[seal.actuator]
        want, sealed = [], []
        real_data = seal.data
        for w in range(W):
            mine = [c for c in contacts if c[0] == w]
            frame = np.zeros((len(mine), 9))
            frame[:, :3] = np.reshape([c[3] for c in mine], (-1, 3))
            ctrl = np.zeros(m.nu)
            ctrl[seal.actuator] = hi if suction[w] else lo
            seal.data = SimpleNamespace(  # the contacts MuJoCo would list, and the poses the seal reads
                xmat=xmat[w].reshape(-1, 9), xquat=xquat[w], xpos=host.xpos[w], ctrl=ctrl,
                eq_active=np.zeros(m.neq), ncon=len(mine),
                contact=SimpleNamespace(geom1=[c[1] for c in mine], geom2=[c[2] for c in mine], frame=frame))
            seal.held = int(held[w]) if held[w] >= 0 else None
            seal.update()
            seal.data = real_data
            new = seal.held is not None and held[w] < 0
            sealed.append(new)
            want.append((seal.held if new else -1, m.eq_data[seal.welds[seal.held]].copy() if new else None,
                         seal.grip() if new else None))
        with wp.ScopedDevice("cpu"):
            C = max(len(contacts), 1)
            geom = wp.array(np.int32([c[1:3] for c in contacts]).reshape(-1, 2), dtype=wp.vec2i)
            frame = np.zeros((C, 3, 3), np.float32)
            frame[: len(contacts), 0] = np.reshape([c[3] for c in contacts], (-1, 3))
            worldid = wp.array(np.int32([c[0] for c in contacts]), dtype=int)
            of_geom = np.full(m.ngeom, -1, np.int32)
            of_geom[pool.geom] = np.arange(P)
            cup_held = wp.array(np.int32(held), dtype=int)
            candidate = wp.full(W, P, dtype=int)
            wxmat = wp.array(xmat.astype(np.float32), dtype=wp.mat33)
            wp.launch(K.seal_find, dim=C, inputs=[
                wp.array([len(contacts)], dtype=int), geom, wp.array(frame, dtype=wp.mat33), worldid, seal.pad,
                wp.array(of_geom, dtype=int), seal.cup, wxmat, wp.array(np.int32(suction), dtype=int), cup_held,
                float(np.cos(np.deg2rad(SEAL_ANGLE_DEG))), candidate])
            found = candidate.numpy().copy()
            sim, boxes = bodies(host), boxes_struct(status, color, bins, serial)
            eq_data = wp.array(np.repeat(m.eq_data[None], W, 0).astype(np.float32), dtype=vec11)
            grips = wp.full((W, E, 2), float("nan"), dtype=float)
            wp.launch(K.seal_make, dim=W, inputs=[candidate, struct, boxes, seal.cup, sim,
                                                  wp.array(xquat.astype(np.float32), dtype=wp.quat), wxmat, eq_data,
                                                  cup_held, grips])
            got_eq, got_active, got_held, got_grips = eq_data.numpy(), sim.eq_active.numpy(), cup_held.numpy(), \
                grips.numpy()
        for w, (box, weld, grip) in enumerate(want):
            assert (found[w] < P) == (box >= 0), w
            if box < 0:
                assert got_held[w] == held[w] and not got_active[w].any()
                continue
            assert found[w] == box and got_held[w] == box and got_active[w, seal.welds[box]]
            np.testing.assert_allclose(got_eq[w, seal.welds[box], :10], weld[:10], atol=1e-5)
            offset, turn = got_grips[w, serial[w, box]]
            assert offset == pytest.approx(grip[0], abs=1e-5)
            assert (turn - grip[1] + 45.0) % 90.0 - 45.0 == pytest.approx(0.0, abs=1e-3)
        assert 20 <= sum(sealed) <= W - 20  # it sealed in some worlds and not in others
    finally:
        env.close()
