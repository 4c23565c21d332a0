#!/usr/bin/env python3
"""Golden-file regression: runs an app with the scene and overrides stored in a golden file and
compares a few scalars of its summary.json and diagnostics.csv with the stored values.

  golden.py --app build/apps/column_collapse \\
            --golden data/reference/golden/column_collapse_2d.json --work /tmp/golden
  golden.py ... --regenerate   # run once and store the new values (settings, tolerances kept)

Golden file (JSON): "scene" (path relative to the golden file), "set" (the --set overrides),
"quantities": {name: {"source": "summary", "key": K} or {"source": "diagnostics",
"column": C, "frame": F} ("frame": "sum" adds the column over all frames), "value",
"abs", "rel"}. A quantity passes when |value - golden| <= abs + rel * |golden|.
Exit status: 0 all pass (or regenerated), 1 a quantity differs, 2 the run itself failed.
"""
import argparse
import csv
import json
import math
import pathlib
import shutil
import subprocess
import sys


def run_app(app, scene, overrides, out):
    shutil.rmtree(out, ignore_errors=True)
    command = [app, str(scene), "--out", str(out), "--quiet"]
    for assignment in overrides:
        command += ["--set", assignment]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.stderr.write(result.stderr)
        sys.exit(f"golden.py: {' '.join(command)} exited with {result.returncode}")


def measure(spec, summary, rows):
    if spec["source"] == "summary":
        return summary["results"][spec["key"]]
    column = spec["column"]
    if spec["frame"] == "sum":
        return math.fsum(float(row[column]) for row in rows)
    matches = [row for row in rows if int(float(row["frame"])) == spec["frame"]]
    if len(matches) != 1:
        sys.exit(f"golden.py: diagnostics.csv has {len(matches)} rows for frame {spec['frame']}")
    return float(matches[0][column])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--app", required=True, help="the app executable")
    parser.add_argument("--golden", required=True, type=pathlib.Path, help="golden JSON file")
    parser.add_argument("--work", required=True, type=pathlib.Path, help="output folder of the run")
    parser.add_argument("--regenerate", action="store_true", help="store the new values")
    args = parser.parse_args()

    golden = json.loads(args.golden.read_text())
    run_app(args.app, args.golden.parent / golden["scene"], golden["set"], args.work)
    summary = json.loads((args.work / "summary.json").read_text())
    with open(args.work / "diagnostics.csv", newline="") as f:
        rows = list(csv.DictReader(f))

    failed = 0
    print(f"{'quantity':36} {'value':>24} {'golden':>24} {'|difference|':>12} {'tolerance':>12}")
    for name, spec in golden["quantities"].items():
        value = measure(spec, summary, rows)
        if args.regenerate:
            spec["value"] = value
            print(f"{name:36} {value:24.17g} (stored)")
            continue
        expected = spec["value"]
        difference = abs(value - expected)
        tolerance = spec["abs"] + spec["rel"] * abs(expected)
        ok = difference <= tolerance
        failed += not ok
        print(f"{name:36} {value:24.17g} {expected:24.17g} {difference:12.3g} {tolerance:12.3g}"
              f"{'' if ok else '  FAILED'}")

    if args.regenerate:
        args.golden.write_text(json.dumps(golden, indent=2) + "\n")
        print(f"wrote {args.golden}")
        return 0
    print(f"{failed} of {len(golden['quantities'])} quantities outside their tolerance")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
