"""Shared by the bad-input drivers (fluid_app_errors.py, coupled_app_errors.py): runs an app on
one rewritten scene and lists what is wrong with its exit. Bad input must exit 2 with exactly
one stderr line naming the scene file and line of the key, the key path and the expected
substrings, and must leave no --out folder."""
import pathlib
import shutil
import subprocess


def check_bad_input(app, scene_file, line, path, expected):
    """Runs `app scene_file`; returns (problems, stderr). `line` is the key's line in the file."""
    out = scene_file.with_name(scene_file.stem + "_out")
    r = subprocess.run([app, str(scene_file), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=60)
    problems = []
    if r.returncode != 2:
        problems.append(f"exit {r.returncode}, expected 2")
    if len(r.stderr.strip().splitlines()) != 1:
        problems.append(f"{len(r.stderr.strip().splitlines())} stderr lines, expected 1")
    for sub in [f"{scene_file.name}:{line}:", f"'{path}'"] + expected:
        if sub not in r.stderr:
            problems.append(f"message lacks {sub!r}")
    if out.exists():
        problems.append("the --out folder was created")
    return problems, r.stderr.strip()


def run_cases(app, scene, work, cases):
    """Runs every case and prints one line each; returns the exit status of the driver.
    `cases`: (label, key path, rewrite, expected) with rewrite(text) -> (new text, key line)."""
    work = pathlib.Path(work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    text = pathlib.Path(scene).read_text()
    failures = 0
    for i, (label, path, rewrite, expected) in enumerate(cases):
        rewritten, line = rewrite(text)
        scene_file = work / f"case_{i}.yaml"
        scene_file.write_text(rewritten)
        problems, message = check_bad_input(app, scene_file, line, path, expected)
        status = "ok" if not problems else "FAILED: " + "; ".join(problems)
        print(f"{label}: {status}\n  {message}")
        failures += bool(problems)
    return 1 if failures else 0
