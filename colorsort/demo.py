"""Run the cell headless with a simple scripted arm motion and film it.

Example::

    colorsort-demo --seconds 60 --out outputs --width 640 --height 480

writes ``outputs/cell.mp4`` (the scene camera) and ``outputs/cell.png`` (its last frame).
The arm sweeps between its home pose and poses over the bins while the belt brings boxes to
the sensor and stops; the scripted expert that sorts them arrives with the planner.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np
import robosuite as suite
from tqdm import tqdm

import colorsort  # noqa: F401  (registers the task)
from colorsort.video import VideoWriter, save_png

logger = logging.getLogger("colorsort.demo")

# Joint-space sweep of the IRB 140 [rad]: home, then turned toward each bin, wrist kept down.
SWEEP = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 1.5708, 0.0],
        [0.35, 0.25, -0.05, 0.0, 1.37, 0.0],
        [0.75, 0.30, -0.10, 0.0, 1.37, 0.0],
        [0.95, 0.45, -0.15, 0.0, 1.27, 0.0],
    ]
)
SEGMENT_S = 2.5  # time per sweep segment [s]


def sweep_target(t: float) -> np.ndarray:
    """Joint target [rad] at time ``t`` [s]: a smooth back-and-forth through ``SWEEP``."""
    path = np.concatenate([SWEEP, SWEEP[-2:0:-1]])
    seg, s = divmod(t / SEGMENT_S, 1.0)
    a, b = path[int(seg) % len(path)], path[(int(seg) + 1) % len(path)]
    s = 3 * s**2 - 2 * s**3
    return a + s * (b - a)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0, help="sim time to run [s]")
    p.add_argument("--out", type=Path, default=Path("outputs"), help="output folder")
    p.add_argument("--width", type=int, default=640, help="video width [px]")
    p.add_argument("--height", type=int, default=480, help="video height [px]")
    p.add_argument("--preset", default="default", help="task preset")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if args.seconds <= 0:
        print("--seconds must be positive", file=sys.stderr)
        return 2
    env = suite.make("ColorSort", robots="IRB140", preset=args.preset, seed=args.seed, ignore_done=True,
                     has_offscreen_renderer=True, use_camera_obs=False)
    env.reset()
    steps = int(round(args.seconds * env.control_freq))
    video_path, still_path = args.out / "cell.mp4", args.out / "cell.png"
    start = time.perf_counter()
    frame = None
    with VideoWriter(video_path, fps=env.control_freq) as video:
        for _ in tqdm(range(steps), desc="simulating", unit="step"):
            _, _, _, info = env.step(np.concatenate([sweep_target(env.cur_time), [-1.0, -1.0]]))
            frame = env.sim.render(camera_name="scene", width=args.width, height=args.height)[::-1]
            video.write(frame)
    save_png(still_path, frame)
    wall = time.perf_counter() - start
    print(f"{args.seconds:.0f} s of sim in {wall:.1f} s wall ({args.seconds / wall:.2f}x real time); "
          f"boxes spawned {info['spawned']}, belt running {info['belt_running']}")
    print(f"video: {video_path} ({video.frames} frames)\nstill: {still_path}")
    env.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
