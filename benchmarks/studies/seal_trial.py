"""A seal trial: how fast may a box move under the cup and still be sealed and lifted? Measured, not assumed.

For a relative speed v [m/s] the belt (a tracking belt, which never stops) runs at v and the cup, held still
over the belt, comes down onto a box as the tracking expert of version 1 did (``dip_heights``: down 4.3 cm
in 0.2 s with suction on, 0.05 s on the box, up until the box's bottom is 5 cm over the belt in 0.15 s), the
box timed to arrive under it as the pad lands. ``trial`` says whether the vacuum sealed, whether the box came
up with the cup, the box's offset from the cup's axis once lifted [mm] and its tilt [deg]. The tracking expert
matches the belt's velocity, so the relative speed it seals at is its matching error; ``benchmarks/bench_seal.py``
prints the margin over a range of speeds.
"""

from __future__ import annotations

import numpy as np

from colorsort.config import CellLayout
from colorsort.envs.robosuite_task import ColorSort
from colorsort.expert.calibration import Calibration
from colorsort.expert.config import ExpertConfig
from colorsort.expert.planning import CupIK, DensePath, Waypoint, site_yaw
from colorsort.expert.tracking import smoothstep

DESCEND, HOLD, LIFT = 0.2, 0.05, 0.15  # [s]


def dip_heights(layout: CellLayout, dt: float) -> np.ndarray:
    """Cup heights [m], one per control period ``dt`` [s]: from 4 cm over a 10 cm box's top down 3 mm into it in
    ``DESCEND``, held ``HOLD``, then up until the box's bottom is 5 cm over the belt in ``LIFT``."""
    top = layout.belt_top_z + layout.box_size
    z_over, z_on, z_up = top + 0.04, top - 0.003, top + 0.05
    tau = dt * np.arange(int(np.ceil((DESCEND + HOLD + LIFT) / dt)) + 1)
    down = z_over + (z_on - z_over) * np.array([smoothstep(u) for u in tau / DESCEND])
    up = z_on + (z_up - z_on) * np.array([smoothstep(u) for u in (tau - DESCEND - HOLD) / LIFT])
    return np.where(tau <= DESCEND, down, up)


def trial(speed: float, robot: str = "IRB140", x_cup: float = 0.42) -> dict:
    """One pick of a box moving at ``speed`` [m/s] under a cup held still over ``x_cup`` [m]."""
    env = ColorSort(robots=robot, preset="tracking", belt_speed=speed, spawn_period=600.0, seed=0,
                    has_offscreen_renderer=False, ignore_done=True)
    obs = env.reset()
    for box in env.boxes_in_play():
        env.remove_box(box)
    cfg, L, dt = ExpertConfig(), env.layout, env.control_timestep
    cal = Calibration.from_env(env, (cfg.sensor_image_size,) * 2)
    ik = CupIK(cal.kinematics, cal.home)
    yaw = site_yaw(ik.cup_pose(cal.home)[1])
    heights = dip_heights(L, dt)  # with the cup held still over x_cup
    q_over = ik.solve(Waypoint("over", (x_cup, L.belt_y, heights[0]), yaw), cal.home)
    for k in range(40):  # 2 s: to the pose over the belt, and settle
        s = smoothstep(min(1.0, k / 30))
        obs, _, _, _ = env.step(np.concatenate([cal.home + s * (q_over - cal.home), [-1.0, -1.0]]))
    joints, q = [q_over], q_over
    for z in heights[1:]:
        q = ik.solve(Waypoint("down and up", (x_cup, L.belt_y, z), yaw), q)
        joints.append(q)
    path = DensePath(np.array(joints), dt)
    box = env.put_box("red", x_cup + speed * DESCEND, L.belt_y)  # under the cup as the pad lands
    obs = env.observe()
    sealed = False
    for k in range(len(heights) + 10):
        ref, vel, _ = path.sample((k + 1) * dt)
        obs, _, _, info = env.step(np.concatenate([ref + cal.lead * vel, [1.0, -1.0]]))
        sealed = sealed or info["suction_sealed"]
    # came up with the cup: its bottom more than half the lift over the belt
    lifted = (box.status.value == "in_play"
              and env.box_pos(box)[2] > L.belt_top_z + L.box_size / 2 + cfg.track_lift_gap / 2)
    cup = np.asarray(obs["robot0_eef_pos"])
    offset = 1000 * float(np.hypot(*(env.box_pos(box)[:2] - cup[:2]))) if lifted else float("nan")
    w = env.plant.pool.pose(box)[3]
    tilt = float(np.degrees(2 * np.arccos(min(1.0, abs(w))))) if lifted else float("nan")
    held = bool(info["suction_sealed"])
    env.close()
    return {"speed": speed, "sealed": bool(sealed), "held": held, "lifted": bool(lifted), "offset_mm": offset,
            "turn_deg": tilt}
