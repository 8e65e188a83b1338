"""A learned policy's forward pass on the CPU: batch size, memory order and precision, side by side.

    python benchmarks/bench_forward.py [--policies baselines/act-camera-tracking,baselines/act-camera]
                                       [--batch-sizes 1,8] [--repeats 12] [--threads 1]

For each checkpoint, times one action-chunk prediction (``select_action`` on a just-reset policy: ACT's whole
forward, Diffusion Policy's denoising loop) on random observations of its own shapes, under
``torch.inference_mode``, at each batch size: images in contiguous (N, 3, H, W) order as LeRobot's
``preprocess_observation`` gives them, in channels-last order (``colorsort-eval``'s), and channels-last under
bfloat16 CPU autocast (``--precision bfloat16``). Prints the minimum over ``--repeats`` (the machine is shared:
the least-disturbed run), the time per observation, and each setting's speed-up over the contiguous float32
forward at batch 1. ``--threads``: torch threads, as each
``colorsort-eval`` worker sets them (1).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import time

os.environ.setdefault("HF_HUB_OFFLINE", "1")

import torch  # noqa: E402

from colorsort.benchmark.policies import LeRobotPolicy, checkpoint_cameras  # noqa: E402
from colorsort.results import recorded  # noqa: E402

SETTINGS = (("contiguous float32", False, False), ("channels-last float32", True, False),
            ("channels-last bfloat16", True, True))


def observations(policy: LeRobotPolicy, cameras: tuple[str, ...], size: tuple[int, int] | None, n: int,
                 channels_last: bool) -> dict:
    """A preprocessed batch of ``n`` random observations of the checkpoint's shapes."""
    features = policy.policy.config.input_features
    batch: dict = {k: torch.rand(n, *f.shape) for k, f in features.items() if not k.startswith("observation.images")}
    for camera in cameras:
        assert size is not None
        image = torch.rand(n, size[0], size[1], 3).permute(0, 3, 1, 2)  # channels-last strides, as colorsort-eval
        batch[f"observation.images.{camera}"] = image if channels_last else image.contiguous()
    return policy.preprocessor({**batch, "task": [""] * n})


def forward_ms(policy: LeRobotPolicy, batch: dict, bf16: bool, repeats: int) -> float:
    """The fastest of ``repeats`` chunk predictions [ms]."""
    torch.manual_seed(0)
    best = float("inf")
    for _ in range(repeats):
        policy.policy.reset()  # an empty queue: the next select_action predicts a chunk
        autocast = torch.autocast("cpu", dtype=torch.bfloat16) if bf16 else contextlib.nullcontext()
        start = time.perf_counter()
        with torch.inference_mode(), autocast:
            policy.policy.select_action(batch)
        best = min(best, time.perf_counter() - start)
    return 1000 * best


def bench(path: str, sizes: list[int], repeats: int) -> None:
    cameras, size = checkpoint_cameras(path)
    policy = LeRobotPolicy(path)
    seen = f"cameras {'+'.join(cameras)} at {size[0]} px" if cameras and size else "no cameras"
    print(f"\n{path} ({policy.policy.config.type}, {seen}), {torch.get_num_threads()} torch threads, "
          f"minimum of {repeats}")
    print(f"{'batch':<7}{'setting':<26}{'forward [ms]':>14}{'per observation [ms]':>22}{'speed-up':>10}")
    reference = None
    for n in sizes:
        for name, channels_last, bf16 in SETTINGS:
            policy.policy.to(memory_format=torch.channels_last if channels_last else torch.contiguous_format)
            ms = forward_ms(policy, observations(policy, cameras, size, n, channels_last), bf16, repeats)
            reference = reference or ms
            print(f"{n:<7}{name:<26}{ms:>14.1f}{ms / n:>22.2f}{reference / (ms / n):>9.2f}x")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policies", default="baselines/act-camera-tracking,baselines/act-camera")
    p.add_argument("--batch-sizes", default="1,8")
    p.add_argument("--repeats", type=int, default=12)
    p.add_argument("--threads", type=int, default=1)
    args = p.parse_args()
    torch.set_num_threads(args.threads)
    for path in args.policies.split(","):
        bench(path, [int(n) for n in args.batch_sizes.split(",")], args.repeats)


if __name__ == "__main__":
    with recorded(__file__):
        main()
