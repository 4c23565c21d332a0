"""The 3D column collapse on the GPU against the CPU (label gpu): the runouts of
column_collapse with device: cuda (double and single precision) must be within 1 % of the CPU's.
Exits 77 (ctest: skipped) when the build or the machine has no usable CUDA device.

    python3 column_runout.py <apps dir> <data dir> <work dir> [key=value ...]   (scene overrides)
"""
import json
import subprocess
import sys
from pathlib import Path

apps, data, work = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
extra = sys.argv[4:]
scene = data / "scenes" / "column_collapse_3d.yaml"


def run(name, *sets):
    out = work / name
    cmd = [str(apps / "column_collapse"), str(scene), "--out", str(out), "--quiet"]
    for s in ("output.particles=false", "output.png=false", *sets, *extra):
        cmd += ["--set", s]
    result = subprocess.run(cmd, capture_output=True, text=True)
    return result, out


gpu, gpu_out = run("cuda_double", "device=cuda")
# Only a missing back-end or GPU is a skip; any other refusal (memory, a feature) fails.
if gpu.returncode != 0 and ("no CUDA back-end" in gpu.stderr or "no CUDA device" in gpu.stderr):
    print("SKIPPED:", gpu.stderr.strip().splitlines()[-1])
    sys.exit(77)
if gpu.returncode != 0:
    print(gpu.stderr)
    sys.exit(1)
single, single_out = run("cuda_single", "device=cuda", "device_precision=single")
cpu, cpu_out = run("cpu")
for r in (single, cpu):
    if r.returncode != 0:
        print(r.stderr)
        sys.exit(1)
summary = {name: json.loads((out / "summary.json").read_text()) for name, out in
           (("cpu", cpu_out), ("cuda double", gpu_out), ("cuda single", single_out))}
reference = summary["cpu"]["results"]["runout"]
failed = False
for name, s in summary.items():
    runout = s["results"]["runout"]
    error = abs(runout - reference) / reference
    wall = float(s["info"]["wall_seconds"])
    print(f"{name:12s} runout {runout:.5f} m  difference {error:.2e}  wall {wall:.1f} s")
    failed |= error > 0.01
sys.exit(1 if failed else 0)
