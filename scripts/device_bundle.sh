#!/usr/bin/env bash
# Gathers programs built here and the shared libraries they load (except the C library's own)
# into one folder, to run them on a machine without the project's Debian packages (the
# accelerator machine: docs/gpu.md):
#   bash scripts/device_bundle.sh <build dir> <bundle dir> <program paths relative to build dir...>
# Then, there: LD_LIBRARY_PATH=<bundle dir>/lib <bundle dir>/bin/<program>
set -euo pipefail
build=$1
bundle=$2
shift 2
rm -rf "$bundle"
mkdir -p "$bundle/bin" "$bundle/lib"
for program in "$@"; do
  cp "$build/$program" "$bundle/bin/"
  ldd "$build/$program" | awk '/=> \// {print $3}' | while read -r library; do
    case "$(basename "$library")" in
      libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux*) ;;
      *) cp -nL "$library" "$bundle/lib/" ;;
    esac
  done
done
strip --strip-unneeded "$bundle"/bin/* "$bundle"/lib/* 2>/dev/null || true
du -sh "$bundle"
