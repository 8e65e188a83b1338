"""The batched cell on MuJoCo Warp against MuJoCo's CPU step, side by side in one run.

Run on a machine with a CUDA GPU and the ``gpu`` extra (``pip install -e ".[gpu]"``)::

    python benchmarks/bench_warp.py --policy baselines/act-camera-snapshot --policy-worlds 4096 --policy-episodes 8192

It measures, in one process on one machine:
- the first build of the batched cell (Warp's kernel compile, cached afterwards under ~/.cache/warp);
- control steps per second of the batched cell with every rule on (belt, ray, seal, referee,
  spawner, joint servo), for each number of worlds: the arm holds its home pose, boxes ride the belt;
  physics steps per second are that times the physics steps of a control step;
- MuJoCo's C ``mj_step`` on the same compiled model in ``--cpu-procs`` processes (one per core): physics
  only, no rules and no controller, an upper bound on what the CPU cell steps;
- a policy evaluated on the batched cell (``--policy``, state or camera), ``--policy-episodes`` episodes on
  ``N`` worlds (``evaluate_batched``: a world that finished starts the next episode while the others run):
  episodes per minute from start to the last episode's end, the success rate with its 95% interval, and
  how many episodes ran into the time limit (each holds its world for the whole limit);
- with ``--cpu-policy-episodes N``, the same policy on the CPU cell (robosuite, ``colorsort-eval``'s path) in
  ``--cpu-procs`` processes on the same seeds: the CPU path's episodes per minute beside the batched cell's.
Figures go to stdout and to ``docs/results/bench_warp_<arguments>.md`` (``colorsort.results``).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import platform
import sys
import time
from pathlib import Path

from colorsort.results import recorded


def cpu_steps(args: tuple[str, int]) -> float:
    """mj_step per second of one process on the saved model (boxes parked, arm at home)."""
    import mujoco

    folder, steps = args  # read with mujoco alone: a spawned process need not import the package
    model = mujoco.MjModel.from_binary_path(str(Path(folder) / "cell.mjb"))
    d = mujoco.MjData(model)
    d.qpos[:] = json.loads((Path(folder) / "cell.json").read_text())["qpos0"]
    mujoco.mj_forward(model, d)
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, d)
    return steps / (time.perf_counter() - start)


def main() -> int:
    with recorded(__file__):
        return run()


def run() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spec", default=None, help="a saved CellSpec folder (default: build the variant's cell)")
    parser.add_argument("--variant", default="default")
    parser.add_argument("--device", default="cuda:0", help="Warp's device")
    parser.add_argument("--worlds", default="1,64,512,4096,8192", help="world counts to step")
    parser.add_argument("--steps", type=int, default=20, help="timed control steps per world count")
    parser.add_argument("--policy", default=None, help="a LeRobot checkpoint to evaluate")
    parser.add_argument("--policy-worlds", default="1024,4096", help="worlds per evaluation")
    parser.add_argument("--policy-episodes", type=int, default=None, help="episodes per evaluation (default: worlds)")
    parser.add_argument("--episode-length", type=int, default=None, help="policy episodes' step limit")
    parser.add_argument("--cpu-policy-episodes", type=int, default=0,
                        help="episodes of the policy on the CPU cell in --cpu-procs processes (0: none)")
    parser.add_argument("--render-worlds", default="1024,4096", help="worlds whose cameras are rendered at once")
    parser.add_argument("--cameras", default="sensor,wrist", help="cameras rendered in the render timing")
    parser.add_argument("--image-size", type=int, default=64, help="their size [px]")
    parser.add_argument("--cpu-procs", type=int, default=os.cpu_count(), help="processes for the CPU reference")
    parser.add_argument("--cpu-steps", type=int, default=3000)
    parser.add_argument("--json", default=None, help="write the figures as JSON here")
    parser.add_argument("--cold", action="store_true",
                        help="compile into an empty kernel cache, so that the first build is a cold compile")
    args = parser.parse_args()

    import numpy as np
    import torch
    import warp as wp

    wp.config.quiet = True
    if args.cold:  # before Warp initialises (MuJoCo Warp's import does)
        import tempfile

        wp.config.kernel_cache_dir = tempfile.mkdtemp(prefix="warp-cold-")

    from colorsort.batched.cell import BatchedCell
    from colorsort.batched.spec import CellSpec, spec_for_variant
    from colorsort.variants import get_variant

    variant = get_variant(args.variant)
    if args.spec is None:
        args.spec = str(spec_for_variant(variant.name).save(Path("outputs") / "cellspec" / variant.name))
    spec = CellSpec.load(args.spec)
    device = wp.get_device(args.device)
    gpu = torch.cuda.get_device_name(device.ordinal) if device.is_cuda else platform.processor() or "cpu"
    figures: dict = {"device": gpu, "variant": variant.name, "substeps": spec.substeps, "worlds": {}}
    hold = np.r_[spec.qpos0[spec.arm_qpos], -1.0, -1.0].astype(np.float32)
    worlds = [int(w) for w in args.worlds.split(",")]
    for k, n in enumerate(worlds):
        start = time.perf_counter()  # a world count that fails (memory) is reported, the others still run
        try:
            cell = BatchedCell(spec, variant, n, device=args.device, max_boxes=16)
            cell.reset(list(range(10_000, 10_000 + n)))
            action = torch.as_tensor(np.tile(hold, (n, 1)), device=cell.torch_device)
            cell.step(action)
            first = time.perf_counter() - start
            if k == 0:
                figures["first_build_s"] = first
            cell.step(action)
            start = time.perf_counter()
            for _ in range(args.steps):
                cell.step(action)
            per = (time.perf_counter() - start) / args.steps
            row = {"control_step_ms": 1000 * per, "control_steps_per_s": 1 / per,
                   "physics_steps_per_s": n * spec.substeps / per, "build_s": first}
        except Exception as error:
            row = {"error": f"{type(error).__name__}: {error}"[:300]}
        figures["worlds"][n] = row
        print(f"{n:>6} worlds: {row}", flush=True)
        cell = None
    figures["render"] = {}
    cameras = tuple(args.cameras.split(","))
    for n in [int(w) for w in args.render_worlds.split(",") if w]:
        try:
            cell = BatchedCell(spec, variant, n, device=args.device, max_boxes=16, cameras=cameras,
                               image_size=(args.image_size, args.image_size))
            cell.reset(list(range(10_000, 10_000 + n)))
            with wp.ScopedDevice(cell.device):
                cell._render()
                start = time.perf_counter()
                for _ in range(args.steps):
                    cell._render()
                per = (time.perf_counter() - start) / args.steps
            row = {"render_ms": 1000 * per, "images_per_s": n * len(cameras) / per}
        except Exception as error:  # a size the device cannot hold: say so, go on
            row = {"error": f"{type(error).__name__}: {error}"[:300]}
        figures["render"][n] = row
        print(f"render {n} worlds, {cameras} at {args.image_size} px: {row}", flush=True)
        cell = None
    with mp.get_context("spawn").Pool(args.cpu_procs) as pool:
        rates = pool.map(cpu_steps, [(args.spec, args.cpu_steps)] * args.cpu_procs)
    figures["cpu"] = {"procs": args.cpu_procs, "steps_per_s": float(sum(rates)), "per_proc": float(np.mean(rates))}
    print("cpu", figures["cpu"], flush=True)
    if args.policy:
        from colorsort.batched.evaluate import evaluate_batched

        figures["policy"] = {}
        for n in [int(w) for w in args.policy_worlds.split(",")]:
            episodes = args.policy_episodes or n
            batched = evaluate_batched(args.policy, variant.name, episodes, seed=10_000, envs=n, device=args.device,
                                       episode_length=args.episode_length, progress=False, spec=spec)
            report, timing = batched.report, batched.timing
            lo, hi = report.success_ci95
            row = {"worlds": n, "episodes": episodes, "seconds": timing.seconds, "control_steps": timing.control_steps,
                   "control_step_ms": 1000 * timing.seconds / timing.control_steps,
                   "time_limit": sum(e["ended"] == "time limit" for e in report.per_episode),
                   "episodes_per_min": 60 * episodes / timing.seconds, "success": report.success_rate, "ci95": [lo, hi],
                   "correct": report.correct, "misplaced": report.misplaced, "dropped": report.dropped,
                   "per_episode": [{k: e[k] for k in ("seed", "success", "ended", "steps")}
                                   | {"outcomes": [b["outcome"] for b in e["boxes"]]} for e in report.per_episode]}
            figures["policy"][n] = row
            print(f"policy {n}: { {k: v for k, v in row.items() if k != 'per_episode'} }", flush=True)
    if args.policy and args.cpu_policy_episodes:
        from colorsort.benchmark.evaluate import evaluate, observation_settings

        cameras, size = observation_settings(args.policy, None, None)
        start = time.perf_counter()
        try:
            report = evaluate(args.policy, variant.name, args.cpu_policy_episodes, seed=10_000, cameras=cameras,
                              image_size=size, episode_length=args.episode_length, envs=args.cpu_procs,
                              progress=False)
            seconds = time.perf_counter() - start
            figures["cpu_policy"] = {"episodes": report.episodes, "procs": args.cpu_procs, "seconds": seconds,
                                     "episodes_per_min": 60 * report.episodes / seconds,
                                     "success": report.success_rate, "ci95": list(report.success_ci95)}
        except Exception as error:  # the CPU cell needs robosuite's assets, and OpenGL for cameras
            figures["cpu_policy"] = {"error": f"{type(error).__name__}: {error}"[:300]}
        print("cpu policy", figures["cpu_policy"], flush=True)
    print(markdown(figures, args))
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=1, default=str))
    return 0


def markdown(f: dict, args) -> str:
    cache = "a cold compile into an empty kernel cache" if args.cold else "with the kernel cache as it was"
    lines = [f"The batched cell on MuJoCo Warp: {f['device']}; variant `{f['variant']}`, {f['substeps']} physics "
             "steps per control step.", "",
             f"First build ({cache}): "
             f"{f.get('first_build_s', float('nan')):.0f} s.", "",
             "| worlds | control step [ms] | control steps/s | physics steps/s | x CPU (all processes) |",
             "| --- | --- | --- | --- | --- |"]
    cpu = f["cpu"]["steps_per_s"]
    for n, r in f["worlds"].items():
        if "error" in r:
            lines.append(f"| {n} | {r['error']} | | | |")
            continue
        lines.append(f"| {n} | {r['control_step_ms']:.1f} | {r['control_steps_per_s']:.1f} | "
                     f"{r['physics_steps_per_s']:,.0f} | {r['physics_steps_per_s'] / cpu:.1f} |")
    if f.get("render"):
        lines += ["", f"Rendering cameras {args.cameras} at {args.image_size} px (ray-traced, every world at once):",
                  "", "| worlds | render [ms] | images/s |", "| --- | --- | --- |"]
        for n, r in f["render"].items():
            lines.append(f"| {n} | {r['error']} | |" if "error" in r else
                         f"| {n} | {r['render_ms']:.1f} | {r['images_per_s']:,.0f} |")
    lines += ["", f"CPU reference: MuJoCo's `mj_step` on the same model (no rules, no controller), "
              f"{f['cpu']['procs']} processes: {cpu:,.0f} steps/s in all, {f['cpu']['per_proc']:,.0f} per process."]
    if f.get("policy"):
        lines += ["", f"Policy `{args.policy}` on `{f['variant']}`, seeds from 10000, the policy on the same device"
                  + (f", episodes cut at {args.episode_length} steps" if args.episode_length else "") + ":", "",
                  "| worlds | episodes | wall [s] | control steps | per step [ms] | episodes/min | success (95% CI) "
                  "| correct | misplaced | dropped | at the time limit |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for n, r in f["policy"].items():
            lines.append(f"| {n} | {r['episodes']} | {r['seconds']:.1f} | {r['control_steps']} | "
                         f"{r['control_step_ms']:.1f} | {r['episodes_per_min']:,.0f} | "
                         f"{100 * r['success']:.1f}% ({100 * r['ci95'][0]:.1f}-{100 * r['ci95'][1]:.1f}%) | "
                         f"{r['correct']} | {r['misplaced']} | {r['dropped']} | {r['time_limit']} |")
    c = f.get("cpu_policy")
    if c and "error" in c:
        lines += ["", f"The CPU cell's run of the policy failed: {c['error']}"]
    elif c:
        best = max(r["episodes_per_min"] for r in f["policy"].values())
        lo, hi = c["ci95"]
        lines += ["", f"The same policy on the CPU cell (`colorsort-eval`'s path, {c['procs']} processes, the same "
                  f"seeds): {c['episodes']} episodes in {c['seconds']:.0f} s, {c['episodes_per_min']:,.0f} "
                  f"episodes/min, success {100 * c['success']:.1f}% ({100 * lo:.1f}-{100 * hi:.1f}%); the "
                  f"batched cell's best above is {best / c['episodes_per_min']:.1f} times that."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
