"""Speed of the ColorSort env, measured side by side in one run on one compiled model.

    python benchmarks/bench_env.py [--robot IRB140] [--seconds 3] [--repeats 5]

Prints raw ``mujoco.mj_step`` steps/s, the env's physics steps/s through ``env.step`` (the
controller, belt, seal and bookkeeping included) and their ratio, each measured ``--repeats`` times
alternately (median and range; the ratio of each pair), and frames/s of each camera at 128x128 and
480x640. Both loops run the same scene: the arm holding its home pose, boxes riding the belt and
queueing at the sensor.
"""

from __future__ import annotations

import argparse
import copy
import statistics
import time

import colorsort  # noqa: F401 - first: it picks the headless GL backend (MUJOCO_GL) before MuJoCo loads one

# isort: split
import mujoco
import numpy as np
import robosuite as suite

from colorsort.cell.cameras import CAMERAS, WRIST_CAMERA_MJCF
from colorsort.results import recorded


def timed(fn, seconds: float) -> float:
    """Calls of ``fn`` per second over about ``seconds`` [s] of wall time."""
    n, start = 0, time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds:
        fn()
        n += 1
    return n / elapsed


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--robot", default="IRB140")
    p.add_argument("--seconds", type=float, default=3.0, help="wall time per measurement [s]")
    p.add_argument("--repeats", type=int, default=5, help="alternated measurements of raw and env speed")
    args = p.parse_args()

    env = suite.make("ColorSort", robots=args.robot, seed=0, ignore_done=True, has_offscreen_renderer=True)
    env.reset()
    hold = np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]])  # suction off, no belt pass
    for _ in range(100):  # warm up; boxes on the belt
        env.step(hold)
    substeps = int(round(env.control_timestep / env.model_timestep))

    # Raw physics on a copy of the same compiled model and state, controls frozen.
    model = env.mj_model
    data = copy.copy(env.mj_data)
    raws, envs = [], []
    for _ in range(args.repeats):  # alternated: a load that comes and goes touches both
        raws.append(timed(lambda: mujoco.mj_step(model, data), args.seconds))
        envs.append(timed(lambda: env.step(hold), args.seconds) * substeps)
    ratios = [e / r for e, r in zip(envs, raws, strict=True)]

    def spread(values: list[float], form: str) -> str:
        return f"{format(statistics.median(values), form):>12} {format(min(values), form)}-{format(max(values), form)}"

    print(f"{'measure':<34}{'median':>12} range over {args.repeats} repeats")
    print(f"{'raw mj_step [steps/s]':<34}{spread(raws, ',.0f')}")
    print(f"{'env.step physics [steps/s]':<34}{spread(envs, ',.0f')}")
    print(f"{'env / raw':<34}{spread(ratios, '.2f')}")
    print(f"{'env real-time factor':<34}{statistics.median(envs) * env.model_timestep:>12.1f}")
    for h, w in ((128, 128), (480, 640)):
        for cam in CAMERAS:
            name = WRIST_CAMERA_MJCF if cam == "wrist" else cam
            env.sim.render(camera_name=name, width=w, height=h)  # allocate buffers
            fps = timed(lambda name=name, w=w, h=h: env.sim.render(camera_name=name, width=w, height=h),
                        args.seconds / 2)
            print(f"{f'{cam} camera {h}x{w} [frames/s]':<34}{fps:>12.1f}")
    env.close()


if __name__ == "__main__":
    with recorded(__file__):
        main()
