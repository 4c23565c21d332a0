#!/usr/bin/env python3
"""Lean scenes (issue 5): a scene that does not need a capability pays nothing for it. Runs short
scenes and asserts, from the stages and the memory per field that every run reports in
summary.json ("info": "stages", "memory_bytes.<field>"):

  dry     a dry-sand scene run by the coupled app (a coupled scene file without `fluid`) holds no
          fluid field and runs no fluid, pressure, exchange or volume-fraction stage; its stages,
          its memory per field and its motion are those of the same scene run by the solid app;
  fluid   a fluid-only scene (dam break) holds no particle.F / particle.plastic and runs no
          stress_forces, deformation or plasticity stage;
  elastic an elastic scene (jello_collide) runs no plasticity stage;
  openvdb none of these runs calls into OpenVDB, while a scene with a level-set collider
          (goo_slits) does.

How OpenVDB is observed: every level-set loader (libmpm/src/geometry/level_set_vdb.cpp) calls
openvdb::initialize() before anything else. libmpm_core reaches it through a lazily bound PLT
slot, and the dynamic linker reports a lazy binding when the slot is first used
(LD_DEBUG=bindings), so the binding appears exactly when a loader ran. The goo_slits run
proves that the probe sees a call; eager binding (LD_BIND_NOW, -z now) would report the
binding in every run and fail the test rather than hide a call. libopenvdb.so itself is mapped
into every process of a build with SEDIMENT_WITH_OPENVDB=ON (it is a link dependency of
libmpm_core); only a build with the option OFF leaves it out entirely.

  lean_scenes.py --solid-scene build/apps/solid_scene --coupled-app build/apps/submerged_collapse \\
      --dam-break build/apps/dam_break --jello-collide build/apps/jello_collide \\
      --goo-slits build/apps/goo_slits --scenes data/scenes --work /tmp/lean

Exit status: 0 all assertions hold, 1 one fails (each failure is printed), 2 a run failed.
"""
import argparse
import csv
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

QUICK = ["output.png=false", "output.particles=false"]
# The lazy binding of openvdb::initialize() (in its versioned namespace, e.g. openvdb::v10_0)
# for a caller outside OpenVDB: libmpm_core, or the app when it is linked statically.
# OpenVDB's own openvdb::points::internal::initialize is bound when the library loads.
OPENVDB_INITIALIZE = re.compile(
    r"binding file (?!\S*libopenvdb)\S+ \[\d+\] to \S*libopenvdb\S* \[\d+\]: "
    r"normal symbol `_ZN7openvdb\d+v\d+_\d+10initializeEv'")


def run(name, app, scene, overrides, work):
    """Runs `app` on `scene` under the binding probe; returns (summary, initialize bound)."""
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    probe = work / f"{name}.ld"
    for old in work.glob(f"{name}.ld.*"):
        old.unlink()
    command = [app, str(scene), "--out", str(out), "--quiet"]
    for assignment in QUICK + overrides:
        command += ["--set", assignment]
    env = dict(os.environ, LD_DEBUG="bindings", LD_DEBUG_OUTPUT=str(probe))
    env.pop("LD_BIND_NOW", None)
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    if result.returncode != 0:
        sys.stderr.write(result.stderr)
        print(f"lean_scenes.py: {' '.join(command)} exited with {result.returncode}", file=sys.stderr)
        sys.exit(2)
    bound = False
    for log in work.glob(f"{name}.ld.*"):
        with open(log, errors="replace") as f:
            bound = bound or any(OPENVDB_INITIALIZE.search(line) for line in f)
        log.unlink()
    return json.loads((out / "summary.json").read_text()), bound


def diagnostics(out):
    with open(out / "diagnostics.csv", newline="") as f:
        return list(csv.DictReader(f))


def stages(summary):
    text = summary["info"]["stages"]
    return text.split(",") if text else []


def memory(summary):
    prefix = "memory_bytes."
    return {k[len(prefix):]: int(v) for k, v in summary["info"].items() if k.startswith(prefix)}


class Checks:
    def __init__(self):
        self.failed = 0

    def expect(self, what, passed, detail=""):
        print(f"check {what}: {'ok' if passed else 'FAILED'}{' (' + detail + ')' if detail else ''}")
        self.failed += not passed


