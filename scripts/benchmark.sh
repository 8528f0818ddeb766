#!/usr/bin/env bash
# semslam's benchmark (scripts/benchmark.py): builds the semslam binary (release preset, as scripts/build.sh,
# only that target), then runs every benchmark case and writes OUT/results.json and OUT/results.md.
#   scripts/benchmark.sh [--quick] [--runs N] [--out DIR] [--cases REGEX] [--long-drive DIR] [--first-output]
#                        [--update-baseline] [--write-docs]      (--help: every option)
# Paths given (--out, --markdown, ...) are taken relative to the folder the script is started from.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
preset="${SEMSLAM_BUILD_PRESET:-release}"
for a in "$@"; do
  case "$a" in
    -h|--help|--list|--markdown|--markdown=*) exec /usr/bin/python3 "$root/scripts/benchmark.py" "$@" ;;
  esac
done
# The options checked before the build: a mistyped one costs no build.
/usr/bin/python3 "$root/scripts/benchmark.py" --list "$@" >/dev/null
(
  cd "$root"
  ./scripts/install-deps.sh
  export CCACHE_DIR="${CCACHE_DIR:-$HOME/.cache/ccache}"
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
  cmake --preset "$preset" >/dev/null
  start=$(date +%s)
  cmake --build --preset "$preset" --target semslam_cli -j "$(nproc)"
  echo "build (semslam binary, $preset): $(( $(date +%s) - start )) s"
)
command="scripts/benchmark.sh"
[ $# -eq 0 ] || command+="$(printf ' %q' "$@")"  # as typed, quoted where needed
SEMSLAM_BENCH_COMMAND="$command" exec /usr/bin/python3 "$root/scripts/benchmark.py" \
  --bin "$root/build/$preset/bin/semslam" "$@"
