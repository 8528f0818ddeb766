#!/usr/bin/env bash
# Runs every libFuzzer target of fuzz/ for a bounded time (FUZZ_SECONDS each, default 5) from its seed corpus
# in fuzz/corpus/NAME (copied: the repository's corpus is not changed), and prints the executions per target.
# The targets are built by the asan preset (or `cmake --build --preset fuzz`). Exits non-zero when a target
# finds an input that crashes a reader or escapes it with anything but semslam's own input errors; the input
# is printed (hex) and kept in $FUZZ_ARTIFACTS (default: a temporary folder, printed).
set -euo pipefail
if [ $# -gt 0 ]; then
  echo "usage: scripts/fuzz.sh   (no arguments; FUZZ_SECONDS, FUZZ_BUILD_DIR, FUZZ_ARTIFACTS set it up)" >&2
  exit 2
fi
seconds="${FUZZ_SECONDS:-5}"
# libFuzzer reads -max_total_time=0 (or a word) as "no limit": the run would never end.
if ! [[ $seconds =~ ^[0-9]+$ ]] || [ "$seconds" -eq 0 ]; then
  echo "fuzz: FUZZ_SECONDS must be a whole number of seconds above 0, not '$seconds'" >&2
  exit 2
fi
# Folders given relative to where the script was started from, not to the checkout it moves to.
build="$(realpath -m "${FUZZ_BUILD_DIR:-$(dirname "$0")/../build/asan/fuzz}")"
artifacts="${FUZZ_ARTIFACTS:+$(realpath -m "$FUZZ_ARTIFACTS")}"
cd "$(dirname "$0")/.."
work="$(mktemp -d)"
artifacts="${artifacts:-$work/artifacts}"
mkdir -p "$artifacts"
trap 'rm -rf "$work/corpus"' EXIT
# Ctrl-C reaches the running target too, which then exits as if it had failed: without this the script would
# report it FAILED and go on with the next target. A signal sent to the script alone stops the target as well.
child=
on_signal() {
  trap '' INT TERM
  if [ -n "$child" ]; then
    kill -TERM "$child" 2>/dev/null || true
    wait "$child" 2>/dev/null || true
  fi
  echo "fuzz: interrupted" >&2
  exit "$1"
}
trap 'on_signal 130' INT
trap 'on_signal 143' TERM
failed=0 total=0
for corpus in fuzz/corpus/*/; do
  name="$(basename "$corpus")"
  target="$build/fuzz_$name"
  if [ ! -x "$target" ]; then
    echo "fuzz: $target is not built (cmake --build --preset fuzz)" >&2
    exit 1
  fi
  mkdir -p "$work/corpus/$name"
  cp "$corpus"* "$work/corpus/$name/"
  log="$work/$name.log"
  # In the background, so that a signal is handled at once (wait returns), not after the target's time.
  "$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/$name-" "$work/corpus/$name" >"$log" 2>&1 &
  child=$!
  status=0
  wait "$child" || status=$?
  child=
  if [ "$status" -eq 0 ]; then
    runs="$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo '?')"
    corpus_size="$(ls "$work/corpus/$name" | wc -l)"
    echo "fuzz_$name: $runs executions in $seconds s, corpus $(ls "$corpus" | wc -l) -> $corpus_size inputs, no failure"
    total=$((total + ${runs//\?/0}))
  else
    failed=1
    echo "fuzz_$name: FAILED" >&2
    grep -vE '^(#[0-9]+|INFO:)' "$log" | tail -60 >&2
    for input in "$artifacts/$name-"*; do
      [ -f "$input" ] || continue
      echo "input $input:" >&2
      od -A d -c "$input" | head -16 >&2
    done
  fi
done
echo "fuzz: $total executions in all; artifacts in $artifacts"
exit "$failed"
