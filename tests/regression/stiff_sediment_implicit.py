#!/usr/bin/env python3
"""The implicit solid step as a coupled sediment (stiff_block_in_water.yaml, coupled_scene):

1. At the explicit step (time.max_dt = frame_dt / 171, what the explicit sediment of
   E = 1e6 Pa takes), the implicit sediment follows the explicit one through the fall and the
   impact on the water: kinetic energy and vertical momentum of every frame within 1 % of
   their peaks (measured 0.15 % and 0.4 %).
2. The shipped scene (E = 1e8 Pa) runs at the fluid's time step: at least 50 times fewer steps
   than the explicit sediment's limit 0.5 dx / c would take (measured about 200 times), with
   the sediment's mass conserved.

    stiff_sediment_implicit.py --app BUILD/apps/coupled_scene --scenes data/scenes --work DIR
"""
import argparse
import math
import pathlib
import sys

from app_runs import read_csv, run_app

ap = argparse.ArgumentParser()
ap.add_argument("--app", required=True)
ap.add_argument("--scenes", required=True)
ap.add_argument("--work", required=True)
args = ap.parse_args()
scene = pathlib.Path(args.scenes) / "stiff_block_in_water.yaml"
work = pathlib.Path(args.work)
failures = []

short = ["sediment.youngs_modulus=1e6", "time.end=0.2"]
run_app(args.app, scene, work / "implicit", short + [f"time.max_dt={0.02 / 171}"])
run_app(args.app, scene, work / "explicit", short + ["sediment.solver=explicit"])
implicit = read_csv(work / "implicit" / "diagnostics.csv")
explicit = read_csv(work / "explicit" / "diagnostics.csv")
for key in ("kinetic_energy", "momentum_y"):
    a = [float(r[key]) for r in implicit]
    b = [float(r[key]) for r in explicit]
    peak = max(abs(x) for x in b)
    worst = max(abs(x - y) for x, y in zip(a, b)) / peak
    print(f"{key}: largest difference {worst:.2e} of the peak {peak:.4g}")
    if len(a) != len(b) or worst > 0.01:
        failures.append(f"{key} differs by {worst:.3g} of its peak")

run_app(args.app, scene, work / "fluid_step")
rows = read_csv(work / "fluid_step" / "diagnostics.csv")
steps = sum(int(float(r["steps"])) for r in rows)
E, nu, rho, dx = 1e8, 0.25, 2650.0, 0.005
c = math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho)
explicit_steps = float(rows[-1]["time"]) / (0.5 * dx / c)
print(f"steps: {steps}, explicit limit {explicit_steps:.0f} ({explicit_steps / steps:.0f} times more)")
if steps * 50 > explicit_steps:
    failures.append(f"{steps} steps, not 50 times below the explicit {explicit_steps:.0f}")
mass = [float(r["mass_sediment"]) for r in rows]
if max(abs(m - mass[0]) for m in mass) > 1e-12 * mass[0]:
    failures.append(f"sediment mass changed: {mass[0]} -> {mass[-1]}")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
