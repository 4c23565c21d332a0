#!/usr/bin/env python3
"""Sand in a turning drum on an adaptive grid with particle resampling on and off, against the
uniform grid of its finest dx (issue 13, paper Fig. 11):

  uniform     data/scenes/rotating_drum.yaml without its adaptive block;
  resampling  the scene as it is: particles split near the free surface and merge inside;
  none        the scene without its adaptive.resample line: types fixed at seeding.

Asserted: with resampling the free-surface layer stays made of finest particles (mean
surface_fine_fraction over the second half >= 0.9), mass is conserved to round-off, the
particle count stays below that of the uniform run (it grew without bound under a merge guard
on counts alone), and the repose angle is within 5 degrees of the uniform run's (the drum's
traction acts on fine nodes: with the domain walls' layer reaching into the drum it fell to
half). The run without resampling is reported, not asserted on.

  rotating_drum_resampling.py --app build/apps/rotating_drum --scenes data/scenes --work /tmp/drum
      [--set key=value ...]

Exit status: 0 all hold, 1 one fails (printed), 2 a run failed.
"""
import sys

from app_runs import parse_scene_app_args, report, run_with_diagnostics as run, scene_app_parser


def main():
    parser = scene_app_parser()
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parse_scene_app_args(parser)
    scene = args.scenes / "rotating_drum.yaml"
    lines = scene.read_text().splitlines(keepends=True)
    def without(prefixes):
        return "".join(line for line in lines if not line.lstrip().startswith(prefixes))

    off_scene = args.work / "rotating_drum_no_resampling.yaml"
    off_scene.write_text(without(("resample:",)))
    uniform_scene = args.work / "rotating_drum_uniform.yaml"
    uniform_scene.write_text(without(("adaptive:", "levels:", "surface_band:", "resample:", "refine:",
                                      "color_by:")))
    on, on_rows = run(args.app, scene, args.work / "on", args.overrides)
    off, _ = run(args.app, off_scene, args.work / "off", args.overrides)
    uniform, _ = run(args.app, uniform_scene, args.work / "uniform",
                     [o for o in args.overrides if not o.startswith("adaptive.")])
    mass0, mass1 = float(on_rows[0]["mass"]), float(on_rows[-1]["mass"])
    print(f"surface_fine_fraction: resampling {on['surface_fine_fraction']:.3f}, "
          f"none {off['surface_fine_fraction']:.3f}")
    print(f"repose_angle [deg]: uniform {uniform['repose_angle']:.1f}, resampling {on['repose_angle']:.1f}, "
          f"none {off['repose_angle']:.1f}")
    print(f"particles: uniform {uniform['particles']:.0f}, resampling {on['particles']:.0f}, "
          f"none {off['particles']:.0f}; split {on_rows[-1]['particles_split']}, "
          f"merged {on_rows[-1]['particles_merged']}")
    return report([("the resampled surface stays fine", on["surface_fine_fraction"] >= 0.9),
                   ("mass is conserved to round-off", abs(mass1 - mass0) <= 1e-12 * mass0),
                   ("resampling holds fewer particles than the uniform grid", on["particles"] < uniform["particles"]),
                   ("the repose angle is within 5 degrees of the uniform grid's",
                    abs(on["repose_angle"] - uniform["repose_angle"]) <= 5.0)])


if __name__ == "__main__":
    sys.exit(main())
