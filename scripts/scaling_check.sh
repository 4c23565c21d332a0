#!/usr/bin/env bash
# Many-core scaling of the CPU path (issue targets in docs/performance.md, "Many-core scaling"),
# for a machine with many cores (the accelerator machine has 16):
#   [PARTS="step pressure flagship table2"] bash scripts/scaling_check.sh <bin dir> <log dir> [thread counts...]
# <bin dir> holds bench_step and bench_pressure, and for the parts that run apps
# sediment_transport, column_collapse and jello_collide (LD_LIBRARY_PATH finds their libraries).
# Runs, at each thread count (default: 1 2 4 8 16, capped at the machine's cores), the parts
# named in PARTS (default "step pressure flagship"):
#   step      the whole solid step (sand, jello; the fluid and coupled steps), bench_step
#   pressure  the MGPCG pressure solves, bench_pressure
#   flagship  the 3D flagship to 0.3 s (sediment_transport --threads N): its stage table
#   table2    the adaptive grid against uniform at the paper's sizes (bench/adaptive_table2.py
#             --threads N), at the first and last thread count only (minutes each)
# prints the tables, one log per run to <log dir>. Run from the repository's root (scenes).
set -u
bin=$1
log=$2
shift 2
threads=("$@")
[ ${#threads[@]} -gt 0 ] || threads=(1 2 4 8 16)
parts=" ${PARTS:-step pressure flagship} "
cores=$(nproc)
usable=()
for t in "${threads[@]}"; do [ "$t" -le "$cores" ] && usable+=("$t"); done
mkdir -p "$log"
echo "scaling_check: $cores cores, threads ${usable[*]}, parts${parts% }"
source "$(dirname "$0")/run_logged.sh"
run() {  # run <name> <timeout s> <command...>: the run and the end of its table
  local name=$1
  run_logged "$log" "$@"
  grep -vE "^\s*$" "$log/$name.log" | tail -n 16
}
wanted() { [[ $parts == *" $1 "* ]]; }
if wanted step; then
  run step_solid 240 "$bin/bench_step" --case sand jello --cells 96 --steps 10 --repeat 3 --threads "${usable[@]}"
  run step_fluid 150 "$bin/bench_step" --case fluid coupled --cells 64 --steps 10 --repeat 1 --threads "${usable[@]}"
fi
if wanted pressure; then
  for t in "${usable[@]}"; do
    run "pressure_$t" 60 "$bin/bench_pressure" --poisson-3d 128 --dam-break-3d 64 --poisson-2d 16 --dam-break-2d 16 \
      --solvers mgpcg --threads "$t"
  done
fi
if wanted flagship; then
  for t in "${usable[@]}"; do
    run_logged "$log" "flagship_$t" 120 "$bin/sediment_transport" data/scenes/sediment_transport_3d.yaml \
      --set time.end=0.3 --set output.png=false --set output.particles=false --quiet --threads "$t" \
      --out "$log/flagship_$t"
    grep -E "^\s*(mixture_pressure|total) " "$log/flagship_$t.log"
  done
fi
if wanted table2; then
  for t in "${usable[0]}" "${usable[-1]}"; do
    for case in sand_paper jello_paper; do
      run "table2_${case}_$t" 400 python3 "$(dirname "$0")/../bench/adaptive_table2.py" --bin "$bin" --case "$case" \
        --threads "$t"
    done
  done
fi
