#!/usr/bin/env python3
"""The benchmark programs refuse bad options before they allocate or time anything.

Each case runs a benchmark with one bad option (a thread count outside [1, cores], a size
beyond the memory of the machine, an unknown solver, a tolerance out of range) and asserts
that it exits with an error status (not a signal: no abort, no std::bad_alloc) within a few
seconds, with a message on stderr naming the option, and prints no timing table.

  bench_errors.py --bench-dir DIR        (the folder of bench_step, bench_transfer, bench_pressure)
"""
import argparse
import os
import pathlib
import subprocess
import sys

parser = argparse.ArgumentParser()
parser.add_argument("--bench-dir", required=True, type=pathlib.Path)
args = parser.parse_args()
cores = os.cpu_count() or 1

# (program, arguments, text the message must hold)
CASES = [
    ("bench_step", ["--threads", "0"], "--threads"),
    ("bench_step", ["--threads", str(cores + 1)], "--threads"),
    ("bench_transfer", ["--threads", "0"], "--threads"),
    ("bench_transfer", ["--threads", str(cores + 1)], "--threads"),
    ("bench_transfer", ["--particles-spacing", "0.001", "--steps", "0"], "--particles-spacing 0.001"),
    ("bench_pressure", ["--threads", "0"], "--threads"),
    ("bench_pressure", ["--threads", str(cores + 1)], "--threads"),
    ("bench_pressure", ["--poisson-3d", "60000"], "--poisson-3d 60000"),
    ("bench_pressure", ["--dam-break-2d", "1"], "--dam-break-2d"),
    ("bench_pressure", ["--solvers", "multigridish"], "--solvers"),
    ("bench_pressure", ["--rtol", "0"], "--rtol"),
]

failures = 0
for program, options, expected in CASES:
    exe = args.bench_dir / program
    if not exe.exists():
        print(f"skip {program}: not built")
        continue
    try:
        run = subprocess.run([str(exe), *options], capture_output=True, text=True, timeout=30)
    except subprocess.TimeoutExpired:
        print(f"FAIL {program} {' '.join(options)}: still running after 30 s")
        failures += 1
        continue
    problems = []
    if run.returncode <= 0:
        problems.append(f"exit status {run.returncode} (expected an error status > 0)")
    if expected not in run.stderr:
        problems.append(f"stderr does not name '{expected}': {run.stderr.strip()[:300]!r}")
    if "ns/p-step" in run.stdout or "solve s" in run.stdout:
        problems.append("a timing table was printed")
    status = "FAIL" if problems else "ok"
    print(f"{status:4} {program} {' '.join(options)}: exit {run.returncode}, {run.stderr.strip().splitlines()[0] if run.stderr.strip() else ''}")
    for p in problems:
        print("     ", p)
    failures += bool(problems)
sys.exit(1 if failures else 0)
