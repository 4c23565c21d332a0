#!/usr/bin/env python3
"""The error exits of the apps, run end to end.

Bad input: every case writes a small scene, runs an app on it and asserts exit status 2, a
stderr that is exactly one line "<app>: input error: <file>:<line>:<col>: key '<path>' =
<value>: <accepted range>" (the substrings of each case are checked), nothing on stdout and
no --out folder (an app validates the whole scene before it writes anything).
Threads: --threads outside [1, the cores this process may use] exits 2 naming the option, the
value and the range, before anything is written; --threads 1 runs, and the summary records it.
Numerical stop: a valid scene whose gravity overflows the grid velocity to infinity in the
first step must exit 3 with one message naming the stage, the grid node and the quantity.

  app_errors.py --column-collapse EXE --jello-collide EXE --goo-slits EXE --vibrating-bar EXE
                --work DIR
"""
import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys

# Small scenes; {placeholders} are filled per case, and each case changes one key.
JELLO = """\
dim: 2
domain: {{lo: [0, 0], hi: [1, 0.6]}}
grid: {{dx: 0.05}}
materials:
  - name: jello
    density: {density}
    youngs_modulus: {youngs_modulus}
    poisson_ratio: {poisson_ratio}
    elasticity: fixed_corotated
bodies:
  - {{shape: box, lo: [0.2, 0.2], hi: [0.4, 0.4], material: jello, velocity: [1, 0]}}
  - {{shape: box, lo: {lo}, hi: {hi}, material: jello, velocity: [-1, 0]}}
walls: {{contact: separate}}
time: {{end: 0.05, frame_dt: 0.01}}
{gravity_key}: [0, 0]
{adaptive}
"""
JELLO_DEFAULTS = dict(density=1000, youngs_modulus="1.0e5", poisson_ratio=0.3, lo="[0.6, 0.24]",
                      hi="[0.8, 0.44]", gravity_key="gravity", adaptive="")

COLUMN = """\
dim: 2
column:
  width: 0.1
  aspect_ratio: 1.0
  {cells_key}: 10
material:
  name: sand
  density: 2650
  youngs_modulus: 3.0e6
  poisson_ratio: 0.3
  elasticity: hencky_stvk
  plasticity:
    model: drucker_prager
    friction_angle: {friction_angle}
walls: {{contact: separate, y_min: sticky, y_max: open}}
time: {{end: 0.1}}
gravity: [0, -9.81]
{reference}
"""
COLUMN_DEFAULTS = dict(cells_key="cells_per_width", friction_angle=32, reference="")

GOO = """\
dim: 2
domain: {{lo: [0, 0], hi: [1, 1]}}
grid: {{dx: 0.05}}
materials:
  - {{name: goo, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk, plasticity: {{model: von_mises, yield_stress: 600}}}}
bodies:
  - {{shape: sphere, center: [0.5, 0.7], radius: 0.1, material: goo}}
colliders:
  - {{type: level_set, file: {mesh}, voxel_size: 0.01, slice_z: 0.3, contact: separate}}
time: {{end: 0.1}}
"""

BAR = """\
dim: 2
bar: {{length: 1.0, amplitude: 0.01, cells: {cells}}}
material: {{density: 1.0, youngs_modulus: 100.0, poisson_ratio: 0.0}}
walls: {{contact: slip, x_min: sticky, x_max: open}}
time: {{end: 0.1}}
gravity: [0, 0]
"""

# A valid scene that overflows: an almost massless stiffness (the elastic time-step limit is
# far above the frame) lets dt = frame_dt = 100 s, and dt * 1e308 m/s^2 is infinite.
OVERFLOW = """\
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.1}
materials:
  - {name: fluffy, density: 1000, youngs_modulus: 1.0e-300, poisson_ratio: 0.3}
bodies:
  - {shape: box, lo: [0.4, 0.4], hi: [0.6, 0.6], material: fluffy}
walls: {contact: separate}
time: {end: 100, frame_dt: 100}
gravity: [0, -1.0e308]
output: {png: false, particles: false}
"""


def case(name, app, template, defaults, changes, line_of, expected, files=None, args=()):
    """`line_of`: text on the line the message must point at (None: no file position)."""
    return dict(name=name, app=app, text=template.format(**{**defaults, **changes}), line_of=line_of,
                expected=expected, files=files or {}, args=list(args))


