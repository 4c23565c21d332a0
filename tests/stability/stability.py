#!/usr/bin/env python3
"""The stability suite: stiff and extreme solid cases, each with its stated expected outcome.

Every case runs an app on a scene with --set overrides and must end as expected: either it
completes (exit 0) with bounded energy (solid_scene --check: the total energy never grows by
more than 2 %) and no NaN in diagnostics.csv, or it stops with exit 3 and a message that
names the stage, the particle or node and the quantity. A case that hangs past its timeout,
dies by a signal or leaves NaNs fails.

    stability.py --bin BUILD/apps --work DIR [--doc docs/stability.md] [--only NAME]
"""
import argparse, csv, json, math, os, shutil, subprocess, sys, time

BASE = "data/scenes/stability/block_drop.yaml"
BLOCK = "bodies.0"

# (name, what it stresses, scene, overrides, expectation)
#   expectation: ("completes", None) or ("stops", [substrings of the one-line message])
CASES = [
    ("stiff_1e7", "Young's modulus 1e7 Pa, automatic time step", BASE,
     ["materials.0.youngs_modulus=1e7", "time.end=0.05"], ("completes", None)),
    ("stiff_1e10", "Young's modulus 1e10 Pa, automatic time step (dt ~ 2e-6 s)", BASE,
     ["materials.0.youngs_modulus=1e10", "time.end=0.01"], ("completes", None)),
    ("max_dt_10x", "time.max_dt 10x above the stable step: the controller subdivides, never exceeds the limit", BASE,
     ["materials.0.youngs_modulus=1e7", "time.max_dt=3e-3", "time.end=0.05"], ("completes", None)),
    ("crushed_5pct", "block crushed to 5 % of its height (F = diag(1, 0.05)) and released", BASE,
     [f"{BLOCK}.stretch=[1, 0.05]", f"{BLOCK}.lo=[0.3, 0.2]", f"{BLOCK}.hi=[0.7, 0.22]",
      "materials.0.elasticity=neo_hookean", "time.end=0.3"], ("completes", None)),
    ("inverted_fixed_corotated", "every particle starts inverted, F = diag(1, -0.5) (fixed corotated)", BASE,
     [f"{BLOCK}.stretch=[1, -0.5]", "time.end=0.2"], ("completes", None)),
    ("inverted_neo_hookean", "inverted start with Neo-Hookean, whose log J is undefined for det F <= 0", BASE,
     [f"{BLOCK}.stretch=[1, -0.5]", "materials.0.elasticity=neo_hookean", "time.end=0.2"],
     ("stops", ["stage 'stress_forces'", "particle", "inverted", "det F"])),
    ("twisted_bar_3d", "3D bar held at x = 0 (sticky wall), spun about its axis at 20 rad/s", "data/scenes/stability/twisted_bar_3d.yaml",
     [], ("completes", None)),
    ("impact_100ms", "block hits the floor at 100 m/s", BASE,
     [f"{BLOCK}.velocity=[0, -100]", "time.end=0.02", "time.frame_dt=0.002"], ("completes", None)),
    ("leaves_domain", "the floor is open: the block falls out of the grid", BASE,
     ["walls.y_min=open", "time.end=1"], ("stops", ["stage 'sort'", "particle", "left the grid domain"])),
    ("single_particle", "one particle (one lattice point in the body)", BASE,
     [f"{BLOCK}.lo=[0.5, 0.5]", f"{BLOCK}.hi=[0.52, 0.52]", f"{BLOCK}.particles_per_cell=1"], ("completes", None)),
    ("empty_domain", "no particles at all", "data/scenes/stability/empty.yaml", [], ("completes", None)),
    ("zero_gravity", "a block at rest without gravity stays exactly at rest", BASE,
     ["gravity=[0, 0]"], ("completes", None)),
]


def run_case(bin_dir, work, case):
    name, _, scene, overrides, (outcome, needles) = case
    out = os.path.join(work, name)
    shutil.rmtree(out, ignore_errors=True)
    cmd = [os.path.join(bin_dir, "solid_scene"), scene, "--out", out, "--quiet"]
    for o in overrides:
        cmd += ["--set", o]
    if outcome == "completes":
        cmd.append("--check")
    start = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return False, "hang: no exit within 120 s", {}
    seconds = time.monotonic() - start
    info = {"seconds": seconds, "exit": p.returncode}
    if p.returncode < 0:
        return False, f"killed by signal {-p.returncode}", info
    rows = []
    path = os.path.join(out, "diagnostics.csv")
    if os.path.exists(path):
        with open(path) as f:
            rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            if not math.isfinite(float(v)):
                return False, f"non-finite {k} in diagnostics.csv frame {r['frame']}", info
    info["steps"] = sum(int(float(r["steps"])) for r in rows)
    info["max_speed"] = max((float(r["max_speed"]) for r in rows), default=0.0)
    if outcome == "completes":
        summary = os.path.join(out, "summary.json")
        if p.returncode != 0 or not os.path.exists(summary):
            return False, f"expected completion, got exit {p.returncode}: {p.stderr.strip()[-400:]}", info
        info["energy_growth"] = json.load(open(summary))["results"]["energy_growth"]
        if name == "zero_gravity" and info["max_speed"] != 0.0:
            return False, f"a block at rest moved (max speed {info['max_speed']})", info
        return True, "completed, energy bounded", info
    message = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    info["message"] = message
    if p.returncode != 3:
        return False, f"expected a numerical stop (exit 3), got exit {p.returncode}: {message}", info
    missing = [n for n in needles if n not in message]
    if missing:
        return False, f"message lacks {missing}: {message}", info
    return True, "stopped with a diagnostic", info


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--doc")
    ap.add_argument("--only")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    failures, lines = 0, []
    for case in CASES:
        if args.only and case[0] != args.only:
            continue
        ok, why, info = run_case(args.bin, args.work, case)
        failures += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {case[0]:26s} {why}  {json.dumps(info)}")
        expected = "completes, energy growth < 2 %" if case[4][0] == "completes" else \
            "stops (exit 3) naming " + ", ".join(case[4][1])
        measured = (f"growth {info.get('energy_growth', 0):.2e}, {info.get('steps', 0)} steps, "
                    f"{info.get('seconds', 0):.1f} s") if case[4][0] == "completes" else info.get("message", why)
        lines.append(f"| `{case[0]}` | {case[1]} | {expected} | {'pass' if ok else 'FAIL'}: {measured} |")
    if args.doc:
        with open(args.doc, "w") as f:
            f.write(open(os.path.join(os.path.dirname(__file__), "stability_header.md")).read())
            f.write("| case | setup | expected outcome | measured |\n| --- | --- | --- | --- |\n")
            f.write("\n".join(lines) + "\n")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
