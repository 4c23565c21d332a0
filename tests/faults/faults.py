#!/usr/bin/env python3
"""Fault injection: runs are killed, stopped, restarted from corrupted, truncated or foreign
checkpoints, given edited input files, a full disk and an output folder that cannot be written,
and each case checks its stated outcome. A continued run must be bit-identical to the run that
was never interrupted: the same diagnostics.csv rows (every column at 17 significant digits but
the seconds_* timings and run_id) and the same state_checksum in summary.json (the checksum of
every particle channel of the final checkpoint).

  faults.py --apps build/apps --scenes data/scenes --work /tmp/faults [--seed N] [--doc F]

Kill times are drawn at random (the seed is printed; --seed repeats a draw). Exit status 0 when
every case has its expected outcome; --doc writes the results table into a Markdown file
between the markers <!-- faults:begin --> and <!-- faults:end -->.
"""
import argparse
import csv
import os
import random
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

# The base run: a small 2D granular column collapse of about a second on one core.
BASE = ["--set", "column.cells_per_width=12", "--set", "time.end=0.5", "--set", "time.frame_dt=0.02",
        "--set", "output.png=false", "--quiet"]
EXIT_STOPPED = {signal.SIGTERM: 143, signal.SIGINT: 130}


class Case:
    def __init__(self, name, fault, expected):
        self.name, self.fault, self.expected = name, fault, expected
        self.observed, self.ok = "", False


