#!/usr/bin/env bash
# Reproduces semslam's default bag-of-words vocabulary, data/vocabulary/semslam.voc, with our own tools only:
# renders the synthetic city (`semslam synth`) and trains on its left images (`semslam vocab train`), then
# measures place recognition on a second, differently seeded town with its loops (`semslam vocab eval`).
#
#   scripts/make-vocabulary.sh [--build DIR] [--source synth|procedural] [--frames N] [--k K] [--levels L]
#
# --source procedural trains on procedurally drawn images instead (no renderer needed).
# The result is deterministic for a given build of semslam.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build/release
source=synth
frames=600
k=13
levels=4
features=2000
seed=1
eval_seed=7
usage="usage: scripts/make-vocabulary.sh [--build DIR] [--source synth|procedural] [--frames N] [--k K] [--levels L]"
while [[ $# -gt 0 ]]; do
  case $1 in
    -h|--help) echo "$usage"; exit 0 ;;
    --build|--source|--frames|--k|--levels)
      [[ $# -ge 2 ]] || { echo "make-vocabulary.sh: $1 needs a value" >&2; echo "$usage" >&2; exit 2; } ;;&
    --build) build=$2; shift 2 ;;
    --source) source=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --k) k=$2; shift 2 ;;
    --levels) levels=$2; shift 2 ;;
    *) echo "make-vocabulary.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
bin=$build/bin/semslam
[[ -x $bin ]] || { echo "make-vocabulary.sh: $bin not built (cmake --build --preset release)" >&2; exit 1; }
out=$root/data/vocabulary/semslam.voc
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# semslam stops on Ctrl-C and exits 130; say so here too (the vocabulary is written atomically: an interrupted
# training leaves the previous one).
trap 'echo "make-vocabulary.sh: interrupted" >&2; exit 130' INT

case $source in
  synth)
    echo "== rendering $frames frames of the synthetic city (seed $seed)"
    "$bin" synth --out "$work/train" --frames "$frames" --seed "$seed"
    echo "== training k=$k L=$levels"
    "$bin" vocab train --images "$work/train/sequences/00/image_0" --out "$out" --k "$k" --levels "$levels" \
      --features "$features" --seed 1
    ;;
  procedural)
    echo "== training k=$k L=$levels on $frames procedural images"
    "$bin" vocab train --procedural "$frames" --out "$out" --k "$k" --levels "$levels" --features "$features" --seed 1
    ;;
  *) echo "make-vocabulary.sh: --source must be synth or procedural" >&2; exit 2 ;;
esac
"$bin" vocab info "$out"

if ! "$bin" synth --help >/dev/null 2>&1; then
  echo "== (no synthetic city renderer: retrieval not evaluated)"
  exit 0
fi
# A render that fails (or is interrupted) is an error with its reason, not "no renderer".
echo "== place recognition on an unseen town (seed $eval_seed, 1500 frames, loops)"
"$bin" synth --out "$work/eval" --frames 1500 --seed "$eval_seed" -q
"$bin" vocab eval --vocabulary "$out" --sequence "$work/eval/sequences/00"
