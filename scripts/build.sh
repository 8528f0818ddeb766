#!/usr/bin/env bash
# Installs the dependencies (if missing), configures and builds. Preset: $SEMSLAM_BUILD_PRESET (default release;
# the sanitizer presets build only the CLI, the tests and the fuzz targets).
set -euo pipefail
if [ $# -gt 0 ]; then  # a preset given as an argument would be ignored and release built
  echo "usage: [SEMSLAM_BUILD_PRESET=release|debug|asan|tsan|ci] scripts/build.sh   (no arguments)" >&2
  exit 2
fi
cd "$(dirname "$0")/.."
preset="${SEMSLAM_BUILD_PRESET:-release}"
./scripts/install-deps.sh
# The compiler cache lives outside the clone, so that a fresh clone (CI's) starts warm; CCACHE_BASEDIR makes
# the paths relative, so that clones in different places share it.
export CCACHE_DIR="${CCACHE_DIR:-$HOME/.cache/ccache}"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
cmake --preset "$preset" >/dev/null
start=$(date +%s)
cmake --build --preset "$preset" -j "$(nproc)"
echo "build ($preset): $(( $(date +%s) - start )) s"
