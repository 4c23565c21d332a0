"""Shared by the regression scripts that compare runs of a scene app: their command line, one
run without particle frames or previews, its results and CSV outputs, and the report of the
checks."""
import argparse
import csv
import json
import pathlib
import subprocess
import sys

QUICK = ["--set", "output.png=false", "--set", "output.particles=false", "--quiet"]


def scene_app_parser():
    """A command line with the options every comparison takes: --app, --scenes, --work."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--app", required=True, help="the scene app's executable")
    parser.add_argument("--scenes", required=True, type=pathlib.Path, help="data/scenes")
    parser.add_argument("--work", required=True, type=pathlib.Path, help="folder for the runs")
    return parser


def parse_scene_app_args(parser):
    """The parsed command line, its --work folder created."""
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    return args


def run_app(app, scene, out, overrides=()):
    """Runs `app scene --out out --set <override>...` and returns summary.json's results; a
    failed run prints its command and stderr and exits with status 2."""
    command = [str(app), str(scene), "--out", str(out)] + QUICK
    for assignment in overrides:
        command += ["--set", assignment]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        print(f"run failed ({done.returncode}): {' '.join(command)}\n{done.stderr}")
        sys.exit(2)
    return json.loads((out / "summary.json").read_text())["results"]


def read_csv(path):
    """The rows of a CSV file with a header, as dicts of text."""
    with open(path) as f:
        return list(csv.DictReader(f))


def run_with_diagnostics(app, scene, out, overrides=()):
    """run_app's results and the rows of the run's diagnostics.csv."""
    return run_app(app, scene, out, overrides), read_csv(out / "diagnostics.csv")


def report(checks):
    """Prints each (what, holds) check; the exit status: 0 all hold, 1 one fails."""
    failed = 0
    for what, ok in checks:
        print(f"check {what}: {'ok' if ok else 'FAILED'}")
        failed += not ok
    return 1 if failed else 0
