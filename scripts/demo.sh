#!/usr/bin/env bash
# Installs what is missing (Debian), builds only the semslam binary (not the tests and benchmarks) and runs the
# whole pipeline on the built-in synthetic city; outputs go to ${1:-out/demo}. Extra arguments go to `semslam demo`.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/demo}"
shift || true
preset="${SEMSLAM_BUILD_PRESET:-release}"
./scripts/install-deps.sh
export CCACHE_DIR="${CCACHE_DIR:-$PWD/.cache/ccache}"
cmake --preset "$preset" >/dev/null
start=$(date +%s)
cmake --build --preset "$preset" --target semslam_cli -j "$(nproc)"
echo "build (semslam binary, $preset): $(( $(date +%s) - start )) s"
./build/"$preset"/bin/semslam demo --out "$out" "$@"
