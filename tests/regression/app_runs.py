"""Shared by the regression scripts that compare runs of a scene app: one run without
particle frames or previews, its results, and its CSV outputs."""
import csv
import json
import subprocess
import sys

QUICK = ["--set", "output.png=false", "--set", "output.particles=false", "--quiet"]


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