CASES = [
    case("unknown_key", "jello_collide", JELLO, JELLO_DEFAULTS, {"gravity_key": "gravty"}, "gravty:",
         ["unknown key 'gravty'", "(did you mean 'gravity'?)"]),
    case("unknown_key_app", "column_collapse", COLUMN, COLUMN_DEFAULTS, {"cells_key": "cells_per_widht"},
         "cells_per_widht:", ["unknown key 'column.cells_per_widht'", "(did you mean 'cells_per_width'?)"]),
    case("wrong_type_number", "jello_collide", JELLO, JELLO_DEFAULTS, {"youngs_modulus": "soft"},
         "youngs_modulus: soft", ["key 'materials[0].youngs_modulus' = soft", "expected a number > 0"]),
    case("wrong_type_list", "jello_collide", JELLO, JELLO_DEFAULTS, {"poisson_ratio": "[0.3]"},
         "poisson_ratio: [0.3]",
         ["key 'materials[0].poisson_ratio' = [0.3]", "expected a number in (-1, 0.5), got a list"]),
    case("wrong_type_integer", "vibrating_bar", BAR, {}, {"cells": "many"}, "cells: many",
         ["key 'bar.cells' = many", "expected an integer in [2, 65536]"]),
    case("youngs_modulus_negative", "jello_collide", JELLO, JELLO_DEFAULTS, {"youngs_modulus": -5},
         "youngs_modulus: -5", ["key 'materials[0].youngs_modulus' = -5", "expected a number > 0"]),
    case("youngs_modulus_zero", "jello_collide", JELLO, JELLO_DEFAULTS, {"youngs_modulus": 0},
         "youngs_modulus: 0", ["key 'materials[0].youngs_modulus' = 0", "expected a number > 0"]),
    case("youngs_modulus_command_line", "jello_collide", JELLO, JELLO_DEFAULTS, {}, None,
         ["command line --set materials.0.youngs_modulus=-1", "key 'materials[0].youngs_modulus' = -1",
          "expected a number > 0"], args=["--set", "materials.0.youngs_modulus=-1"]),
    case("poisson_ratio_half", "jello_collide", JELLO, JELLO_DEFAULTS, {"poisson_ratio": 0.5},
         "poisson_ratio: 0.5", ["key 'materials[0].poisson_ratio' = 0.5", "expected a number in (-1, 0.5)"]),
    case("poisson_ratio_minus_one", "jello_collide", JELLO, JELLO_DEFAULTS, {"poisson_ratio": -1},
         "poisson_ratio: -1", ["key 'materials[0].poisson_ratio' = -1", "expected a number in (-1, 0.5)"]),
    case("friction_angle_90", "column_collapse", COLUMN, COLUMN_DEFAULTS, {"friction_angle": 90},
         "friction_angle: 90",
         ["key 'material.plasticity.friction_angle' = 90", "expected a number in [0, 90)"]),
    case("friction_angle_negative", "column_collapse", COLUMN, COLUMN_DEFAULTS, {"friction_angle": -1},
         "friction_angle: -1",
         ["key 'material.plasticity.friction_angle' = -1", "expected a number in [0, 90)"]),
    case("density_zero", "jello_collide", JELLO, JELLO_DEFAULTS, {"density": 0}, "density: 0",
         ["key 'materials[0].density' = 0", "expected a number > 0"]),
    case("body_beyond_domain_hi", "jello_collide", JELLO, JELLO_DEFAULTS, {"hi": "[1.2, 0.44]"},
         "hi: [1.2, 0.44]", ["key 'bodies[1].hi' = [1.2, 0.44]", "expected the body inside the domain",
                             "lies outside the domain (0, 0) - (1, 0.6)"]),
    case("body_below_domain_lo", "jello_collide", JELLO, JELLO_DEFAULTS, {"lo": "[0.6, -0.1]"},
         "lo: [0.6, -0.1]", ["key 'bodies[1].lo' = [0.6, -0.1]", "expected the body inside the domain"]),
    case("adaptive_levels_out_of_range", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 9}"}, "levels: 9",
         ["key 'adaptive.levels' = 9", "expected an integer in [1, 6]"]),
    case("adaptive_region_outside_domain", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 2, refine: [{box: {lo: [0.5, 0.2], hi: [1.5, 0.4]}}]}"}, "hi: [1.5, 0.4]",
         ["key 'adaptive.refine[0].box.hi' = [1.5, 0.4]", "the box must end inside the domain (<= 1) on axis 0"]),
    case("adaptive_region_level", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 2, refine: [{box: {lo: [0.5, 0.2], hi: [0.6, 0.4]}, level: 3}]}"},
         "level: 3", ["key 'adaptive.refine[0].level' = 3", "expected an integer in [0, 1]"]),
    case("adaptive_refinement_memory", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 6, refine: [{box: {lo: [0.2, 0.2], hi: [0.8, 0.5]}}]}"}, "adaptive:",
         ["key 'adaptive.refine[0].box'", "refining to level 5 (dx 1e-05 m) refines more than",
          "the tree may take half of the", "shrink the region, lower its level or coarsen grid.dx"],
         args=["--set", "grid.dx=1e-5", "--max-memory", "0.05"]),
    case("adaptive_resample_order", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 3, resample: {d_small: 0.01, d_medium: 0.03, d_large: 0.02}}"},
         "d_large: 0.02", ["key 'adaptive.resample.d_large' = 0.02", "must exceed d_medium = 0.03",
                           "0 <= d_small < d_medium < d_large"]),
    case("adaptive_resample_small_above_medium", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 3, resample: {d_small: 0.05, d_medium: 0.03, d_large: 0.06}}"},
         "d_medium: 0.03", ["key 'adaptive.resample.d_medium' = 0.03", "must exceed d_small = 0.05"]),
    case("adaptive_resample_travel_too_far", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 3, resample: {d_small: 0.01, d_medium: 0.03, d_large: 0.05, max_travel: 0.02}}"},
         "max_travel: 0.02", ["key 'adaptive.resample.max_travel' = 0.02", "must lie in (0, (d_medium - d_small) / 2 = 0.01]"]),
    case("adaptive_resample_travel_and_every", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 3, resample: {d_medium: 0.03, d_large: 0.05, every: 5, max_travel: 0.01}}"},
         "max_travel: 0.01", ["key 'adaptive.resample.max_travel' = 0.01", "replaces every = 5"]),
    case("adaptive_resample_fixed_grid", "jello_collide", JELLO, JELLO_DEFAULTS,
         {"adaptive": "adaptive: {levels: 3, follow_particles: false, resample: {d_medium: 0.01, d_large: 0.02}}"},
         "follow_particles: false", ["key 'adaptive.follow_particles' = false",
                                     "resampling changes the particle types: the grid must follow them"]),
    case("mesh_missing", "goo_slits", GOO, {}, {"mesh": "missing_plate.obj"}, "missing_plate.obj",
         ["key 'colliders[0].file' = missing_plate.obj", "missing_plate.obj: cannot open the mesh file"]),
    case("mesh_garbage", "goo_slits", GOO, {}, {"mesh": "garbage.obj"}, "garbage.obj",
         ["key 'colliders[0].file' = garbage.obj", "garbage.obj:3: face corner '7' refers to a missing vertex"],
         files={"garbage.obj": "v 0 0 0\nv 1 0 0\nf 1 2 7\n"}),
    case("reference_profile_unordered", "column_collapse", COLUMN, COLUMN_DEFAULTS,
         {"reference": "reference_profile: deposit.csv"}, "reference_profile: deposit.csv",
         ["key 'reference_profile' = deposit.csv", "line 3 is not 'x,height' with finite numbers and x increasing"],
         files={"deposit.csv": "x,height\n0.1,0.2\n0.05,0.1\n"}),
]


