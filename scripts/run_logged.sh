# Sourced by the check scripts (gpu_check.sh, scaling_check.sh):
#   run_logged <log dir> <name> <timeout s> <command...>
# runs the command under a time limit with its output in <log dir>/<name>.log and prints
# "== <name>: exit <status> in <seconds> s".
run_logged() {
  local log=$1 name=$2 limit=$3
  shift 3
  local start=$SECONDS
  timeout "$limit" "$@" >"$log/$name.log" 2>&1
  echo "== $name: exit $? in $((SECONDS - start)) s"
}
