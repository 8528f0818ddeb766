#!/usr/bin/env bash
# Soak test: a long synthetic drive (loops, GPS every frame, landmarks, noisy truth labels) through `semslam run` at
# the default (realtime) pacing, then resident memory against frames from the run's tracking.csv (rss_mib per
# frame): a table per 1000 frames with the share of new ground, and an SVG plot.
# Usage: scripts/soak.sh [FRAMES (10000)] [DIR (out/soak)] [SVG (DIR/soak_rss.svg)]
# Long: rendering 10,000 frames takes about 10 minutes of both cores and SLAM 17 minutes (the camera's time); the
# dataset (5.4 GB) is kept in DIR/city for the next time.
set -euo pipefail
cd "$(dirname "$0")/.."
frames="${1:-10000}"
dir="${2:-out/soak}"
svg="${3:-$dir/soak_rss.svg}"
bin=build/release/bin/semslam
[ -x "$bin" ] || ./scripts/build.sh
if [ ! -f "$dir/city/sequences/00/times.txt" ] || [ "$(wc -l <"$dir/city/sequences/00/times.txt")" -ne "$frames" ]; then
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