class Faults:
    def __init__(self, args):
        self.apps, self.scenes, self.work = Path(args.apps), Path(args.scenes), Path(args.work)
        self.rng = random.Random(args.seed)
        self.collapse = self.app("column_collapse")
        self.scene = self.scenes / "column_collapse.yaml"
        shutil.rmtree(self.work, ignore_errors=True)
        self.work.mkdir(parents=True)
        self.reference = None

    def app(self, name):
        return str(self.apps / name / name) if (self.apps / name).is_dir() else str(self.apps / name)

    def command(self, out, extra=(), app=None, scene=None):
        return [app or self.collapse, str(scene or self.scene), "--out", str(out)] + BASE + list(extra)

    def run(self, out, extra=(), **kw):
        done = subprocess.run(self.command(out, extra, **kw), capture_output=True, text=True)
        return done.returncode, done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ""

    def start(self, out, extra=()):
        return subprocess.Popen(self.command(out, extra), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)

    # --- comparison with the uninterrupted run ---------------------------------------------
    def rows(self, out):
        with open(Path(out) / "diagnostics.csv") as f:
            rows = list(csv.DictReader(f))
        return [{k: v for k, v in r.items() if not k.startswith("seconds_") and k != "run_id"} for r in rows], \
            {r["run_id"] for r in rows}

    def checksum(self, out):
        text = (Path(out) / "summary.json").read_text()
        m = re.search(r'"state_checksum"\s*:\s*"([^"]+)"', text)
        return m.group(1) if m else None

    def same_as_reference(self, out):
        rows, runs = self.rows(out)
        ref_rows, _ = self.rows(self.reference)
        if len(runs) != 1:
            return False, f"diagnostics.csv mixes {len(runs)} run ids"
        if rows != ref_rows:
            first = next((i for i, (a, b) in enumerate(zip(rows, ref_rows)) if a != b), min(len(rows), len(ref_rows)))
            return False, f"diagnostics differ from frame {first} ({len(rows)} rows, reference {len(ref_rows)})"
        if self.checksum(out) != self.checksum(self.reference):
            return False, f"state checksum {self.checksum(out)} != {self.checksum(self.reference)}"
        stale = [p.name for p in Path(out).iterdir() if ".tmp-" in p.name]
        if stale:
            return False, f"temporary files left: {stale}"
        return True, f"{len(rows)} rows and state checksum {self.checksum(out)} equal the uninterrupted run's"

    def newest_checkpoint(self, out):
        numbered = sorted(Path(out).glob("checkpoint_[0-9]*.h5"))
        stopped = Path(out) / "checkpoint_stopped.h5"
        return stopped if stopped.exists() else (numbered[-1] if numbered else None)

    def continue_run(self, out, extra=()):
        """Restarts from the newest checkpoint (a fresh run when there is none) to the end."""
        checkpoint = self.newest_checkpoint(out)
        code, line = self.run(out, list(extra) + (["--restart", str(checkpoint)] if checkpoint else []))
        if code != 0:
            raise RuntimeError(f"the continued run failed ({code}): {line}")

    # --- the cases -----------------------------------------------------------------------------
    def uninterrupted(self, case):
        out = self.work / "reference"
        began = time.monotonic()
        code, line = self.run(out)
        self.duration = time.monotonic() - began
        self.reference = out
        case.ok = code == 0 and self.checksum(out) is not None
        case.observed = f"exit {code}, {self.duration:.2f} s, state checksum {self.checksum(out)}"

    def killed(self, case, how, during_output=False, kills=1):
        out = self.work / case.name
        extra = ["--set", "output.checkpoint_every=1"] if how == signal.SIGKILL else []
        if during_output:  # frames of one step or two: most of the time goes to writing them
            extra += ["--set", "time.frame_dt=0.0005", "--set", "time.end=0.05"]
        reference = self.reference
        if during_output:
            code, line = self.run(self.work / (case.name + "_reference"), extra)
            reference = self.work / (case.name + "_reference")
        codes, err = [], ""
        for k in range(kills):
            # A kill that comes after the run ended tests nothing: the first run is tried again,
            # sooner, until the signal lands (a restart that ended simply finished the run).
            delay = self.rng.uniform(0.1, 0.7) * self.duration
            for attempt in range(6):
                if k == 0:
                    shutil.rmtree(out, ignore_errors=True)
                checkpoint = self.newest_checkpoint(out) if k else None
                process = self.start(out, extra + (["--restart", str(checkpoint)] if checkpoint else []))
                time.sleep(delay)
                process.send_signal(how)
                _, err = process.communicate()
                if process.returncode != 0 or k > 0:
                    break
                delay /= 2
            codes.append(process.returncode)
            if process.returncode == 0:
                break
        expected = -signal.SIGKILL if how == signal.SIGKILL else EXIT_STOPPED[how]
        missed = [c for c in codes if c == 0]
        wrong = [c for c in codes if c not in (0, expected)]
        if wrong:
            case.observed = f"exit codes {codes}, expected {expected}: {err.strip().splitlines()[-1:]}"
            return
        self.continue_run(out, extra)
        saved, self.reference = self.reference, reference
        case.ok, why = self.same_as_reference(out)
        self.reference = saved
        case.ok = case.ok and codes[0] != 0
        case.observed = f"exit codes {codes}" + (" (the last restart ended before its kill)" if missed else "") + \
            f"; continued: {why}"

    def failed_restart_then_restart(self, case):
        out = self.work / case.name
        extra = ["--set", "output.checkpoint_every=5", "--set", "output.checkpoints_kept=10"]
        code, _ = self.run(out, extra)
        process = self.start(out, extra + ["--restart", str(out / "checkpoint_0010.h5")])
        time.sleep(self.rng.uniform(0.1, 0.6) * self.duration)
        process.kill()
        process.wait()
        latest = self.newest_checkpoint(out)
        self.continue_run(out, extra)
        case.ok, why = self.same_as_reference(out)
        case.observed = f"killed the restart from frame 10; continued from {latest.name}: {why}"

    def changed_checkpoint(self, case, change, expected_exit, expected_text):
        out = self.work / case.name
        self.run(out, ["--set", "output.checkpoint_every=5"])
        checkpoint = out / "checkpoint_0025.h5"
        before = (out / "diagnostics.csv").read_bytes()
        data = bytearray(checkpoint.read_bytes())
        change(data)
        checkpoint.write_bytes(bytes(data))
        code, line = self.run(out, ["--restart", str(checkpoint)])
        untouched = (out / "diagnostics.csv").read_bytes() == before
        case.ok = code == expected_exit and expected_text in line and untouched
        case.observed = f"exit {code}: {line[:160]}" + ("; folder untouched" if untouched else "; FOLDER CHANGED")

    @staticmethod
    def scale_one_mass(data):
        # Every particle of the column has the same mass and the same volume0: the two doubles
        # that occur once per particle. The mass is the larger (density > 1 kg/m^3); its first
        # occurrence is scaled by 1000.
        counts = {}
        for i in range(0, len(data) - 8, 8):
            counts[bytes(data[i:i + 8])] = counts.get(bytes(data[i:i + 8]), 0) + 1
        candidates = [v for v in counts if 1e-9 < abs(struct.unpack("<d", v)[0]) < 1e6]
        value = max(candidates, key=lambda v: (counts[v], abs(struct.unpack("<d", v)[0])))
        at = bytes(data).find(value)
        data[at:at + 8] = struct.pack("<d", struct.unpack("<d", value)[0] * 1000)

    def foreign(self, case, other_scene):
        out, other = self.work / case.name, self.work / (case.name + "_other")
        self.run(out)
        self.run(other, ["--set", "column.cells_per_width=10"] if other_scene else [])
        before = (out / "diagnostics.csv").read_bytes()
        code, line = self.run(out, ["--restart", str(other / "checkpoint_0025.h5")])
        untouched = (out / "diagnostics.csv").read_bytes() == before
        expected = "another scene" if other_scene else "belongs to run"
        case.ok = code == 2 and expected in line and untouched
        case.observed = f"exit {code}: {line[:160]}"

    def edited_mesh(self, case):
        if not Path(self.app("goo_slits")).exists():  # built with OpenVDB only
            case.ok, case.observed = True, "skipped: this build has no goo_slits app (OpenVDB off)"
            return
        folder = self.work / case.name
        (folder / "meshes").mkdir(parents=True)
        (folder / "scenes").mkdir()
        shutil.copy(self.scenes / "goo_slits.yaml", folder / "scenes")
        mesh = folder / "meshes" / "slotted_plate.obj"
        shutil.copy(self.scenes.parent / "meshes" / "slotted_plate.obj", mesh)
        app, scene, out = self.app("goo_slits"), folder / "scenes" / "goo_slits.yaml", folder / "out"
        extra = ["--set", "grid.dx=0.03", "--set", "time.end=0.06"]
        command = [app, str(scene), "--out", str(out), "--quiet", "--set", "output.png=false"] + extra
        subprocess.run(command, capture_output=True)
        text = mesh.read_text().splitlines()
        first_vertex = next(i for i, l in enumerate(text) if l.startswith("v "))
        x, y, z = map(float, text[first_vertex].split()[1:4])
        text[first_vertex] = f"v {x + 0.01} {y} {z}"
        mesh.write_text("\n".join(text) + "\n")
        done = subprocess.run(command + ["--restart", str(out / "checkpoint_0003.h5")], capture_output=True, text=True)
        line = done.stderr.strip().splitlines()[-1]
        case.ok = done.returncode == 2 and "changed since" in line
        case.observed = f"exit {done.returncode}: {line[:200]}"

    def disk_full(self, case):
        out = self.work / case.name
        out.mkdir()

        def small_files():  # writes past 64 kB fail with EFBIG, as on a full disk with ENOSPC
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, 64 * 1024))

        done = subprocess.run(self.command(out, ["--set", "output.checkpoint_every=1"]), capture_output=True, text=True,
                              preexec_fn=small_files)
        line = done.stderr.strip().splitlines()[-1]
        stale = [p.name for p in out.iterdir() if ".tmp-" in p.name]
        case.ok = done.returncode == 4 and "cannot write" in line and not stale
        case.observed = f"exit {done.returncode}: {line[:200]}" + (f"; left {stale}" if stale else "; no partial file")

    def unwritable_folder(self, case):
        blocker = self.work / case.name
        blocker.write_text("a file where the output folder's parent should be\n")
        code, line = self.run(blocker / "out")
        case.ok = code == 4 and str(blocker) in line
        case.observed = f"exit {code}: {line[:200]}"
        if os.geteuid() != 0:  # permissions bind only a user other than root
            folder = self.work / (case.name + "_readonly")
            folder.mkdir()
            folder.chmod(0o555)
            code2, line2 = self.run(folder)
            folder.chmod(0o755)
            case.ok = case.ok and code2 == 4
            case.observed += f"; read-only folder: exit {code2}: {line2[:120]}"

    def rerun_into_used_folder(self, case):
        out = self.work / case.name
        self.run(out)
        code, _ = self.run(out, ["--set", "time.end=0.2"])
        rows, runs = self.rows(out)
        later = [p.name for p in out.iterdir() if re.search(r"_(\d{4})\.", p.name) and
                 int(re.search(r"_(\d{4})\.", p.name).group(1)) > 10]
        case.ok = code == 0 and len(rows) == 11 and len(runs) == 1 and not later
        case.observed = f"exit {code}; {len(rows)} rows of {len(runs)} run; files of frames > 10 left: {len(later)}"

    def stale_temporaries(self, case):
        out = self.work / case.name
        out.mkdir()
        dead = subprocess.Popen(["true"])
        dead.wait()
        stale = out / f"particles_0003.h5.tmp-{dead.pid}"
        stale.write_text("half a file")
        code, _ = self.run(out)
        case.ok = code == 0 and not stale.exists()
        case.observed = f"exit {code}; the dead process's temporary file {'remains' if stale.exists() else 'removed'}"

    def bounded_input(self, case, extra, expected_text):
        code, line = self.run(self.work / case.name, extra)
        case.ok = code == 2 and expected_text in line and not (self.work / case.name / "diagnostics.csv").exists()
        case.observed = f"exit {code}: {line[:200]}"

    def duplicate_key(self, case):
        scene = self.work / "duplicate.yaml"
        scene.write_text(self.scene.read_text() + "\ntime: {end: 0.1}\n")
        code, line = self.run(self.work / case.name, scene=scene)
        case.ok = code == 2 and "given twice" in line
        case.observed = f"exit {code}: {line[:200]}"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--apps", required=True)
    parser.add_argument("--scenes", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--doc", help="Markdown file whose faults table is replaced")
    args = parser.parse_args()
    if args.seed is None:
        args.seed = random.SystemRandom().randrange(1 << 31)
    print(f"faults: seed {args.seed}")
    f = Faults(args)

    def mass(d):
        Faults.scale_one_mass(d)

    def truncate(d):
        del d[len(d) // 2:]

    cases = [
        (Case("uninterrupted", "none (the reference)", "exit 0"), f.uninterrupted),
        (Case("sigterm_stepping", "SIGTERM at a random time", "exit 143 with a checkpoint; continued run identical"),
         lambda c: f.killed(c, signal.SIGTERM)),
        (Case("sigint_stepping", "SIGINT (Ctrl-C) at a random time", "exit 130 with a checkpoint; continued run identical"),
         lambda c: f.killed(c, signal.SIGINT)),
        (Case("kill9_stepping", "kill -9 at a random time (checkpoint_every=1)", "continued from the last checkpoint: identical"),
         lambda c: f.killed(c, signal.SIGKILL)),
        (Case("kill9_three_times", "kill -9 three times, each restart killed again", "identical after the last restart"),
         lambda c: f.killed(c, signal.SIGKILL, kills=3)),
        (Case("kill9_output", "kill -9 while frames are written (a frame every step or two)", "no partial file; identical"),
         lambda c: f.killed(c, signal.SIGKILL, during_output=True)),
        (Case("sigterm_output", "SIGTERM while frames are written", "exit 143; continued run identical"),
         lambda c: f.killed(c, signal.SIGTERM, during_output=True)),
        (Case("failed_restart", "a restart from frame 10 killed, then restarted from its newest checkpoint",
              "no frames lost or spliced: identical"), f.failed_restart_then_restart),
        (Case("corrupt_checkpoint", "one particle's mass x1000 in checkpoint_0025.h5", "exit 4 (checksum); folder untouched"),
         lambda c: f.changed_checkpoint(c, mass, 4, "checksum")),
        (Case("truncated_checkpoint", "checkpoint_0025.h5 cut to half", "exit 4; folder untouched"),
         lambda c: f.changed_checkpoint(c, truncate, 4, "checkpoint_0025.h5")),
        (Case("foreign_checkpoint", "restart from another run's checkpoint (same scene)", "exit 2 (run id); folder untouched"),
         lambda c: f.foreign(c, False)),
        (Case("other_scene_checkpoint", "restart from a checkpoint of another resolution", "exit 2 (scene digest)"),
         lambda c: f.foreign(c, True)),
        (Case("edited_mesh", "collider mesh edited between run and restart (goo_slits)", "exit 2 naming the file and key"),
         f.edited_mesh),
        (Case("disk_full", "writes fail past 64 kB (RLIMIT_FSIZE, EFBIG)", "exit 4 naming the file; no partial file"),
         f.disk_full),
        (Case("unwritable_folder", "output folder cannot be created or written", "exit 4 naming the folder"),
         f.unwritable_folder),
        (Case("rerun_used_folder", "a 10-frame run into the folder of a 25-frame run", "only the new run's files"),
         f.rerun_into_used_folder),
        (Case("stale_temporaries", "a dead process's *.tmp-PID file in the folder", "removed"), f.stale_temporaries),
        (Case("frame_overflow", "time.end=3e9 time.frame_dt=1", "exit 2 naming time.frame_dt; nothing written"),
         lambda c: f.bounded_input(c, ["--set", "time.end=3e9", "--set", "time.frame_dt=1"], "time.frame_dt")),
        (Case("memory_estimate", "--max-memory 0.001 (1 MB) for a 2D column", "exit 2 with the estimate; nothing written"),
         lambda c: f.bounded_input(c, ["--max-memory", "0.001"], "GB")),
        (Case("duplicate_key", "a scene with the key 'time' twice", "exit 2 naming both lines"), f.duplicate_key),
    ]
    for case, body in cases:
        began = time.monotonic()
        try:
            body(case)
        except Exception as e:  # a case that cannot even run has failed
            case.ok, case.observed = False, f"{type(e).__name__}: {e}"
        print(f"{'ok  ' if case.ok else 'FAIL'} {case.name:24s} {time.monotonic() - began:5.1f} s  {case.observed}")
        sys.stdout.flush()

    if args.doc:
        table = ["| case | fault | expected | observed | |", "|---|---|---|---|---|"]
        for case, _ in cases:
            observed = case.observed.replace("|", "/").replace(str(f.work) + "/", "")
            table.append(f"| `{case.name}` | {case.fault} | {case.expected} | {observed} | "
                         f"{'ok' if case.ok else 'FAILED'} |")
        doc = Path(args.doc)
        text = doc.read_text()
        begin, end = "<!-- faults:begin -->", "<!-- faults:end -->"
        head, rest = text.split(begin)
        _, tail = rest.split(end)
        doc.write_text(head + begin + f"\n(seed {args.seed})\n\n" + "\n".join(table) + "\n" + end + tail)
    failed = [c.name for c, _ in cases if not c.ok]
    print(f"faults: {len(cases) - len(failed)}/{len(cases)} as expected" + (f"; failed: {failed}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
