#!/usr/bin/env bash
# Installs dependencies, builds, and runs the flagship scene with its default settings.
# Output (HDF5 + XDMF particles, PNG previews, diagnostics.csv, summary.json) goes to
# out/column_collapse/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target column_collapse
./build/apps/column_collapse data/scenes/column_collapse.yaml --out out/column_collapse
