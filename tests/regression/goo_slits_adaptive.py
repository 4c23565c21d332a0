#!/usr/bin/env python3
"""The goo of goo_slits through slits narrower than a coarse cell (issue 13, paper Fig. 2):

  uniform coarse  (dx = 0.05 m, the adaptive scene's coarsest cells): no goo passes the plate;
  uniform fine    (dx = 0.0125 m, its finest cells): some passes;
  adaptive        (goo_slits_adaptive.yaml: fine only within 0.03 m of the plate): passes, with
                  a mass fraction within 0.03 of the uniform fine grid's, and never deeper in
                  the plate than a fine cell.

  goo_slits_adaptive.py --app build/apps/goo_slits --scenes data/scenes --work /tmp/goo

Exit status: 0 all hold, 1 one fails (printed), 2 a run failed.
"""
import sys

from app_runs import parse_scene_app_args, report, run_app as run, scene_app_parser


def main():
    parser = scene_app_parser()
    args = parse_scene_app_args(parser)
    coarse = run(args.app, args.scenes / "goo_slits.yaml", args.work / "coarse", ["grid.dx=0.05"])
    fine = run(args.app, args.scenes / "goo_slits.yaml", args.work / "fine", ["grid.dx=0.0125"])
    adaptive = run(args.app, args.scenes / "goo_slits_adaptive.yaml", args.work / "adaptive", [])
    through = {name: r["mass_fraction_through"] for name, r in
               (("coarse", coarse), ("fine", fine), ("adaptive", adaptive))}
    print(f"mass fraction through the plate: {through}; adaptive max_penetration "
          f"{adaptive['max_penetration']:.4g} m")
    return report([("the uniform coarse grid holds all the goo", through["coarse"] == 0.0),
                   ("the uniform fine grid lets goo through", through["fine"] > 0.05),
                   ("the adaptive grid lets goo through like the fine grid (within 0.03)",
                    abs(through["adaptive"] - through["fine"]) < 0.03),
                   ("the adaptive goo stays within a fine cell of the plate surface",
                    adaptive["max_penetration"] < 0.0125)])


if __name__ == "__main__":
    sys.exit(main())
