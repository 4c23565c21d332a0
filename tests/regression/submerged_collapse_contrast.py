#!/usr/bin/env python3
"""Rondon, Pouliquen & Aussillous (2011) in the coupled solver (submerged_collapse.yaml,
data/reference/rondon2011.md), at dx = 1 cm for the first 1.5 s:

1. With dilatancy (the shipped scene) the loose column (phi = 0.55) runs out at least twice as
   far as the dense one (phi = 0.60, H0 = 4.2 cm), and the excess pore pressure under the
   column, averaged over the first second, is positive under the loose one and negative under
   the dense one (measured: runout 7.5 / 1.4 cm, pressure +72 / -59 Pa; the experiment at
   1.3 s: 13.7 / 2.4 cm, at 1.1 s +133 / -126 Pa). Made to fail with dilatancy K = 1 instead
   of 4.09 (the loose pressure -31 Pa).
2. The control without dilatancy (the two keys removed): some part of the contrast is gone
   (measured: runout 5.0 / 3.4 cm, both pressures negative, -56 / -42 Pa), so the
   assertions above test the mechanism, not the packing's weight alone.
3. The same contrast with the pore water as a weakly compressible liquid (fluid.solver:
   weakly_compressible, c = 10 m/s; its pressure from the storage equation,
   coupling/stages/pore_pressure.h) instead of the mixture projection (measured: runout
   6.3 / 0.56 cm, pressure +113 / -44 Pa).

    submerged_collapse_contrast.py --app BUILD/apps/submerged_collapse
        --scene data/scenes/submerged_collapse.yaml --work DIR
"""
import argparse
import pathlib
import re
import sys

from app_runs import run_app

ap = argparse.ArgumentParser()
ap.add_argument("--app", required=True)
ap.add_argument("--scene", required=True)
ap.add_argument("--work", required=True)
args = ap.parse_args()
work = pathlib.Path(args.work)
work.mkdir(parents=True, exist_ok=True)
failures = []

coarse = ["grid.dx=0.01", "walls.thickness=0.01", "time.end=1.5"]
dense = ["sediment.packing_fraction=0.60", "bodies.0.hi=[0.07,0.052]"]
# The control: the same scene without the dilatancy keys (and the rate block, whose suspension
# viscosity needs the critical packing).
text = pathlib.Path(args.scene).read_text()
plain = re.sub(r"\n\s*(dilatancy|critical_packing|rate):[^\n]*", "", text)
if plain.count("\n") != text.count("\n") - 3:
    sys.exit("the scene's dilatancy keys were not found")
plain_scene = work / "no_dilatancy.yaml"
plain_scene.write_text(plain)


def contrast(scene, tag, extra=()):
    loose = run_app(args.app, scene, work / f"{tag}_loose", coarse + list(extra))
    packed = run_app(args.app, scene, work / f"{tag}_dense", coarse + dense + list(extra))
    print(f"{tag}: runout loose {loose['runout']:.4f} m, dense {packed['runout']:.4f} m; "
          f"mean base pore pressure (first second) loose {loose['mean_base_pore_pressure_1s']:+.1f} Pa, "
          f"dense {packed['mean_base_pore_pressure_1s']:+.1f} Pa")
    return loose, packed


def unmet(loose, packed):
    """The parts of Rondon et al.'s contrast that a pair of runs does not show."""
    out = []
    if not loose["runout"] > 2.0 * packed["runout"] > 0.0:
        out.append(f"loose runout {loose['runout']:.4f} m is not twice the dense {packed['runout']:.4f} m")
    if not loose["mean_base_pore_pressure_1s"] > 0.0:
        out.append(f"loose pore pressure mean {loose['mean_base_pore_pressure_1s']:.1f} Pa is not positive")
    if not packed["mean_base_pore_pressure_1s"] < 0.0:
        out.append(f"dense pore pressure mean {packed['mean_base_pore_pressure_1s']:.1f} Pa is not negative")
    return out


failures += unmet(*contrast(args.scene, "dilatant"))
failures += ["weakly compressible pore water: " + f for f in unmet(*contrast(
    args.scene, "compressible", ["fluid.solver=weakly_compressible", "fluid.speed_of_sound=10"]))]
if not unmet(*contrast(plain_scene, "plain")):
    failures.append("without dilatancy the contrast is still there: the test does not test dilatancy")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
