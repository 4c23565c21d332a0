#!/usr/bin/env python3
"""Adaptive against uniform grid on the 3D scenes of the adaptive GIMP paper's Table 2.

For the 3D jello collision and the 3D dry sand column, runs the app once on the uniform grid of
the finest dx and once on the adaptive grid with that finest dx (same particles per cell of
each level), alternating, and prints a markdown table: particles at the end, steps, seconds of
the stages per step (the apps' own stage timers), the memory the run's fields hold at the end
(the apps' "memory held per field" table) and the peak resident set size of the process, with
the uniform/adaptive ratios; the stage seconds leave out the apps' measurements (the jellos'
body_gap). Memory held is what the particle and grid fields and the grids' index tables
(particle buckets; an adaptive grid's tree, ghost tables and transfer lists) hold, as the apps'
summary.json reports it (memory_bytes.*: capacities, not sizes). docs/performance.md has the
figures and the command.

    python3 bench/adaptive_table2.py --bin build/apps [--case jello|sand|jello_paper|jello_paper_band2|jello_paper_band1|sand_paper|sand_paper_every_step|all]
        [--repeat N]
        [--set KEY=VALUE] [--threads N]
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

# The apps' measuring stages (not part of the step the paper times): left out of the stage seconds.
MEASUREMENT_STAGES = ("body_gap",)
QUIET = ["--set", "output.png=false", "--set", "output.particles=false", "--quiet"]

# Per case: the app, its scene, the uniform settings, and what the adaptive run adds.
CASES = {
    "jello": {
        "app": "jello_collide",
        "scene": "data/scenes/jello_collide_3d.yaml",
        "uniform": ["grid.dx=0.00625", "time.end=0.01"],
        # Three levels (coarsest dx 0.025 m); each cube keeps its finest particles within 4
        # finest cells of its surface, coarse ones inside.
        "adaptive": ["adaptive.levels=3", "adaptive.surface_band=0.025"],
    },
    "sand": {
        "app": "column_collapse",
        "scene": "data/scenes/column_collapse_3d.yaml",
        "uniform": ["column.cells_per_width=40", "time.end=0.01"],
        # The 2D adaptive column's keys (data/scenes/column_collapse_adaptive.yaml): three levels,
        # fine particles within 3 finest cells of the surface, split within 2, merged beyond 3;
        # resampled once the particles may have moved half a finest cell.
        # The free surface as the paper's criterion: the smooth walls are none (the rough floor is).
        "adaptive": ["adaptive.levels=3", "adaptive.surface_band=0.0075", "adaptive.resample.d_small=0",
                     "adaptive.resample.d_medium=0.005", "adaptive.resample.d_large=0.0075",
                     "adaptive.resample.max_travel=0.00125", "adaptive.surface_walls=rough"],
    },
}
# The same scenes at the paper's size (Table 2: 1.74 M and 1.68 M particles on the uniform grid):
# each jello 48 finest cells wide (1.77 M), the column 60 (1.73 M); the refinement's distances
# kept in finest cells.
CASES["jello_paper"] = dict(CASES["jello"], uniform=["grid.dx=0.004166666666666667", "time.end=0.01"],
                            adaptive=["adaptive.levels=3", "adaptive.surface_band=0.016666666666666666"])
# Bands of 2 and 1 finest cells: the 3D contact gap at the paper's size came out within 8 % of
# the band of 4 cells' (docs/accuracy.md, colliding jellos) with 58 % and 35 % of its particles.
CASES["jello_paper_band2"] = dict(CASES["jello_paper"],
                                  adaptive=["adaptive.levels=3", "adaptive.surface_band=0.008333333333333333"])
CASES["jello_paper_band1"] = dict(CASES["jello_paper"],
                                  adaptive=["adaptive.levels=3", "adaptive.surface_band=0.004166666666666667"])
SAND_PAPER_BANDS = ["adaptive.levels=3", "adaptive.surface_band=0.005", "adaptive.resample.d_small=0",
                    "adaptive.resample.d_medium=0.0033333333333333335", "adaptive.resample.d_large=0.005",
                    "adaptive.surface_walls=rough"]
CASES["sand_paper"] = dict(CASES["sand"], uniform=["column.cells_per_width=60", "time.end=0.003"],
                           adaptive=SAND_PAPER_BANDS + ["adaptive.resample.max_travel=0.0008333333333333334"])
# As the paper's dynamic adaptation: resampled every step.
CASES["sand_paper_every_step"] = dict(CASES["sand_paper"], adaptive=SAND_PAPER_BANDS)


def run(binary, scene, sets, out, extra=()):
    """Runs one app (`extra`: more of its options); returns (stage seconds, steps, particles, memory
    held [B], peak RSS [B], wall [s])."""
    cmd = [binary, scene, "--out", out] + QUIET + list(extra)
    for s in sets:
        cmd += ["--set", s]
    start = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - start
    if proc.returncode != 0:
        sys.exit(f"adaptive_table2: {' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
    # The largest of this process's children so far: measure() gives each run its own process.
    rss_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    stages, measurements = None, 0.0
    for line in (proc.stdout + proc.stderr).splitlines():
        fields = line.split()
        if len(fields) >= 2 and fields[0] == "total":
            stages = float(fields[1])
        if len(fields) >= 2 and fields[0] in MEASUREMENT_STAGES:
            measurements += float(fields[1])
    if stages is not None:
        stages -= measurements
    with open(os.path.join(out, "summary.json")) as f:
        info = json.load(f)["info"]
    steps, particles = int(info["steps"]), int(info["particles"])
    memory = sum(int(v) for k, v in info.items() if k.startswith("memory_bytes."))
    if stages is None or steps == 0:
        sys.exit(f"adaptive_table2: no stage table or no step in the run of {' '.join(cmd)}")
    return stages, steps, particles, memory, rss_kb * 1024, wall


def measure(binary, scene, sets, extra):
    """One run in a fresh interpreter, so that ru_maxrss is this run's alone."""
    with tempfile.TemporaryDirectory() as out:
        code = ("import sys; sys.path.insert(0, %r); import adaptive_table2 as t; "
                "print(*t.run(%r, %r, %r, %r, %r))" % (os.path.dirname(os.path.abspath(__file__)), binary, scene,
                                                         sets, out, extra))
        proc = subprocess.run([sys.executable, "-B", "-c", code], capture_output=True, text=True)
        if proc.returncode != 0:
            sys.exit(proc.stdout + proc.stderr)
        s, n, p, m, r, w = proc.stdout.split()
        return float(s), int(n), int(p), int(m), int(r), float(w)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", required=True, help="folder of the app binaries (build/apps)")
    parser.add_argument("--case", choices=list(CASES) + ["all"], default="all",
                        help="one case, or all: jello and sand (the paper-size cases take minutes each)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a scene override added to both runs, after the case's own (repeatable)")
    parser.add_argument("--repeat", type=int, default=1, help="alternating runs of each grid; the best is kept")
    parser.add_argument("--threads", type=int, help="the apps' --threads, which check its range (default: every core this process may use)")
    args = parser.parse_args()
    if args.repeat < 1:
        sys.exit(f"adaptive_table2: --repeat {args.repeat}: accepted range is >= 1")
    extra = ["--threads", str(args.threads)] if args.threads is not None else []
    names = ["jello", "sand"] if args.case == "all" else [args.case]
    print("| case | grid | particles (end) | steps | stages [s/step] | memory held [MB] | peak RSS [MB] | wall [s] |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for name in names:
        case = CASES[name]
        binary = os.path.join(args.bin, case["app"])
        if not os.access(binary, os.X_OK):
            sys.exit(f"adaptive_table2: --bin {args.bin}: no executable {case['app']} there")
        best = {}
        for _ in range(args.repeat):
            for grid, sets in (("uniform", case["uniform"] + args.set),
                               ("adaptive", case["uniform"] + case["adaptive"] + args.set)):
                r = measure(binary, case["scene"], sets, extra)
                if grid not in best or r[0] / r[1] < best[grid][0] / best[grid][1]:
                    best[grid] = r
        for grid in ("uniform", "adaptive"):
            s, n, p, m, rss, w = best[grid]
            print(f"| {name} | {grid} | {p} | {n} | {s / n:.4f} | {m / 1e6:.1f} | {rss / 1e6:.0f} | {w:.1f} |")
        u, a = best["uniform"], best["adaptive"]
        print(f"| {name} | uniform / adaptive | {u[2] / a[2]:.2f} | | {(u[0] / u[1]) / (a[0] / a[1]):.2f} | "
              f"{u[3] / a[3]:.2f} | {u[4] / a[4]:.2f} | {u[5] / a[5]:.2f} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
