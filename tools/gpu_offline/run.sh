#!/bin/bash
# On the GPU machine, from a copy of the repository: unpack bundle.sh's parts (in STAGE) and run the GPU benchmarks
# of docs/gpu.md: bench_warp.py (speed from 1 to 8,192 worlds, the camera policy's episodes per minute; the state
# policy's on the batched cell and on the CPU cell in one process per core) and
# bench_warp_scores.py (each shipped policy on each variant it was scored on, 200 episodes). Results (the markdown
# docs/results would hold, JSON, logs) in RESULTS; everything ends by DEADLINE seconds.
#
#   STAGE=/tmp/stage RESULTS=/tmp/res bash tools/gpu_offline/run.sh
T0=$(date +%s); el(){ echo "[$(( $(date +%s) - T0 )) s] $*"; }; left(){ echo $(( DEADLINE - ($(date +%s) - T0) )); }
DEADLINE=${DEADLINE:-550}; DEV=${DEV:-cuda:0}; W=${W:-1,64,512,1024,4096,8192}; RW=${RW:-1024,4096,8192}
PW=${PW:-4096}; PE=${PE:-$PW}; EP=${EP:-200}; STAGE=${STAGE:-/tmp/stage}; RESULTS=${RESULTS:-/tmp/res}
SITE=${SITE:-/tmp/site}
mkdir -p "$SITE" "$RESULTS/md"
cat "$STAGE"/part-* | tar x -C "$STAGE" || { el "the parts do not make the archive"; ls -la "$STAGE"; exit 1; }
(cd "$SITE" && xz -d -T0 < "$STAGE/pkgs.tar.xz" | tar x) || { el "unpacking failed"; exit 1; }
mkdir -p baselines outputs && cp -r "$STAGE"/pol/. baselines/ && rm -rf outputs/cellspec \
    && cp -r "$STAGE/specs" outputs/cellspec
[ -e colorsort/assets ] || ln -s ../assets colorsort/assets  # what setup.py's package_dir maps, without installing
# MUJOCO_GL=disable: nothing here draws with OpenGL (Warp renders), and the machine may have no EGL
export PYTHONPATH=$SITE:$PWD HF_HUB_OFFLINE=1 PYTHONUNBUFFERED=1 MUJOCO_GL=disable COLORSORT_RESULTS=$RESULTS/md
python3 -c "import warp, mujoco_warp, lerobot, colorsort.batched.evaluate" || exit 1
CACHE=$(python3 -c "import warp; warp.config.quiet = True; warp.init(); print(warp.config.kernel_cache_dir)")
mkdir -p "$CACHE" && xz -d < "$STAGE/warp-cache.tar.xz" | tar x -C "$CACHE"  # precompile_cuda.py's kernels
el "unpacked; $(ls "$CACHE" | wc -l) modules in Warp's kernel cache"
timeout $(( $(left) - 60 )) python3 benchmarks/bench_warp.py --spec outputs/cellspec/default --device "$DEV" \
    --worlds "$W" --steps 10 --render-worlds "$RW" --cameras snapshot --image-size 32 \
    --policy baselines/act-camera-snapshot --policy-worlds "$PW" --policy-episodes "$PE" --json "$RESULTS/speed.json" \
    > "$RESULTS/log_speed.txt" 2>&1
el "bench_warp exit $?"
# the CPU path beside the batched cell: the state policy (no OpenGL needed) on the CPU cell in one process per core
timeout $(( $(left) / 3 )) python3 benchmarks/bench_warp.py --spec outputs/cellspec/default --device "$DEV" \
    --worlds 1 --steps 3 --render-worlds "" --policy baselines/act-state --policy-worlds "$PW" \
    --cpu-policy-episodes "${CPU_EPISODES:-64}" --json "$RESULTS/speed_state.json" > "$RESULTS/log_speed_state.txt" 2>&1
el "bench_warp (state, CPU path) exit $?"
for policy in act-camera-snapshot act-state; do
    timeout $(( $(left) / 2 )) python3 benchmarks/bench_warp_scores.py --policies "baselines/$policy" \
        --variants default,fast,jitter,lighting,distractors,seed --episodes "$EP" --device "$DEV" \
        --specs outputs/cellspec --json "$RESULTS/scores_$policy.json" > "$RESULTS/log_scores_$policy.txt" 2>&1
    el "bench_warp_scores $policy exit $?"
done
grep -h -v "^Module" "$RESULTS"/log_*.txt | grep "^|\|^policy\|^baselines\|worlds:" | tail -60
el done
