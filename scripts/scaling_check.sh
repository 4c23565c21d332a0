#!/usr/bin/env bash
# Many-core scaling of the CPU path (issue targets in docs/performance.md, "Many-core scaling"),
# for a machine with many cores (the accelerator machine has 16):
#   bash scripts/scaling_check.sh <bin dir> <log dir> [thread counts...]
# <bin dir> holds bench_step and bench_pressure (LD_LIBRARY_PATH finds their libraries). Runs the
# whole solid step (sand, jello; the fluid and coupled steps) and the MGPCG pressure solves at
# each thread count (default: 1 2 4 8 16, capped at the machine's cores); prints the tables, one
# log per run to <log dir>.
set -u
bin=$1
log=$2
shift 2
threads=("$@")
[ ${#threads[@]} -gt 0 ] || threads=(1 2 4 8 16)
cores=$(nproc)
usable=()
for t in "${threads[@]}"; do [ "$t" -le "$cores" ] && usable+=("$t"); done
mkdir -p "$log"
echo "scaling_check: $cores cores, threads ${usable[*]}"
source "$(dirname "$0")/run_logged.sh"
run() {  # run <name> <timeout s> <command...>: the run and the end of its table
  local name=$1
  run_logged "$log" "$@"
  grep -vE "^\s*$" "$log/$name.log" | tail -n 16
}
run step_solid 240 "$bin/bench_step" --case sand jello --cells 96 --steps 10 --repeat 3 --threads "${usable[@]}"
run step_fluid 150 "$bin/bench_step" --case fluid coupled --cells 64 --steps 10 --repeat 1 --threads "${usable[@]}"
for t in "${usable[@]}"; do
  run "pressure_$t" 60 "$bin/bench_pressure" --poisson-3d 128 --dam-break-3d 64 --poisson-2d 16 --dam-break-2d 16 \
    --solvers mgpcg --threads "$t"
done
