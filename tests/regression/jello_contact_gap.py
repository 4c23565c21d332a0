#!/usr/bin/env python3
"""Colliding jellos in 2D (issue 13, paper Fig. 4): the gap the grid leaves between the blocks at
contact, on a uniform coarse grid, a uniform fine grid and an adaptive grid fine along the
blocks' surfaces only:

  coarse    jello_collide.yaml at dx = 4 h (the adaptive grid's coarsest spacing);
  fine      jello_collide.yaml at dx = h;
  adaptive  jello_collide_adaptive.yaml: three levels, finest h, each block's finest particles
            within 4 h of its surface, coarse ones inside.

Asserted: every run rebounds and keeps its momentum to round-off; the adaptive gap at contact
(summary min_body_gap, the closest approach over every step, mpm/geometry/body_gap.h) is at
most 1.25 times the fine grid's and less than a third of the coarse grid's, with fewer than a
third of the fine grid's particles; its kinetic energy after the rebound within 0.1 of the fine
run's (KE(end) / KE(0)); the min_body_gap column at its cap (no contact) until t = 0.05 s and
below it from t = 0.08 s (the blocks meet at about 0.067 s).

  jello_contact_gap.py --app build/apps/jello_collide --scenes data/scenes --work /tmp/jg
      [--dx 0.0025] [--end 0.12]

Exit status: 0 all hold, 1 one fails (printed), 2 a run failed.
"""
import json
import sys

from app_runs import parse_scene_app_args, report, run_with_diagnostics, scene_app_parser


def main():
    parser = scene_app_parser()
    parser.add_argument("--dx", type=float, default=0.0025, help="the finest spacing h [m]")
    parser.add_argument("--end", type=float, default=0.12, help="end time [s] (after the rebound)")
    args = parse_scene_app_args(parser)
    end = [f"time.end={args.end}"]
    runs = {}
    for name, scene, sets in [("coarse", "jello_collide.yaml", [f"grid.dx={4 * args.dx}"]),
                              ("fine", "jello_collide.yaml", [f"grid.dx={args.dx}"]),
                              ("adaptive", "jello_collide_adaptive.yaml",
                               [f"grid.dx={args.dx}", "adaptive.levels=3", f"adaptive.surface_band={4 * args.dx}"])]:
        runs[name], rows = run_with_diagnostics(args.app, args.scenes / scene, args.work / name, end + sets)
        info = json.loads((args.work / name / "summary.json").read_text())["info"]
        runs[name]["particles"] = int(info["particles"])
        # The blocks start 0.2 m apart and close at 3 m/s: no contact reported before t = 0.05 s
        # (the column at its cap, at most 0.02 m), a gap below the cap from t = 0.08 s.
        cap = float(rows[0]["min_body_gap"])
        runs[name]["contact_when_they_meet"] = (
            all(float(r["min_body_gap"]) == cap for r in rows if float(r["time"]) <= 0.05) and
            all(float(r["min_body_gap"]) < cap for r in rows if float(r["time"]) >= 0.08))
        r = runs[name]
        print(f"{name:8s}: min_body_gap {r['min_body_gap']:.4g} m ({r['min_body_gap'] / args.dx:.3f} h), "
              f"particles {r['particles']:.0f}, KE(end)/KE(0) {r['kinetic_energy_ratio']:.4f}, "
              f"(KE + elastic)(end)/(0) {r['energy_ratio']:.4f}, "
              f"momentum_drift {r['momentum_drift']:.2g}, rebound {r['rebound']:.0f}")
    coarse, fine, adaptive = runs["coarse"], runs["fine"], runs["adaptive"]
    checks = [(f"{n}: rebounds, momentum to round-off, contact from when the blocks meet",
               r["rebound"] == 1 and r["momentum_drift"] < 1e-9 and r["contact_when_they_meet"])
              for n, r in runs.items()]
    checks += [("the adaptive gap is at most 1.25 times the fine grid's",
                adaptive["min_body_gap"] <= 1.25 * fine["min_body_gap"]),
               ("the adaptive gap is less than a third of the coarse grid's",
                adaptive["min_body_gap"] < coarse["min_body_gap"] / 3),
               ("the adaptive run holds fewer than a third of the fine run's particles",
                adaptive["particles"] < fine["particles"] / 3),
               ("the adaptive rebound keeps the fine run's kinetic energy to 0.1",
                abs(adaptive["kinetic_energy_ratio"] - fine["kinetic_energy_ratio"]) <= 0.1)]
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