def line_number(text, needle):
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


def run(executable, scene, out, args):
    result = subprocess.run([executable, str(scene), "--out", str(out), "--quiet", *args],
                            capture_output=True, text=True, timeout=120)
    return result.returncode, result.stdout, result.stderr


def check_input_error(c, apps, work):
    """Returns the list of problems of one bad-input case (empty: passed)."""
    folder = work / c["name"]
    folder.mkdir(parents=True)
    scene = folder / "scene.yaml"
    scene.write_text(c["text"])
    for name, content in c["files"].items():
        (folder / name).write_text(content)
    out = folder / "out"
    status, stdout, stderr = run(apps[c["app"]], scene, out, c["args"])

    problems = []
    if status != 2:
        problems.append(f"exit status {status}, expected 2 (input error)")
    lines = stderr.splitlines()
    if len(lines) != 1:
        problems.append(f"stderr has {len(lines)} lines, expected one message")
    if not stderr.startswith(f"{c['app']}: input error: "):
        problems.append(f"stderr does not start with '{c['app']}: input error: '")
    expected = list(c["expected"])
    if c["line_of"] is not None:
        expected.insert(0, f"{scene}:{line_number(c['text'], c['line_of'])}:")
    problems += [f"stderr lacks '{text}'" for text in expected if text not in stderr]
    if stdout:
        problems.append("stdout is not empty")
    if out.exists():
        problems.append(f"the output folder {out} was created")
    return problems, stderr


