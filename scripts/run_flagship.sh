#!/usr/bin/env bash
# Installs dependencies, builds, and runs the flagship scene with its default settings: a water
# current scouring an erodible sand bed around a pipeline (apps/sediment_transport, scene
# data/scenes/sediment_transport.yaml; about 2-5 min on 2 cores). Output (fluid_NNNN.h5 and
# sediment_NNNN.h5 with XDMF sidecars, PNG previews, diagnostics.csv, bed_profile.csv,
# checkpoints, summary.json) goes to out/sediment_transport/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target sediment_transport
./build/apps/sediment_transport data/scenes/sediment_transport.yaml --out out/sediment_transport
