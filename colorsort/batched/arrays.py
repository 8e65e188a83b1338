"""The batched cell's arrays as the kernels take them: Warp structs that group the per-box and per-world arrays
(and the cell's constant addresses), so a kernel takes a few structured arguments. ``BatchedCell`` fills them
once with arrays it writes in place, never replaces (a captured graph keeps their addresses)."""

from __future__ import annotations

import warp as wp


@wp.struct
class Pool:
    """The box pool's addresses in the model, the same in every world: each box's qpos, dof, body, geom and weld
    indices, and where it waits parked [m]."""

    size: int
    qpos: wp.array(dtype=int)
    dof: wp.array(dtype=int)
    body: wp.array(dtype=int)
    geom: wp.array(dtype=int)
    weld: wp.array(dtype=int)
    park: wp.array(dtype=wp.vec3)


@wp.struct
class Boxes:
    """Every world's boxes: status (``kernels.STATUSES`` codes), colour (``COLOR_NAMES`` index), bin
    (``BIN_COLORS`` index; -1: none) and serial (-1: not in an episode)."""

    status: wp.array2d(dtype=int)
    color: wp.array2d(dtype=int)
    bin: wp.array2d(dtype=int)
    serial: wp.array2d(dtype=int)


@wp.struct
class Bodies:
    """What the rules read and write of MuJoCo's state, every world: body positions [m], qpos, qvel, each body's
    gravity compensation (1: a parked box floats) and which welds are on."""

    xpos: wp.array2d(dtype=wp.vec3)
    qpos: wp.array2d(dtype=float)
    qvel: wp.array2d(dtype=float)
    gravcomp: wp.array2d(dtype=float)
    eq_active: wp.array2d(dtype=bool)


@wp.struct
class Events:
    """Every world's record of the boxes that left play: how many, and per event its time [s], serial, colour,
    outcome (``kernels.OUTCOMES`` codes) and bin (-1: none)."""

    count: wp.array(dtype=int)
    time: wp.array2d(dtype=wp.float64)
    serial: wp.array2d(dtype=int)
    color: wp.array2d(dtype=int)
    outcome: wp.array2d(dtype=int)
    bin: wp.array2d(dtype=int)


@wp.struct
class Controls:
    """Every world's commands and what its cup and belt report: suction on (0/1), belt pass (0/1), the box held
    (-1: none), the ray blocked (0/1), the belt running (0/1), the encoder [m]."""

    suction_cmd: wp.array(dtype=int)
    belt_pass: wp.array(dtype=int)
    held: wp.array(dtype=int)
    detected: wp.array(dtype=int)
    running: wp.array(dtype=int)
    travel: wp.array(dtype=wp.float64)


@wp.struct
class Rig:
    """The cell's drives, the same in every world: the ray's sensor index, whether the belt tracks (never stops),
    its speed [m/s], the physics step [s], the suction actuator and its off/on controls, the belt joint's addresses."""

    ray: int
    tracking: int
    speed: float
    dt: float
    suction: int
    suction_off: float
    suction_on: float
    belt_qpos: int
    belt_dof: int


@wp.struct
class Draws:
    """Every world's episode draws by serial (``schedule.episode_draws``): colour, offset off the centre line [m],
    yaw [rad]."""

    color: wp.array2d(dtype=int)
    offset: wp.array2d(dtype=float)
    yaw: wp.array2d(dtype=float)
