#!/usr/bin/env bash
# The reproductions of issue 11's defects, as a user would meet them, each with what must happen now:
#   SIGINT after 6 s            -> exit 130, the trajectory of the frames done, run.json "interrupted", a map
#                                  that `semslam localize` loads
#   a second signal             -> quits at once; the next run removes the temporary files it left
#   a reused --out              -> refused without --overwrite; with it, nothing of the earlier run is left,
#                                  but never when it holds the run's own --map-in
#   two runs into one --out     -> the second is refused
#   an unwritable --out         -> refused before the first frame, with the system's reason
#   a Latin-1 landmark name     -> refused up front (one line naming file:line)
#   a Latin-1 sequence path     -> refused up front
#   a 100000 s timestamp gap    -> realtime pacing does not stall (and nanosecond timestamps neither)
#   a zero-byte frame           -> skipped with one warning; the run finishes with its work saved
# Usage: scripts/check-robustness.sh [SEMSLAM_BINARY]   (default build/release/bin/semslam, built if missing)
set -uo pipefail
usage="usage: scripts/check-robustness.sh [SEMSLAM_BINARY]   (default build/release/bin/semslam, built if missing)"
if [ $# -gt 1 ] || [[ ${1:-} == -* ]]; then
  echo "$usage" >&2
  exit 2
fi
if [ $# -eq 1 ]; then
  # A binary given is taken relative to where the script was started, and never built: a mistyped path is an
  # error, not a build of the release preset.
  bin="$(realpath -m -- "$1")"
  if [ ! -x "$bin" ] || [ -d "$bin" ]; then
    echo "check-robustness: $1 is not an executable semslam binary" >&2
    exit 2
  fi
fi
cd "$(dirname "$0")/.." || exit 1
if [ $# -eq 0 ]; then
  bin="$PWD/build/release/bin/semslam"
  if [ ! -x "$bin" ]; then
    SEMSLAM_BUILD_PRESET=release ./scripts/build.sh >/dev/null || exit 1
  fi
fi
passed=0 failed=0
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# Ctrl-C or a SIGTERM: the run in the background (if any) is stopped before its folder is removed, none is left
# running after the script.
pid=
on_signal() {
  trap '' INT TERM
  if [ -n "$pid" ]; then
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  fi
  echo "check-robustness: interrupted ($passed passed, $failed failed so far)" >&2
  exit "$1"
}
trap 'on_signal 130' INT
trap 'on_signal 143' TERM
py=/usr/bin/python3
check() {  # check NAME CONDITION-EXIT-STATUS
  if [ "$2" -eq 0 ]; then
    echo "PASS $1"
    passed=$((passed + 1))
  else
    echo "FAIL $1"
    failed=$((failed + 1))
  fi
}
json() { $py -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$1" "$2"; }
poses() { grep -vc '^#' "$1" 2>/dev/null || echo 0; }

echo "rendering a 200-frame synthetic drive..."
"$bin" synth --out "$work/city" --frames 200 --seed 1 >/dev/null 2>&1 || { echo "synth failed"; exit 1; }
seq="$work/city/sequences/00"

# 1. SIGINT after 6 s of a realtime run (200 frames at 10 Hz take 20 s).
"$bin" run --sequence "$seq" --out "$work/int" --pacing realtime >"$work/int.out" 2>"$work/int.err" &
pid=$!
sleep 6
kill -INT "$pid"
wait "$pid"
status=$?
pid=
frames="$(json "$work/int/run.json" 'd["frames"]' 2>/dev/null || echo 0)"
lines="$(poses "$work/int/trajectory.tum")"
echo "  SIGINT: exit $status, run.json status $(json "$work/int/run.json" 'd["status"]' 2>/dev/null), $frames of 200 frames, $lines poses"
[ "$status" -eq 130 ] && [ "$(json "$work/int/run.json" 'd["status"]')" = interrupted ] && [ "$lines" -gt 0 ] &&
  [ "$frames" -lt 200 ]
check "SIGINT after 6 s saves the trajectory of the frames done and run.json marked interrupted" $?
"$bin" localize --map "$work/int/map.semslam" --sequence "$seq" --out "$work/int-localize" --frames 0:20 -q \
  >"$work/loc.out" 2>&1
check "the interrupted run's map loads in semslam localize ($(tail -1 "$work/loc.out"))" $?

# 2. A second signal quits at once; the next run into the folder removes what it left.
"$bin" run --sequence "$seq" --out "$work/twice" --pacing realtime -q >/dev/null 2>"$work/twice.err" &
pid=$!
sleep 4
kill -TERM "$pid"
for _ in $(seq 100); do grep -q "stopping after" "$work/twice.err" && break; sleep 0.05; done
kill -TERM "$pid"
wait "$pid"
status=$?
pid=
grep -q "quitting at once" "$work/twice.err"
check "a second signal quits at once (exit $status)" $?
echo partial >"$work/twice/.run.json.tmp999999999.0"
"$bin" run --sequence "$seq" --out "$work/twice" --frames 0:10 --pacing fast --overwrite -q >/dev/null 2>&1 &&
  [ -z "$(find "$work/twice" -name '*.tmp[0-9]*')" ]
check "the next run leaves no temporary file of the killed one" $?

# 3. A reused --out.
"$bin" run --sequence "$seq" --out "$work/reuse" --frames 0:30 --pacing fast -q --gps "$work/city/oxts" \
  --landmarks "$work/city/landmarks.csv" >/dev/null 2>&1
echo "a file of the earlier run" >"$work/reuse/plots-of-the-earlier-run.txt"
before="$(ls "$work/reuse" | wc -l)"
"$bin" run --sequence "$seq" --out "$work/reuse" --frames 0:20 --pacing fast -q >/dev/null 2>"$work/reuse.err"
status=$?
[ "$status" -ne 0 ] && grep -q -- "--overwrite" "$work/reuse.err" && [ "$(json "$work/reuse/run.json" 'd["frames"]')" = 30 ]
check "a reused --out is refused without --overwrite ($(cat "$work/reuse.err"))" $?
"$bin" run --sequence "$seq" --out "$work/reuse" --frames 0:20 --pacing fast -q --overwrite >/dev/null 2>&1
[ ! -e "$work/reuse/plots-of-the-earlier-run.txt" ] && [ "$(json "$work/reuse/run.json" 'd["frames"]')" = 20 ]
check "with --overwrite it holds nothing of the earlier run ($before entries before, $(ls "$work/reuse" | wc -l) after)" $?
"$bin" run --sequence "$seq" --out "$work/reuse" --map-in "$work/reuse/map.semslam" --frames 0:10 --pacing fast -q \
  --overwrite >/dev/null 2>"$work/reuse_map.err"
status=$?
[ "$status" -ne 0 ] && grep -q "which this run reads" "$work/reuse_map.err" && [ -s "$work/reuse/map.semslam" ]
check "an --out holding the run's --map-in is never emptied ($(cat "$work/reuse_map.err"))" $?

# 4. Two runs into one --out at once.
"$bin" run --sequence "$seq" --out "$work/two" --pacing realtime -q >/dev/null 2>&1 &
pid=$!
sleep 2
"$bin" run --sequence "$seq" --out "$work/two" --frames 0:10 -q >/dev/null 2>"$work/two.err"
status=$?
kill -KILL "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
pid=
[ "$status" -ne 0 ] && grep -q "another semslam command" "$work/two.err"
check "a second run into the same --out is refused ($(cat "$work/two.err"))" $?

# 5. An unwritable --out, before the first frame.
touch "$work/file"
"$bin" run --sequence "$seq" --out "$work/file/out" -q >/dev/null 2>"$work/unwritable.err"
[ $? -ne 0 ] && grep -q "Not a directory" "$work/unwritable.err"
check "an unusable --out is refused up front ($(cat "$work/unwritable.err"))" $?

# 6. Text that is not UTF-8.
{ head -2 "$work/city/landmarks.csv"; printf 'Caf\xe9 M\xfcller,%s\n' "$(sed -n 3p "$work/city/landmarks.csv" | cut -d, -f2-)"; } \
  >"$work/latin1.csv"
"$bin" run --sequence "$seq" --out "$work/latin1" --gps "$work/city/oxts" --landmarks "$work/latin1.csv" -q \
  >/dev/null 2>"$work/latin1.err"
[ $? -ne 0 ] && grep -q "latin1.csv:3" "$work/latin1.err" && [ "$(wc -l <"$work/latin1.err")" -eq 1 ] &&
  [ ! -e "$work/latin1" ]
check "a Latin-1 landmark name is refused up front ($(cut -c1-160 "$work/latin1.err"))" $?
latin1_dir="$work/$(printf 's\xe9q')"
cp -r "$seq" "$latin1_dir"
"$bin" run --sequence "$latin1_dir" --out "$work/latin1-path" -q >/dev/null 2>"$work/latin1-path.err"
[ $? -ne 0 ] && grep -q "not UTF-8" "$work/latin1-path.err"
check "a Latin-1 sequence path is refused up front" $?

# 7. Timestamp gaps under realtime pacing (a stall would hit the 120 s timeout).
gap="$work/gap"
mkdir -p "$gap"
cp -r "$seq/image_0" "$seq/calib.txt" "$gap/"
awk 'NR <= 20 { printf "%.6f\n", $1 } NR > 20 && NR <= 40 { printf "%.6f\n", $1 + 100000 }' "$seq/times.txt" >"$gap/times.txt"
find "$gap/image_0" -name '*.png' | sort | tail -n +41 | xargs rm -f
start=$(date +%s)
timeout 120 "$bin" run --sequence "$gap" --out "$work/gap-out" --pacing realtime -q >"$work/gap.log" 2>&1
status=$?
[ "$status" -eq 0 ] && [ "$(grep -c 're-anchored' "$work/gap.log")" -eq 1 ]
check "a 100000 s timestamp gap does not stall realtime pacing (40 frames in $(( $(date +%s) - start )) s, one warning)" $?
awk 'NR <= 40 { printf "%.0f\n", 1.3e18 + $1 * 1e9 }' "$seq/times.txt" >"$gap/times.txt"
start=$(date +%s)
timeout 120 "$bin" run --sequence "$gap" --out "$work/ns-out" --pacing realtime -q >"$work/ns.log" 2>&1
check "nanosecond timestamps do not stall realtime pacing (40 frames in $(( $(date +%s) - start )) s)" $?

# 8. A zero-byte frame mid-sequence.
bad="$work/bad"
mkdir -p "$bad"
cp -r "$seq/image_0" "$seq/calib.txt" "$seq/times.txt" "$bad/"
: >"$bad/image_0/000010.png"
# Not -q: that keeps warnings off the terminal (only errors), and the warning is what is checked.
"$bin" run --sequence "$bad" --out "$work/bad-out" --frames 0:40 --pacing fast >/dev/null 2>"$work/bad.log"
status=$?
[ "$status" -eq 0 ] && [ "$(grep -c '000010.png' "$work/bad.log")" -eq 1 ] &&
  [ "$(json "$work/bad-out/run.json" 'd["bad_frames"]["count"]')" = 1 ] && [ -s "$work/bad-out/map.semslam" ] &&
  [ "$(poses "$work/bad-out/trajectory.tum")" -gt 0 ]
check "a zero-byte frame is skipped with one warning and the run finishes with its work saved" $?

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