def strip_phase(names, phase):
    return [n[len(phase) + 1:] if n.startswith(phase + ".") else n for n in names]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    for app in ("solid-scene", "coupled-app", "dam-break", "jello-collide", "goo-slits"):
        parser.add_argument(f"--{app}", required=True, help=f"the {app.replace('-', '_')} executable")
    parser.add_argument("--scenes", required=True, type=pathlib.Path, help="data/scenes")
    parser.add_argument("--work", required=True, type=pathlib.Path, help="folder for the runs")
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    c = Checks()
    vdb_calls = {}

    # Dry sand: the coupled app without `fluid` against the solid app on the same column.
    coarse = ["grid.dx=0.005", "time.end=0.2"]
    solid, vdb_calls["solid_scene"] = run("dry_solid", args.solid_scene, args.scenes / "dry_collapse.yaml",
                                          coarse, args.work)
    dry, vdb_calls["coupled dry"] = run("dry_coupled", args.coupled_app, args.scenes / "dry_collapse_coupled.yaml",
                                        coarse, args.work)
    dry_stages, dry_memory = stages(dry), memory(dry)
    wet = [s for s in dry_stages if re.search(r"pressure|^fluid\.|exchange|volume_fraction", s)]
    c.expect("dry: no fluid, pressure, exchange or volume-fraction stage", not wet, ",".join(wet))
    fluid_fields = {k: v for k, v in dry_memory.items() if k.startswith("fluid.") and v > 0}
    c.expect("dry: no fluid field holds memory", not fluid_fields, str(fluid_fields))
    c.expect("dry: the sediment holds F (the memory report is there)", dry_memory.get("sediment.particle.F", 0) > 0)
    c.expect("dry: the stages of the solid app, in order", strip_phase(dry_stages, "sediment") == stages(solid),
             f"coupled {dry['info']['stages']} / solid {solid['info']['stages']}")
    # The same motion: sediment particles carry phi times the solid particles' mass and volume,
    # which leaves every acceleration unchanged (round-off apart).
    speeds = [(float(a["max_speed"]), float(b["max_speed"]))
              for a, b in zip(diagnostics(args.work / "dry_solid"), diagnostics(args.work / "dry_coupled"))]
    worst = max(abs(a - b) / max(a, 1e-300) for a, b in speeds)
    c.expect("dry: the largest particle speed of every frame agrees with the solid app to 1e-9",
             len(speeds) > 2 and worst < 1e-9, f"{len(speeds)} frames, worst relative difference {worst:.2e}")
    sediment_memory = {k[len("sediment."):]: v for k, v in dry_memory.items() if k.startswith("sediment.")}
    c.expect("dry: the memory per field of the solid app", sediment_memory == memory(solid),
             f"coupled {sediment_memory} / solid {memory(solid)}")

    # A fluid-only scene carries no solid stress fields and runs no solid stage.
    fluid, vdb_calls["dam_break"] = run("fluid_only", args.dam_break, args.scenes / "dam_break.yaml",
                                        ["time.end=0.05"], args.work)
    fluid_memory = memory(fluid)
    solid_fields = {k: v for k, v in fluid_memory.items()
                    if re.search(r"particle\.(F|plastic)$", k) and v > 0}
    c.expect("fluid: no particle.F / particle.plastic memory", not solid_fields, str(solid_fields))
    c.expect("fluid: the memory report is there", fluid_memory.get("particle.x", 0) > 0)
    solid_stages = [s for s in stages(fluid) if re.search(r"stress_forces|deformation|plasticity", s)]
    c.expect("fluid: no stress_forces, deformation or plasticity stage", not solid_stages, ",".join(solid_stages))
    c.expect("fluid: a pressure stage runs", "pressure" in stages(fluid), fluid["info"]["stages"])

    # An elastic scene runs no plasticity stage.
    elastic, vdb_calls["jello_collide"] = run("elastic", args.jello_collide, args.scenes / "jello_collide.yaml",
                                              ["time.end=0.02"], args.work)
    c.expect("elastic: no plasticity stage", "plasticity" not in stages(elastic), elastic["info"]["stages"])
    c.expect("elastic: stress_forces runs", "stress_forces" in stages(elastic), elastic["info"]["stages"])
    c.expect("dry: the plastic sand runs plasticity", "plasticity" in stages(solid), solid["info"]["stages"])

    # OpenVDB: called by the level-set collider of goo_slits only.
    _, level_set = run("level_set", args.goo_slits, args.scenes / "goo_slits.yaml",
                       ["grid.dx=0.02", "time.end=0.02"], args.work)
    c.expect("openvdb: the level-set scene calls openvdb::initialize (the probe sees calls)", level_set)
    for name, called in vdb_calls.items():
        c.expect(f"openvdb: {name} never calls into OpenVDB", not called)
    return 1 if c.failed else 0


if __name__ == "__main__":
    sys.exit(main())
