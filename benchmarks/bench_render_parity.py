"""How differently MuJoCo Warp's renderer and MuJoCo's OpenGL renderer draw the same states of the cell.

    python benchmarks/bench_render_parity.py

The CPU cell runs the scripted expert on a few seeds; at fixed steps (a box on the belt, under the
sensor, in the cup, over a bin) its state is saved and its cameras rendered by OpenGL. The batched
cell (``--device``: Warp's CPU device by default) is set to the same states, one world each, and
renders the same cameras. Per camera: the mean absolute difference of the two images over pixels and
channels [0-255], and the same difference after each image is scaled to its own mean brightness (what is
left once the overall exposure is matched). ``--png`` writes the pairs side by side.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from colorsort.results import recorded


def main() -> int:
    with recorded(__file__):
        return run()


def run() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--variant", default="default")
    parser.add_argument("--seeds", default="10000,10001")
    parser.add_argument("--steps", default="20,60,100,140", help="control steps at which states are taken")
    parser.add_argument("--cameras", default="scene,sensor,wrist")
    parser.add_argument("--image-size", type=int, default=64)
    parser.add_argument("--device", default="cpu", help="Warp's device")
    parser.add_argument("--png", default=None, help="write the image pairs here")
    args = parser.parse_args()

    import torch
    import warp as wp

    import colorsort  # noqa: F401  (registers the task)
    from colorsort.batched.cell import BatchedCell
    from colorsort.batched.spec import CellSpec, air_park_position
    from colorsort.benchmark.policies import ExpertPolicy
    from colorsort.envs.gym_env import ColorSortGymEnv
    from colorsort.variants import get_variant

    wp.config.quiet = True
    cameras = tuple(args.cameras.split(","))
    size = (args.image_size, args.image_size)
    env = ColorSortGymEnv(args.variant, cameras=cameras, image_size=size, render_mode=None)
    expert = ExpertPolicy()
    steps = sorted(int(s) for s in args.steps.split(","))
    states, cpu_images = [], []
    spec = None
    for seed in (int(s) for s in args.seeds.split(",")):
        obs, _ = env.reset(seed=seed)
        expert.reset(env, seed)
        spec = spec or CellSpec.from_env(env.env)
        for step in range(1, steps[-1] + 1):
            obs, *_ = env.step(expert.act(obs))
            if step in steps:
                cell = env.env
                qpos = cell.mj_data.qpos.copy()
                parked = [b.index for b in cell.boxes if b.status.value == "parked"]
                for i in parked:
                    qa = cell.plant.pool.qpos[i]
                    qpos[qa : qa + 7] = (*air_park_position(i), 1.0, 0.0, 0.0, 0.0)
                states.append((seed, step, qpos, cell.mj_model.geom_rgba[spec.box_geom].copy()))
                cpu_images.append({c: obs["pixels"][c].copy() for c in cameras})
    env.close()
    n = len(states)
    batched = BatchedCell(spec, get_variant(args.variant), n, device=args.device, cameras=cameras, image_size=size)
    batched.reset([s[0] for s in states])
    with wp.ScopedDevice(batched.device):
        q = wp.to_torch(batched.d.qpos)
        rgba = wp.to_torch(batched.m.geom_rgba)
        for w, (_, _, qpos, colors) in enumerate(states):
            q[w] = torch.as_tensor(qpos, dtype=torch.float32, device=q.device)
            rgba[w, torch.as_tensor(spec.box_geom)] = torch.as_tensor(colors, dtype=torch.float32, device=q.device)
        import mujoco_warp as mjw

        mjw.forward(batched.m, batched.d)
        batched._render()
    rows = []
    pairs = []
    for c in cameras:
        warp_img = batched.images[c].cpu().numpy().astype(np.float64)
        cpu_img = np.stack([im[c] for im in cpu_images]).astype(np.float64)
        mad = np.abs(warp_img - cpu_img).mean()
        ratio = np.abs(warp_img / max(warp_img.mean(), 1e-9) - cpu_img / max(cpu_img.mean(), 1e-9)).mean()
        scaled = ratio * cpu_img.mean()
        rows.append((c, mad, scaled, cpu_img.mean(), warp_img.mean()))
        pairs.append(np.concatenate([np.concatenate([a, b], 1) for a, b in zip(cpu_img, warp_img, strict=True)], 0))
    lines = [f"Render parity, MuJoCo Warp against MuJoCo's OpenGL renderer: {n} states of `{args.variant}` (seeds "
             f"{args.seeds}, control steps {args.steps} of the scripted expert), {args.image_size} px, Warp device "
             f"`{args.device}`.",
             "", "| camera | mean abs. difference [0-255] | after matching brightness | OpenGL mean | Warp mean |",
             "| --- | --- | --- | --- | --- |"]
    lines += [f"| {c} | {mad:.1f} | {scaled:.1f} | {a:.1f} | {b:.1f} |" for c, mad, scaled, a, b in rows]
    print("\n".join(lines))
    if args.png:
        import cv2

        Path(args.png).mkdir(parents=True, exist_ok=True)
        for c, img in zip(cameras, pairs, strict=True):
            cv2.imwrite(str(Path(args.png) / f"{c}.png"), cv2.resize(img.astype(np.uint8)[:, :, ::-1], None, fx=3, fy=3,
                                                                      interpolation=cv2.INTER_NEAREST))
    return 0


if __name__ == "__main__":
    sys.exit(main())
