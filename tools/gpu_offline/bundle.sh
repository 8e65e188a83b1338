#!/bin/bash
# Pack what the GPU benchmarks need onto a CUDA machine that has Python 3.12 with PyTorch, torchvision, numpy,
# opencv, pyarrow, pandas, scipy and numba but no network (and no robosuite assets): the packages such an image
# lacks (taken from this checkout's .venv), the shipped policies the benchmarks evaluate and each variant's compiled
# cell (CellSpec, built here with robosuite). The archive is split into parts of PART_BYTES for transfer limits.
#
#   sh tools/gpu_offline/bundle.sh [OUT]       # OUT: outputs/gpu-bundle; then carry OUT/part-* and run.sh
#   WARP_CPU=1 sh tools/gpu_offline/bundle.sh  # keeps Warp's CPU compiler: run.sh with DEV=cpu checks the bundle here
#
# What the list holds was measured: the batched evaluation's imports in an environment of only such an image's
# packages plus these (docs/gpu.md, "On a GPU machine without network").
set -eu
OUT=${1:-outputs/gpu-bundle}
PART_BYTES=${PART_BYTES:-60000000}
POLICIES=${POLICIES:-"act-state act-camera-snapshot"}
VARIANTS=${VARIANTS:-"seed default fast jitter lighting distractors"}
SP=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
B=$(mktemp -d)
CPU_COMPILER=--exclude=warp/bin/warp-clang.so
[ -n "${WARP_CPU:-}" ] && CPU_COMPILER=
mkdir -p "$B/pol" "$OUT"
PKGS="robosuite lerobot draccus mergedeep datasets dill multiprocess gymnasium farama_notifications termcolor OpenGL
      glfw mujoco mujoco_warp warp av av.libs"
DISTS=$(cd "$SP" && ls -d robosuite-*.dist-info lerobot-*.dist-info draccus-*.dist-info mergedeep-*.dist-info \
        datasets-*.dist-info dill-*.dist-info multiprocess-*.dist-info gymnasium-*.dist-info \
        farama_notifications-*.dist-info termcolor-*.dist-info pyopengl-*.dist-info glfw-*.dist-info \
        mujoco-*.dist-info mujoco_warp-*.dist-info warp_lang-*.dist-info av-*.dist-info)
# robosuite's meshes and textures and Warp's CPU compiler, examples and tests are not needed to step the cell on a GPU;
# the CPU cell of a state policy needs robosuite's base.xml and bases/null_mount.xml alone
tar -C "$SP" -cf - --exclude=__pycache__ --exclude=robosuite/models/assets/robots \
    --exclude=robosuite/models/assets/grippers --exclude=robosuite/models/assets/bullet_data \
    --exclude=robosuite/models/assets/bases/meshes --exclude=robosuite/models/assets/textures \
    --exclude=robosuite/models/assets/objects ${CPU_COMPILER} --exclude=warp/examples \
    --exclude=warp/tests $PKGS $DISTS | xz -T0 -6 > "$B/pkgs.tar.xz"
for p in $POLICIES; do
    mkdir -p "$B/pol/$p" && cp baselines/"$p"/*.json baselines/"$p"/*.safetensors "$B/pol/$p/"
done
MUJOCO_GL=${MUJOCO_GL:-egl} .venv/bin/python - "$B/specs" $VARIANTS <<'PY'
import sys
from colorsort.batched.spec import spec_for_variant
for variant in sys.argv[2:]:
    spec_for_variant(variant).save(f"{sys.argv[1]}/{variant}")
PY
# the CUDA kernels compiled here for the GPU's architecture (precompile_cuda.py), Warp's kernel cache there
HF_HUB_OFFLINE=1 .venv/bin/python "$(dirname "$0")/precompile_cuda.py" --specs "$B/specs" --out "$B/cache" \
    --arch "${CUDA_ARCH:-90}"
(cd "$B/cache"/* && find . -name "*.cubin" -printf '%h\n' | sort -u | tar -cf - -T - | xz -T0 -6 > "$B/warp-cache.tar.xz")
rm -rf "$B/cache"
rm -f "$OUT"/part-*
tar -C "$B" -cf - . | split -b "$PART_BYTES" - "$OUT/part-"
cp "$(dirname "$0")/run.sh" "$OUT/"
rm -rf "$B"
ls -l "$OUT"
