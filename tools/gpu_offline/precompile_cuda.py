"""Compile the batched cell's Warp kernels for a CUDA GPU on a machine without one, into a kernel cache to carry.

    python tools/gpu_offline/precompile_cuda.py --specs DIR --out CACHE [--arch 90]

A GPU machine compiles every kernel of MuJoCo Warp and the cell the first time it builds a cell (minutes: Warp's
NVRTC, one module after another). Warp keeps what it compiled in its kernel cache, a folder per module named by a
hash of the module's code and options, and skips the compile wherever the cache already holds the module's
binary for the device's architecture. Warp's NVRTC compiles without a GPU, so this script builds a few worlds of
each saved cell (``--specs``, one folder per variant, as ``bundle.sh`` saves them) on Warp's CPU device, with the
snapshot camera, and steps them; each time Warp loads a module for the CPU it also compiles that module, as it is
then, for ``sm_<arch>`` with the block size a CUDA launch would use, into ``--out``. On the GPU machine, that
folder's contents go into Warp's kernel cache (``warp.config.kernel_cache_dir``). A module the CPU run never loads
(code MuJoCo Warp runs on CUDA alone, such as conditional graph nodes) is compiled there as before; a module whose
hash differs is simply not found: the cache can make the first build faster, never wrong.

The binaries are CUBIN, what Warp chooses where the driver is older than its NVRTC (CUDA 13.4 in warp-lang 1.19.0;
the H200 machines' driver is CUDA 13.0); with a newer driver Warp asks for PTX and compiles as before.
"""

from __future__ import annotations

import argparse
import contextvars
import sys
import time
from pathlib import Path

CUDA_DEFAULT_BLOCK_DIM = 256  # warp._src.context._resolve_launch_block_dim's default on CUDA

raw_block_dim: contextvars.ContextVar[int | None] = contextvars.ContextVar("raw_block_dim", default=None)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--specs", required=True, help="saved CellSpecs, one folder per variant")
    parser.add_argument("--out", required=True, help="the kernel cache to write")
    parser.add_argument("--arch", type=int, default=90, help="the GPU's compute capability (90: H100, H200)")
    parser.add_argument("--image-size", type=int, default=32, help="the snapshot camera's size [px]")
    parser.add_argument("--check", action="store_true",
                        help="compile nothing: count the modules the run loads whose binary --out already holds")
    args = parser.parse_args()

    import warp as wp

    wp.config.kernel_cache_dir = str(Path(args.out).resolve())
    wp.config.quiet = True
    from warp._src import context as wpc

    launch = wpc.launch

    def recording_launch(*a, **kw):
        token = raw_block_dim.set(kw.get("block_dim"))
        try:
            return launch(*a, **kw)
        finally:
            raw_block_dim.reset(token)

    wp.launch = wpc.launch = recording_launch  # launch_tiled calls the module's global

    load = wpc.Module.load
    done: set[tuple[str, bytes]] = set()
    failed: list[str] = []

    def load_and_compile(self, device, block_dim=None, *a, **kw):
        if wpc.runtime.get_device(device).is_cpu:
            raw = raw_block_dim.get()
            cuda_block_dim = raw if raw is not None and raw > 0 else CUDA_DEFAULT_BLOCK_DIM
            key = (self.name, self.get_module_hash(cuda_block_dim))
            if key not in done and args.check:
                done.add(key)
                folder = Path(wp.config.kernel_cache_dir) / self.get_module_identifier(cuda_block_dim)
                if not any(folder.glob(f"*.sm{args.arch}*.cubin")):
                    failed.append(f"{self.name}: not in the cache")
            elif key not in done:
                done.add(key)
                try:
                    self._compile(None, None, None, args.arch, False, self.resolved_options[cuda_block_dim])
                except Exception as error:  # a module NVRTC refuses is compiled on the GPU, as without this cache
                    failed.append(f"{self.name}: {type(error).__name__}: {str(error)[:200]}")
        return load(self, device, block_dim, *a, **kw)

    wpc.Module.load = load_and_compile

    import numpy as np
    import torch

    from colorsort.batched.cell import BatchedCell
    from colorsort.batched.spec import CellSpec
    from colorsort.variants import get_variant

    start = time.perf_counter()
    for folder in sorted(Path(args.specs).iterdir()):
        spec = CellSpec.load(folder)
        for cameras in ((), ("snapshot",)):
            cell = BatchedCell(spec, get_variant(folder.name), 2, device="cpu", max_boxes=16, cameras=cameras,
                               image_size=(args.image_size, args.image_size))
            cell.reset([10_000, 10_001])
            hold = np.r_[spec.qpos0[spec.arm_qpos], -1.0, -1.0].astype(np.float32)
            for _ in range(3):
                cell.step(torch.as_tensor(np.tile(hold, (2, 1))))
        print(f"{folder.name}: {len(done)} modules so far, {time.perf_counter() - start:.0f} s", flush=True)
    binaries = sorted(Path(args.out).rglob(f"*.sm{args.arch}*.cubin"))
    size = sum(p.stat().st_size for p in binaries)
    if args.check:
        print(f"{len(done) - len(failed)} of the {len(done)} modules the run loads have their sm_{args.arch} binary "
              f"in {args.out}")
    else:
        print(f"{len(binaries)} CUBIN modules for sm_{args.arch} ({size / 2**20:.1f} MiB) in {args.out}, "
              f"{time.perf_counter() - start:.0f} s; {len(failed)} refused")
    for line in failed:
        print("  ", line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
