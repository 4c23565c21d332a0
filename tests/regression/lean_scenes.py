#!/usr/bin/env python3
"""Lean scenes (issue 5): a scene that does not need a capability pays nothing for it. Runs short
scenes and asserts, from the stages and the memory per field that every run reports in
summary.json ("info": "stages", "memory_bytes.<field>"):

  dry     a dry-sand scene run by the coupled app (a coupled scene file without `fluid`) holds no
          fluid field and runs no fluid, pressure, exchange or volume-fraction stage; its stages,
          its memory per field and its motion are those of the same scene run by the solid app;
  fluid   a fluid-only scene (dam break) holds no particle.F / particle.plastic and runs no
          stress or plasticity stage;
  elastic an elastic scene (jello_collide) runs no plasticity stage;
  uniform a scene without the key `adaptive` builds nothing of the adaptive grid: no refine or
          ghost_velocities stage, no particle.level, one grid; the adaptive jello has all three;
  openvdb none of these processes loads libopenvdb, while a scene with a level-set collider
          (goo_slits) does, through the plugin libmpm_openvdb.

How OpenVDB is observed: a shared libmpm_core does not link OpenVDB; its first level set
dlopen()s the plugin libmpm_openvdb.so beside it, which needs libopenvdb (see
libmpm/src/geometry/level_set_loader.cpp). Under LD_DEBUG=files the dynamic linker reports every
object it loads and the object that needed it (`file=libopenvdb.so.10.0 [0];  needed by
.../libmpm_openvdb.so [0]`), so a process that never loads libopenvdb has no such line. The
goo_slits run proves that the probe sees a load; OpenVDB linked into libmpm_core or an app again
would show the line in every run and fail the test. A goo_slits run with libmpm_core copied to a
folder without the plugin must stop with an input error that names the plugin path. A static
build (--openvdb linked) links OpenVDB into every app, so there the OpenVDB checks are skipped; a
build with SEDIMENT_WITH_OPENVDB=OFF has no OpenVDB at all.

  lean_scenes.py --solid-scene build/apps/solid_scene --coupled-app build/apps/submerged_collapse \\
      --dam-break build/apps/dam_break --jello-collide build/apps/jello_collide \\
      --goo-slits build/apps/goo_slits --openvdb plugin --core build/libmpm/libmpm_core.so \\
      --scenes data/scenes --work /tmp/lean

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
# A load of libopenvdb (file=libopenvdb.so.10.0 or a full path) and the object that needed or
# dlopen()ed it; not the "(relocation dependency)" lines that follow a load.
OPENVDB_LOADED = re.compile(
    r"\bfile=(?:\S*/)?libopenvdb\.so\S* \[\d+\];\s+(?:needed|dynamically loaded) by (\S+) \[\d+\]$")


def run(name, app, scene, overrides, work):
    """Runs `app` on `scene` under the load probe; returns (summary, the objects that made the
    dynamic linker load libopenvdb: empty when it never did)."""
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    probe = work / f"{name}.ld"
    for old in work.glob(f"{name}.ld.*"):
        old.unlink()
    command = [app, str(scene), "--out", str(out), "--quiet"]
    for assignment in QUICK + overrides:
        command += ["--set", assignment]
    env = dict(os.environ, LD_DEBUG="files", LD_DEBUG_OUTPUT=str(probe))
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    if result.returncode != 0:
        sys.stderr.write(result.stderr)
        print(f"lean_scenes.py: {' '.join(command)} exited with {result.returncode}", file=sys.stderr)
        sys.exit(2)
    loaded_by = set()
    for log in work.glob(f"{name}.ld.*"):
        with open(log, errors="replace") as f:
            loaded_by.update(m.group(1) for m in map(OPENVDB_LOADED.search, f) if m)
        log.unlink()
    return json.loads((out / "summary.json").read_text()), loaded_by


def run_without_plugin(app, scene, core, work):
    """Runs `app` on `scene` with a copy of libmpm_core (LD_LIBRARY_PATH) in a folder that holds no
    plugin; returns (exit status, stderr, the plugin path that libmpm_core should name)."""
    lonely = work / "core_without_plugin"
    shutil.rmtree(lonely, ignore_errors=True)
    lonely.mkdir()
    shutil.copy2(core, lonely)
    command = [app, str(scene), "--out", str(work / "no_plugin"), "--quiet"]
    env = dict(os.environ, LD_LIBRARY_PATH=str(lonely))
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    return result.returncode, result.stderr, str(lonely / "libmpm_openvdb.so")


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
    parser.add_argument("--openvdb", required=True, choices=("plugin", "linked"),
                        help="how this build reaches OpenVDB: the plugin of a shared build, or linked in")
    parser.add_argument("--core", required=True, type=pathlib.Path, help="the libmpm_core library")
    parser.add_argument("--scenes", required=True, type=pathlib.Path, help="data/scenes")
    parser.add_argument("--work", required=True, type=pathlib.Path, help="folder for the runs")
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    c = Checks()
    vdb_loads = {}

    # Dry sand: the coupled app without `fluid` against the solid app on the same column.
    coarse = ["grid.dx=0.005", "time.end=0.2"]
    solid, vdb_loads["solid_scene"] = run("dry_solid", args.solid_scene, args.scenes / "dry_collapse.yaml",
                                          coarse, args.work)
    dry, vdb_loads["coupled dry"] = run("dry_coupled", args.coupled_app, args.scenes / "dry_collapse_coupled.yaml",
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
    fluid, vdb_loads["dam_break"] = run("fluid_only", args.dam_break, args.scenes / "dam_break.yaml",
                                        ["time.end=0.05"], args.work)
    fluid_memory = memory(fluid)
    solid_fields = {k: v for k, v in fluid_memory.items()
                    if re.search(r"particle\.(F|plastic)$", k) and v > 0}
    c.expect("fluid: no particle.F / particle.plastic memory", not solid_fields, str(solid_fields))
    c.expect("fluid: the memory report is there", fluid_memory.get("particle.x", 0) > 0)
    solid_stages = [s for s in stages(fluid) if re.search(r"stress|plasticity", s)]
    c.expect("fluid: no stress or plasticity stage", not solid_stages, ",".join(solid_stages))
    c.expect("fluid: a pressure stage runs", "pressure" in stages(fluid), fluid["info"]["stages"])

    # An elastic scene runs no plasticity stage.
    elastic, vdb_loads["jello_collide"] = run("elastic", args.jello_collide, args.scenes / "jello_collide.yaml",
                                              ["time.end=0.02"], args.work)
    c.expect("elastic: no plasticity stage", not any("plasticity" in s for s in stages(elastic)),
             elastic["info"]["stages"])
    c.expect("elastic: p2g with the stress forces runs", "p2g_stress" in stages(elastic), elastic["info"]["stages"])
    c.expect("dry: the plastic sand runs plasticity in its g2p pass", "g2p_plasticity" in stages(solid),
             solid["info"]["stages"])

    # Adaptive grids only where the scene asks for one.
    def adaptive_parts(summary):
        fields = [k for k in summary["info"] if k.startswith("memory_bytes.")]
        return {"refine" in stages(summary), "ghost_velocities" in stages(summary),
                "memory_bytes.particle.level" in fields, any(".level1." in k or k.startswith("memory_bytes.level")
                                                               for k in fields)}
    c.expect("uniform: the elastic scene builds nothing of the adaptive grid", adaptive_parts(elastic) == {False},
             elastic["info"]["stages"])
    adaptive, _ = run("adaptive", args.jello_collide, args.scenes / "jello_collide_adaptive.yaml", ["time.end=0.005"],
                      args.work)
    c.expect("adaptive: the adaptive jello refines, pulls ghosts, types its particles and holds level grids",
             adaptive_parts(adaptive) == {True}, adaptive["info"]["stages"])

    # OpenVDB: loaded for the level-set collider of goo_slits only.
    _, level_set = run("level_set", args.goo_slits, args.scenes / "goo_slits.yaml",
                       ["grid.dx=0.02", "time.end=0.02"], args.work)
    if args.openvdb == "linked":
        print("check openvdb: skipped (a static build links OpenVDB into every app)")
        return 1 if c.failed else 0
    c.expect("openvdb: the level-set scene loads libopenvdb through the plugin (the probe sees loads)",
             bool(level_set) and all("libmpm_openvdb" in by for by in level_set), f"needed by {sorted(level_set)}")
    for name, loaded_by in vdb_loads.items():
        c.expect(f"openvdb: {name} never loads libopenvdb", not loaded_by, f"needed by {sorted(loaded_by)}")
    # The plugin is looked for beside libmpm_core only, and its absence is an input error that names it.
    status, error, plugin = run_without_plugin(args.goo_slits, args.scenes / "goo_slits.yaml", args.core, args.work)
    names_both = plugin in error and "-DSEDIMENT_WITH_OPENVDB=ON" in error
    c.expect("openvdb: without the plugin beside libmpm_core, the level-set scene stops with an input error "
             "naming the plugin and the option", status == 2 and names_both, f"exit {status}: {error.strip()}")
    return 1 if c.failed else 0


if __name__ == "__main__":
    sys.exit(main())