def check_numerical_stop(apps, work):
    folder = work / "overflow"
    folder.mkdir(parents=True)
    scene = folder / "scene.yaml"
    scene.write_text(OVERFLOW)
    status, _, stderr = run(apps["jello_collide"], scene, folder / "out", [])
    message = stderr.strip()
    problems = []
    if status != 3:
        problems.append(f"exit status {status}, expected 3 (numerical error)")
    if len(message.splitlines()) != 1:
        problems.append("stderr is not one message")
    for text in ["jello_collide: numerical error: ", "stage 'grid_update'", "grid node", "non-finite velocity"]:
        if text not in message:
            problems.append(f"stderr lacks '{text}'")
    return problems, stderr


def check_threads(apps, work):
    """--threads: out of range is refused before any output; in range is what the run used."""
    folder = work / "threads"
    folder.mkdir(parents=True)
    scene = folder / "scene.yaml"
    scene.write_text(JELLO.format(**JELLO_DEFAULTS))
    problems, messages = [], []
    for bad in ["0", str(len(os.sched_getaffinity(0)) + 1)]:
        out = folder / f"out_{bad}"
        status, stdout, stderr = run(apps["jello_collide"], scene, out, ["--threads", bad])
        first = stderr.splitlines()[0] if stderr else ""
        messages.append(first)
        if status != 2:
            problems.append(f"--threads {bad}: exit status {status}, expected 2")
        for text in ["jello_collide: --threads", f"Value {bad} not in range 1 to"]:
            if text not in first:
                problems.append(f"--threads {bad}: the first line of stderr lacks '{text}'")
        if out.exists():
            problems.append(f"--threads {bad}: the output folder {out} was created")
    out = folder / "out_1"
    status, _, stderr = run(apps["jello_collide"], scene, out, ["--threads", "1"])
    if status != 0:
        problems.append(f"--threads 1: exit status {status}, expected 0: {stderr.strip()}")
    else:
        threads = json.loads((out / "summary.json").read_text())["info"].get("threads")
        if threads != "1":
            problems.append(f"--threads 1: the summary's info.threads is {threads!r}, expected '1'")
    return problems, " / ".join(messages)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    for app in ["column_collapse", "jello_collide", "goo_slits", "vibrating_bar"]:
        parser.add_argument("--" + app.replace("_", "-"), required=True, dest=app, help=f"the {app} executable")
    parser.add_argument("--work", required=True, type=pathlib.Path, help="scratch folder (emptied)")
    args = parser.parse_args()
    apps = {name: getattr(args, name) for name in ["column_collapse", "jello_collide", "goo_slits", "vibrating_bar"]}
    shutil.rmtree(args.work, ignore_errors=True)

    results = [(c["name"], *check_input_error(c, apps, args.work)) for c in CASES]
    results.append(("threads", *check_threads(apps, args.work)))
    results.append(("numerical_overflow", *check_numerical_stop(apps, args.work)))
    failed = 0
    for name, problems, stderr in results:
        print(f"{'FAILED' if problems else 'ok':6} {name}: {stderr.strip()}")
        for problem in problems:
            print(f"         - {problem}")
        failed += bool(problems)
    print(f"{failed} of {len(results)} cases failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
