#!/usr/bin/env bash
# Installs the dependencies (if missing), configures and builds. Preset: $SEMSLAM_BUILD_PRESET (default release).
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${SEMSLAM_BUILD_PRESET:-release}"
./scripts/install-deps.sh
export CCACHE_DIR="${CCACHE_DIR:-$PWD/.cache/ccache}"
cmake --preset "$preset" >/dev/null
start=$(date +%s)
cmake --build --preset "$preset" -j "$(nproc)"
echo "build ($preset): $(( $(date +%s) - start )) s"
