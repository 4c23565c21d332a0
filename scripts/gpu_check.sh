#!/usr/bin/env bash
# The GPU checks and timings of the CUDA back-end (docs/gpu.md), for a machine with a GPU:
#   bash scripts/gpu_check.sh <bin dir> <log dir> <work dir>
# <bin dir> holds column_collapse, test_cuda_step and bench_cuda (and LD_LIBRARY_PATH finds
# their libraries). Prints the results; one log per check goes to <log dir>, the runs' outputs
# to <work dir>. GPU_CHECK_FULL=1 runs only the whole 10.6 M particle collapse (below);
# GPU_CHECK_CPU=1 adds the CPU's first steps of it.
set -u
bin=$1
log=$2
work=$3
mkdir -p "$log" "$work"
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader
nproc
source "$(dirname "$0")/run_logged.sh"
step() {  # step <name> <timeout s> <command...>: the run and its result lines
  local name=$1
  run_logged "$log" "$@"
  grep -E "device_step|device |variant|warp|first step|momentum|runout|transfers|sand step|bench_cuda|SKIPPED|ERROR|error|test cases|wall|steps" "$log/$name.log" | head -40
}
summary() {  # summary <run dir>: particles, steps, wall, runout and the last frame's device figures
  [ -f "$1/summary.json" ] || return 0
  python3 - "$1/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
i = s["info"]
print(sys.argv[1], "particles", i["particles"], "steps", i["steps"], "wall_seconds", i["wall_seconds"],
      "runout", s["results"]["runout"])
PY
  tail -n 1 "$1/diagnostics.csv" | tr ',' '\n' | paste -d= <(head -n 1 "$1/diagnostics.csv" | tr ',' '\n') - |
    grep -E "^device_|^steps" | tr '\n' ' '
  echo
}
big="--set column.cells_per_width=110 --set output.particles=false --set output.png=false --quiet"
# GPU_CHECK_FULL=1: only the 3D column collapse at 10.6 M particles to the scene's end (1 s,
# 85 900 steps, frames every 0.05 s: 504 s on an H200, docs/performance.md), a call of
# its own (the checks below take another 5 minutes).
if [ "${GPU_CHECK_FULL:-0}" = 1 ]; then
  step collapse_full 580 "$bin/column_collapse" data/scenes/column_collapse_3d.yaml $big --set time.frame_dt=0.05 \
    --set device=cuda --set device_precision=single --out "$work/big_full"
  summary "$work/big_full"
  exit 0
fi
step test_cuda_step 90 "$bin/test_cuda_step"
step column_runout 150 python3 tests/gpu/column_runout.py "$bin" data "$work/runout"
step bench_cuda 240 "$bin/bench_cuda" --steps 10
# The 3D column collapse at 10.6 M particles (column.cells_per_width=110), single precision on
# the GPU, and the first steps of the same scene on the CPU's cores for the per-step ratio.
step collapse_gpu 150 "$bin/column_collapse" data/scenes/column_collapse_3d.yaml $big --set time.end=0.02 \
  --set time.frame_dt=0.02 --set device=cuda --set device_precision=single --out "$work/big_gpu"
# The CPU run is long (0.98 s per step on 16 cores); run it with GPU_CHECK_CPU=1.
[ "${GPU_CHECK_CPU:-0}" = 1 ] && step collapse_cpu 100 "$bin/column_collapse" data/scenes/column_collapse_3d.yaml $big --set time.end=0.0004 \
  --set time.frame_dt=0.0004 --out "$work/big_cpu"
for d in big_gpu big_cpu; do summary "$work/$d"; done
