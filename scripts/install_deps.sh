#!/usr/bin/env bash
# Installs every build and test dependency from Debian 12 packages.
# Idempotent: packages already present are skipped; safe to run repeatedly.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  python3              # regression test drivers
  clang-format         # the layout check of CI (.clang-format)
  gnuplot-nox          # error-vs-run-time plots of the study program
  libeigen3-dev        # small fixed-size linear algebra
  libyaml-cpp-dev      # scene files
  libhdf5-dev          # particle output, checkpoints
  libopenvdb-dev       # level-set colliders, mesh -> SDF
  libboost-iostreams-dev  # needed by OpenVDB's CMake module
  libtbb-dev           # shared-memory threads
  libpng-dev           # previews
  doctest-dev          # tests
  libcli11-dev         # command lines
  nlohmann-json3-dev   # summary.json
  libhypre-dev         # pressure solver back-end (libfluid)
  libsuitesparse-dev   # CHOLMOD direct solve (libfluid)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install_deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
