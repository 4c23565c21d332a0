#!/usr/bin/env python3
"""Bed-load flux of a sediment_transport run from its bed budget.

The sand eroded upstream of a section has passed it (Exner's equation integrated along the
flume): with the bed heights of bed_profile.csv (one row per column, x ascending, 2D),

    M(x) = - packing * rho_s * sum_{columns left of x} (h_final - h_initial) * width   [kg/m]

is the mass per metre of width that crossed the section at x during the run, and M / (rho_s t)
the mean volumetric grain flux [m^2/s] (grains that are still in suspension at the end count
as passed). Prints both for sections every --step metres and, with --reference (a flux in
m^2/s, e.g. the Meyer-Peter & Mueller value of data/reference/meyer_peter_mueller1948.md), the
ratio of each to it. The run's end time is the last row of diagnostics.csv.

    python3 scripts/bed_load_flux.py OUT [--packing 0.6] [--grain-density 2650] [--step 0.15]
                                         [--from 0.2] [--to 1.35] [--reference Q]
"""
import argparse
import csv
import pathlib
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=pathlib.Path, help="the run's output folder")
    ap.add_argument("--packing", type=float, default=0.6, help="the bed's packing fraction (scene: sediment.packing_fraction)")
    ap.add_argument("--grain-density", type=float, default=2650.0, help="rho_s [kg/m^3] (scene: sediment.density)")
    ap.add_argument("--step", type=float, default=0.15, help="spacing of the sections [m]")
    ap.add_argument("--from", dest="first", type=float, default=0.2, help="first section [m]")
    ap.add_argument("--to", dest="last", type=float, default=1.35, help="last section [m]")
    ap.add_argument("--reference", type=float, help="a flux [m^2/s] to compare with")
    a = ap.parse_args()
    checked = [("--packing", a.packing), ("--grain-density", a.grain_density), ("--step", a.step)]
    if a.reference is not None:
        checked.append(("--reference", a.reference))
    for name, value in checked:
        if not value > 0:
            sys.exit(f"bed_load_flux: {name} {value} must be > 0")
    try:
        with open(a.out / "bed_profile.csv") as f:
            rows = list(csv.DictReader(f))
        with open(a.out / "diagnostics.csv") as f:
            diagnostics = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"bed_load_flux: {e}")
    if len(rows) < 2 or "z" in rows[0] or not diagnostics:
        sys.exit(f"bed_load_flux: {a.out} holds no 2D bed profile and diagnostics (a 2D sediment_transport run)")
    t = float(diagnostics[-1]["time"])
    if not t > 0:
        sys.exit(f"bed_load_flux: the run in {a.out} ends at t = {t}")
    x = [float(r["x"]) for r in rows]
    width = x[1] - x[0]
    first_face, last_face = x[0] + 0.5 * width, x[-1] + 0.5 * width
    if a.first < first_face - width or a.last > last_face + width:
        sys.exit(f"bed_load_flux: sections {a.first}..{a.last} m reach outside the profile's {first_face:g}..{last_face:g} m")
    passed, total = [], 0.0  # mass that crossed the right face of each column [kg/m]
    for r in rows:
        total -= a.packing * a.grain_density * (float(r["final_height"]) - float(r["initial_height"])) * width
        passed.append(total)
    print(f"bed budget of {a.out} over t = {t:g} s (packing {a.packing}, rho_s {a.grain_density} kg/m^3)")
    print("| section x [m] | mass passed [kg/m] | mean grain flux [m^2/s] |" + (" / reference |" if a.reference is not None else ""))
    print("|---:|---:|---:|" + ("---:|" if a.reference is not None else ""))
    section = a.first
    while section <= a.last + 1e-9:
        c = min(range(len(x)), key=lambda i: abs(x[i] + 0.5 * width - section))  # the column whose right face is nearest
        q = passed[c] / (a.grain_density * t)
        line = f"| {x[c] + 0.5 * width:.3f} | {passed[c]:.3f} | {q:.3g} |"
        if a.reference is not None:
            line += f" {q / a.reference:.3g} |"
        print(line)
        section += a.step


if __name__ == "__main__":
    main()
