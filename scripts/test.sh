#!/usr/bin/env bash
# Builds and runs the whole test suite (README's test command; CI runs it too).
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${SEMSLAM_BUILD_PRESET:-release}"
./scripts/build.sh
start=$(date +%s)
ctest --preset "$preset" -j "$(nproc)" "$@"
echo "tests ($preset): $(( $(date +%s) - start )) s"
