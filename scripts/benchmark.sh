#!/usr/bin/env bash
# semslam's benchmark (scripts/benchmark.py): builds the semslam binary (release preset, as scripts/build.sh,
# only that target), then runs every benchmark case and writes OUT/results.json and OUT/results.md.
#   scripts/benchmark.sh [--quick] [--runs N] [--out DIR] [--cases REGEX] [--long-drive DIR] [--first-output]
#                        [--update-baseline] [--write-docs]      (--help: every option)
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${SEMSLAM_BUILD_PRESET:-release}"
for a in "$@"; do
  case "$a" in -h|--help|--list|--markdown|--markdown=*) exec /usr/bin/python3 scripts/benchmark.py "$@" ;; esac
done
./scripts/install-deps.sh
export CCACHE_DIR="${CCACHE_DIR:-$HOME/.cache/ccache}"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
cmake --preset "$preset" >/dev/null
start=$(date +%s)
cmake --build --preset "$preset" --target semslam_cli -j "$(nproc)"
echo "build (semslam binary, $preset): $(( $(date +%s) - start )) s"
SEMSLAM_BENCH_COMMAND="scripts/benchmark.sh $*" exec /usr/bin/python3 scripts/benchmark.py \
  --bin "build/$preset/bin/semslam" "$@"
