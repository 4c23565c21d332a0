#!/usr/bin/env bash
# Cost of the coupled step (issue 4, "Performance"; issue 5, "Lean scenes"); the results are in
# docs/performance.md, "Coupled step and lean scenes".
#
#   scripts/coupled_overhead.sh [build-dir] [repeats] [end-time]     (defaults: build 5 0.2)
#
# Runs without previews or particle files, interleaved `repeats` times so that load from other
# processes spreads over all runs:
#   dry           the dry column collapse by the solid app (solid_scene, dry_collapse.yaml) and
#                 by the coupled app without a fluid (submerged_collapse,
#                 dry_collapse_coupled.yaml): the same particles, steps and stages;
#   flagship      sediment_transport.yaml by sediment_transport (both phases, to end-time), and
#                 the same particles one phase at a time by coupled_scene:
#                 sediment_transport_sediment_only.yaml and sediment_transport_fluid_only.yaml,
#                 the fluid once at its own step ("fluid") and once capped at the coupled run's
#                 mean step ("fluid_small_dt"), which the sediment's elastic waves limit.
# Prints per stage the milliseconds per step (the seconds_* columns of diagnostics.csv over
# the steps taken; median and [min-max] over the repeats), the pressure iterations of the
# frames' last solves, and the ratios per repeat: coupled dry / solid, and
# coupled / (sediment + fluid) of the stage sum and of the wall time per step.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
repeats=${2:-5}
end=${3:-0.2}
work=$(mktemp -d "${TMPDIR:-/tmp}/coupled_overhead.XXXXXX")
trap 'rm -rf "$work"' EXIT
scenes=$root/data/scenes
for app in solid_scene submerged_collapse sediment_transport coupled_scene; do
  [[ -x $build/apps/$app ]] || { echo "coupled_overhead.sh: $build/apps/$app not built" >&2; exit 2; }
done

# run NAME APP SCENE [--set KEY=VALUE...]: one run into $work/NAME.
run() {
  local name=$1 app=$2 scene=$3
  shift 3
  "$build/apps/$app" "$scenes/$scene" --set output.png=false --set output.particles=false "$@" \
    --out "$work/$name" --quiet 2>/dev/null
}

for ((r = 1; r <= repeats; ++r)); do
  run "solid.$r" solid_scene dry_collapse.yaml
  run "coupled_dry.$r" submerged_collapse dry_collapse_coupled.yaml
  run "coupled.$r" sediment_transport sediment_transport.yaml --set time.end="$end"
  run "sediment.$r" coupled_scene sediment_transport_sediment_only.yaml --set time.end="$end"
  run "fluid.$r" coupled_scene sediment_transport_fluid_only.yaml --set time.end="$end"
  steps=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['info']['steps'])" "$work/coupled.$r/summary.json")
  run "fluid_small_dt.$r" coupled_scene sediment_transport_fluid_only.yaml --set time.end="$end" \
    --set time.max_dt="$(python3 -c "print($end / $steps)")"
done

python3 - "$work" "$repeats" <<'EOF'
import csv, json, pathlib, statistics, sys

work, repeats = pathlib.Path(sys.argv[1]), int(sys.argv[2])


def load(run, r, strip=""):
    """Seconds per step of each stage (a repeated name numbered), steps, wall time per step and
    the pressure iterations of the frames after the first."""
    with open(work / f"{run}.{r}" / "diagnostics.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], [[float(x) for x in row] for row in rows[1:]]
    steps = sum(row[header.index("steps")] for row in data)
    stages, seen = {}, {}
    for i, name in enumerate(header):
        if name.startswith("seconds_"):
            stage = name[len("seconds_"):].removeprefix(strip)
            seen[stage] = seen.get(stage, 0) + 1
            key = stage if seen[stage] == 1 else f"{stage} ({seen[stage]})"
            stages[key] = sum(row[i] for row in data) / steps
    its = [row[header.index("pressure_iterations")] for row in data[1:]] if "pressure_iterations" in header else []
    info = json.loads((work / f"{run}.{r}" / "summary.json").read_text())["info"]
    return {"stages": stages, "steps": steps, "wall": float(info["wall_seconds"]) / steps, "iterations": its}


def cell(values):
    if not values:
        return "-"
    return f"{1e3 * statistics.median(values):.3f} [{1e3 * min(values):.3f}-{1e3 * max(values):.3f}]"


def table(title, runs):
    print(f"\n{title}: ms per step, median [min-max] of {repeats} runs")
    names = []
    for results in runs.values():
        names += [n for n in results[0]["stages"] if n not in names]
    print(f"{'stage':24s}", *(f"{run:>24s}" for run in runs))
    for name in names:
        print(f"{name:24s}", *(f"{cell([x['stages'][name] for x in runs[run] if name in x['stages']]):>24s}"
                               for run in runs))
    print(f"{'stage sum':24s}", *(f"{cell([sum(x['stages'].values()) for x in runs[run]]):>24s}" for run in runs))
    print(f"{'wall time':24s}", *(f"{cell([x['wall'] for x in runs[run]]):>24s}" for run in runs))
    print(f"{'steps':24s}", *(f"{runs[run][0]['steps']:>24.0f}" for run in runs))
    for run in runs:
        if runs[run][0]["iterations"]:
            print(f"pressure iterations, {run}, last solve of frames 1..:", runs[run][0]["iterations"])


def ratios(what, values):
    print(f"{what}: median {statistics.median(values):.3f} (runs: {', '.join(f'{x:.3f}' for x in values)})")


def per_run(results, key):
    return [sum(x["stages"].values()) if key == "stage sum" else x["wall"] for x in results]


rng = range(1, repeats + 1)
dry = {"solid": [load("solid", r) for r in rng], "coupled_dry": [load("coupled_dry", r, "sediment.") for r in rng]}
table("Dry column collapse (stage names of the coupled run without 'sediment.')", dry)
for key in ("stage sum", "wall time"):
    ratios(f"coupled_dry / solid, {key}",
           [c / s for c, s in zip(per_run(dry["coupled_dry"], key), per_run(dry["solid"], key))])

flagship = {run: [load(run, r) for r in rng] for run in ("coupled", "sediment", "fluid", "fluid_small_dt")}
table("Flagship sediment_transport", flagship)
for fluid in ("fluid", "fluid_small_dt"):
    for key in ("stage sum", "wall time"):
        c, s, f = (per_run(flagship[run], key) for run in ("coupled", "sediment", fluid))
        ratios(f"coupled / (sediment + {fluid}), {key}", [a / (b + d) for a, b, d in zip(c, s, f)])
EOF
