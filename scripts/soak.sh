#!/usr/bin/env bash
# Soak test: a long synthetic drive (loops, GPS every frame, landmarks, noisy truth labels) through `semslam run` at
# the default (realtime) pacing, then resident memory against frames from the run's tracking.csv (rss_mib per
# frame): a table per 1000 frames with the share of new ground, and an SVG plot.
# Usage: scripts/soak.sh [FRAMES (10000)] [DIR (out/soak)] [SVG (DIR/soak_rss.svg)]
# DIR and SVG given are taken relative to where the script is started (the default DIR is in the checkout); the
# binary is $SEMSLAM_BIN, default build/release/bin/semslam (built when missing).
# Long: rendering 10,000 frames takes about 10 minutes of both cores and SLAM 17 minutes (the camera's time); the
# dataset (5.4 GB) is kept in DIR/city for the next time.
set -euo pipefail
usage="usage: scripts/soak.sh [FRAMES (10000)] [DIR (out/soak)] [SVG (DIR/soak_rss.svg)]"
if [ $# -gt 3 ] || [[ ${1:-} == -* ]]; then
  echo "$usage" >&2
  exit 2
fi
frames="${1:-10000}"
if ! [[ $frames =~ ^[1-9][0-9]*$ ]]; then
  echo "soak: FRAMES must be a whole number above 0, not '$frames'" >&2
  echo "$usage" >&2
  exit 2
fi
dir="$(realpath -m -- "${2:-$(dirname "$0")/../out/soak}")"
svg="$(realpath -m -- "${3:-$dir/soak_rss.svg}")"
bin="${SEMSLAM_BIN:+$(realpath -m -- "$SEMSLAM_BIN")}"
cd "$(dirname "$0")/.."
if [ -z "$bin" ]; then
  bin="$PWD/build/release/bin/semslam"
  [ -x "$bin" ] || SEMSLAM_BUILD_PRESET=release ./scripts/build.sh
elif [ ! -x "$bin" ] || [ -d "$bin" ]; then
  echo "soak: SEMSLAM_BIN=$SEMSLAM_BIN is not an executable semslam binary" >&2
  exit 2
fi
times="$dir/city/sequences/00/times.txt"  # written last by synth: a render cut short has none
if [ ! -f "$times" ] || [ "$(wc -l <"$times")" -ne "$frames" ]; then
  rm -rf "$dir/city"
  start=$(date +%s)
  "$bin" synth --out "$dir/city" --frames "$frames" --seed 1 -q
  echo "soak: rendered $frames frames in $(( $(date +%s) - start )) s"
fi
start=$(date +%s)
"$bin" run --sequence "$dir/city" --out "$dir/run" --mode mono --gps "$dir/city/oxts" \
  --landmarks "$dir/city/landmarks.csv" --segmenter truth-noisy:0.25 --overwrite -q
echo "soak: SLAM over $frames frames in $(( $(date +%s) - start )) s"
/usr/bin/python3 scripts/soak_report.py "$dir/run/tracking.csv" --run-json "$dir/run/run.json" \
  --truth "$dir/city/poses/00.txt" --svg "$svg"
