#!/usr/bin/env python3
"""The dry column collapse on an adaptive grid with particle resampling (issue 13, paper
Figs. 1 and 13), against uniform grids at its finest and at its coarsest spacing:

  uniform fine    column_collapse.yaml at the adaptive scene's finest dx;
  uniform coarse  the same at its coarsest dx;
  adaptive        column_collapse_adaptive.yaml: fine particles and cells near the free surface,
                  coarse inside, resampled every step;
  by travel       the same, resampled once the particles may have moved half a finest cell
                  (adaptive.resample.max_travel);
  rough walls     the same, resampled every step, the smooth back wall no surface
                  (adaptive.surface_walls: rough; the sticky floor still is).

Asserted: particles split and merge and mass is conserved to round-off; the adaptive run holds
fewer particles than the uniform fine one; its deposit is closer to the uniform fine deposit
than the uniform coarse one is (the app's profile_error with reference_profile set to the fine
run's profile.csv), and its runout within 10 % of the fine runout. The run by travel resamples
on fewer than a fifth of the steps, and its deposit and runout hold to the same bounds; so do
the rough-walls run's, with fewer particles than the default's (every wall a surface).

  column_collapse_adaptive.py --app build/apps/column_collapse --scenes data/scenes --work /tmp/cc
      [--cells 20] [--levels 2] [--end 0.6]

Exit status: 0 all hold, 1 one fails (printed), 2 a run failed.
"""
import sys

from app_runs import parse_scene_app_args, report, run_with_diagnostics as run, scene_app_parser


def main():
    parser = scene_app_parser()
    parser.add_argument("--cells", type=int, default=20, help="finest cells per column width")
    parser.add_argument("--levels", type=int, default=2)
    parser.add_argument("--end", type=float, default=0.6, help="end time [s]")
    args = parse_scene_app_args(parser)
    coarse_cells = args.cells // 2 ** (args.levels - 1)
    end = [f"time.end={args.end}"]
    fine, _ = run(args.app, args.scenes / "column_collapse.yaml", args.work / "fine",
                  end + [f"column.cells_per_width={args.cells}"])
    # The others' deposits against the fine one: the app's profile_error (mean |h - h_fine| / H0).
    against_fine = end + [f"reference_profile={(args.work / 'fine' / 'profile.csv').resolve()}"]
    coarse, _ = run(args.app, args.scenes / "column_collapse.yaml", args.work / "coarse",
                    against_fine + [f"column.cells_per_width={coarse_cells}"])
    # The scene's bands in finest cells (2 and 3 cells, the seeded band 3 cells) at this dx.
    dx = 0.1 / args.cells
    adaptive_settings = against_fine + [f"column.cells_per_width={args.cells}", f"adaptive.levels={args.levels}",
                                        f"adaptive.surface_band={3 * dx}", f"adaptive.resample.d_medium={2 * dx}",
                                        f"adaptive.resample.d_large={3 * dx}"]
    adaptive, rows = run(args.app, args.scenes / "column_collapse_adaptive.yaml", args.work / "adaptive",
                         adaptive_settings)
    travel, travel_rows = run(args.app, args.scenes / "column_collapse_adaptive.yaml", args.work / "travel",
                              adaptive_settings + [f"adaptive.resample.max_travel={dx / 2}"])
    resamplings, steps = float(travel_rows[-1]["resamplings"]), sum(float(r["steps"]) for r in travel_rows)
    rough, _ = run(args.app, args.scenes / "column_collapse_adaptive.yaml", args.work / "rough",
                   adaptive_settings + ["adaptive.surface_walls=rough"])
    d_adaptive, d_coarse = adaptive["profile_error"], coarse["profile_error"]
    split, merged = float(rows[-1]["particles_split"]), float(rows[-1]["particles_merged"])
    mass0, mass1 = float(rows[0]["mass"]), float(rows[-1]["mass"])
    print(f"runout [m]: fine {fine['runout']:.4f}, adaptive {adaptive['runout']:.4f}, coarse {coarse['runout']:.4f}")
    print(f"final height [m]: fine {fine['final_height']:.4f}, adaptive {adaptive['final_height']:.4f}, "
          f"coarse {coarse['final_height']:.4f}")
    print(f"profile_error against the fine deposit (mean |h - h_fine| / H0): adaptive {d_adaptive:.4g}, "
          f"coarse {d_coarse:.4g}")
    print(f"by travel: resampled on {resamplings:.0f} of {steps:.0f} steps (every step: {float(rows[-1]['resamplings']):.0f}); "
          f"runout {travel['runout']:.4f} m, profile_error {travel['profile_error']:.4g}, "
          f"particles {travel['particles']:.0f}")
    print(f"rough walls: runout {rough['runout']:.4f} m, profile_error {rough['profile_error']:.4g}, "
          f"particles {rough['particles']:.0f}")
    print(f"particles split {split:.0f}, merged {merged:.0f}; mass {mass0!r} -> {mass1!r}; final particles: "
          f"fine {fine['particles']:.0f}, adaptive {adaptive['particles']:.0f}")
    return report([("particles split and merge", split > 0 and merged > 0),
                   ("mass is conserved to round-off", abs(mass1 - mass0) <= 1e-12 * mass0),
                   ("the adaptive run holds fewer particles", adaptive["particles"] < fine["particles"]),
                   ("the adaptive profile is closer to the fine one than the coarse profile is",
                    d_adaptive < d_coarse),
                   ("the adaptive runout is within 10 % of the fine runout",
                    abs(adaptive["runout"] - fine["runout"]) <= 0.1 * fine["runout"]),
                   ("by travel: resampled on fewer than a fifth of the steps", 0 < resamplings < steps / 5),
                   ("by travel: the profile is closer to the fine one than the coarse profile is",
                    travel["profile_error"] < d_coarse),
                   ("by travel: the runout is within 10 % of the fine runout",
                    abs(travel["runout"] - fine["runout"]) <= 0.1 * fine["runout"]),
                   ("rough walls: fewer particles than with every wall a surface",
                    rough["particles"] < adaptive["particles"]),
                   ("rough walls: the profile is closer to the fine one than the coarse profile is",
                    rough["profile_error"] < d_coarse),
                   ("rough walls: the runout is within 10 % of the fine runout",
                    abs(rough["runout"] - fine["runout"]) <= 0.1 * fine["runout"])])


if __name__ == "__main__":
    sys.exit(main())
