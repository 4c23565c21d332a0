#!/usr/bin/env python3
"""Runs an app that must FAIL its --check: exit status exactly 1 (a failed check, not a crash,
an input error (2) or a numerical error (3)) and stderr/stdout holding a line that matches
every --match regular expression (the check line that failed).

    expect_check_failure.py --match 'check pressure_converged: .* FAILED' -- APP SCENE --check ...
"""
import argparse, re, subprocess, sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--match", action="append", default=[], help="regular expression a line must match")
    ap.add_argument("--code", type=int, default=1, help="the exit status expected (default 1)")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    args = ap.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    p = subprocess.run(command, capture_output=True, text=True)
    output = p.stdout + p.stderr
    lines = output.splitlines()
    failed = []
    if p.returncode != args.code:
        failed.append(f"exit {p.returncode}, expected {args.code}")
    for pattern in args.match:
        hits = [l for l in lines if re.search(pattern, l)]
        if hits:
            print(f"matched {pattern!r}: {hits[0]}")
        else:
            failed.append(f"no line matches {pattern!r}")
    if failed:
        print("FAILED: " + "; ".join(failed) + "\n--- output (last 40 lines) ---\n" + "\n".join(lines[-40:]))
        return 1
    print(f"ok: exit {p.returncode} as expected")
    return 0


if __name__ == "__main__":
    sys.exit(main())
