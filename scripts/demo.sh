#!/usr/bin/env bash
# Installs what is missing (Debian), builds only the semslam binary (not the tests and benchmarks) and runs the
# whole pipeline on the built-in synthetic city; outputs go to ${1:-out/demo} (a folder given is taken relative to
# where the script is started; the default is in the checkout). Extra arguments go to `semslam demo`; when the
# first argument is an option (`scripts/demo.sh --frames 100`), it goes there too and the outputs to out/demo.
set -euo pipefail
out=out/demo
if [ $# -gt 0 ] && [[ $1 != -* ]]; then
  [ -z "$1" ] || out="$(realpath -m -- "$1")"
  shift
fi
cd "$(dirname "$0")/.."
preset="${SEMSLAM_BUILD_PRESET:-release}"
./scripts/install-deps.sh
export CCACHE_DIR="${CCACHE_DIR:-$PWD/.cache/ccache}"
cmake --preset "$preset" >/dev/null
start=$(date +%s)
cmake --build --preset "$preset" --target semslam_cli -j "$(nproc)"
echo "build (semslam binary, $preset): $(( $(date +%s) - start )) s"
./build/"$preset"/bin/semslam demo --out "$out" "$@"
