#!/usr/bin/env bash
# The installed semslam (cmake --install into a fresh prefix): --version, a tiny synthetic city mapped with the
# installed vocabulary, and the installed Python package (semslam and semslam.city). Arguments: BUILD_DIR WORK_DIR
# [PYTHON].
set -euo pipefail
build="$1"
work="$2"
python="${3:-}"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
bin="$prefix/bin/semslam"
for f in "$bin" "$prefix/share/semslam/vocabulary/semslam.voc" "$prefix/share/semslam/models/enet-cityscapes.yaml" \
         "$prefix/share/semslam/config/default.yaml" "$prefix/share/doc/semslam/LICENSE"; do
  [ -e "$f" ] || { echo "not installed: $f"; exit 1; }
done
"$bin" --version | grep -q "^semslam [0-9.]* (commit " || { echo "--version without a commit"; exit 1; }
"$bin" synth --out "$work/city" --frames 12 --seed 1 -q
"$bin" run --sequence "$work/city/sequences/00" --out "$work/run" --mode stereo --pacing synchronous -q
[ "$(grep -c . "$work/run/trajectory.kitti")" = 12 ] || { echo "trajectory.kitti: not 12 lines"; exit 1; }
# The installed binary read the installed vocabulary.
grep -q "vocabulary $prefix/share/semslam/vocabulary/semslam.voc loaded" "$work/run/run.log" ||
  { echo "the installed binary did not use the installed vocabulary:"; grep vocabulary "$work/run/run.log"; exit 1; }
if [ -n "$python" ]; then
  # The package: semslam/__init__.py, the extension semslam/_semslam*.so and semslam.city beside them.
  init=$(find "$prefix" -path '*/semslam/__init__.py' | head -1)
  [ -n "$init" ] || { echo "the Python package was not installed"; exit 1; }
  package=$(dirname "$init")
  for f in city.py city_plan.py city_tasks.py; do
    [ -f "$package/$f" ] || { echo "not installed: $package/$f"; exit 1; }
  done
  ls "$package"/_semslam*.so >/dev/null || { echo "the extension was not installed in $package"; exit 1; }
  PYTHONPATH="$(dirname "$package")" "$python" -c "
import semslam
m = semslam.load_map('$work/run/map.semslam')
assert m.points.ndim == 2 and m.points.shape[1] == 3 and m.points.shape[0] > 100, m.points.shape
assert m.keyframe_poses.shape[1:] == (4, 4)
print('installed module', semslam.__version__, m)
"
  PYTHONPATH="$(dirname "$package")" "$python" -m semslam.city --help | grep -q -- "--scheduler" ||
    { echo "python3 -m semslam.city --help failed"; exit 1; }
fi
echo "installed semslam: ok"
