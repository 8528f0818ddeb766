#!/usr/bin/env bash
# Builds semslam and runs the whole pipeline on the built-in synthetic city; outputs go to ${1:-out/demo}.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/demo}"
./scripts/build.sh
./build/"${SEMSLAM_BUILD_PRESET:-release}"/bin/semslam demo --out "$out"
