#!/usr/bin/env python3
"""semslam's benchmark: every case once at synchronous pacing and N times at the default realtime pacing, quiet
and with one core kept busy; results.json and a Markdown table, compared with bench/baseline.json.

  scripts/benchmark.sh [--quick] [--runs N] [--out DIR] [--cases REGEX] [--long-drive DIR] [--first-output]
  scripts/benchmark.py --markdown RESULTS.json... --write-docs [--update-baseline]

The cases are in scripts/bench_cases.py (running semslam and making their inputs in scripts/bench_inputs.py), the
figures' comparison and the Markdown in scripts/bench_report.py.
Runs go one at a time. Rendered synthetic towns and composed sequences are cached (--cache, default
~/.cache/semslam-bench) under a key of the renderer's and composer's sources, so a benchmark re-renders only what
changed. results.json is written atomically at the end (results.partial.json after each case); Ctrl-C stops the
run in progress and leaves no half-written file.
"""

import argparse
import datetime
import hashlib
import json
import os
import platform
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import bench_cases  # noqa: E402
import bench_inputs  # noqa: E402
import bench_report  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCHEMA = "semslam-benchmark"
SCHEMA_VERSION = 1


def write_atomically(path, text):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=os.path.dirname(os.path.abspath(path)))
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def git(*args):
    return subprocess.run(["git", "-C", REPO] + list(args), capture_output=True, text=True).stdout.strip()


def commit_info():
    sha = git("rev-parse", "HEAD")
    dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
    return {"sha": sha, "short": sha[:10], "dirty": dirty, "branch": git("rev-parse", "--abbrev-ref", "HEAD")}


def machine_info():
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    memory = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    memory = round(int(line.split()[1]) / 1024 / 1024, 1)
    except OSError:
        pass
    return {"nproc": os.cpu_count(), "cpu": cpu, "memory_gib": memory, "system": platform.platform()}


def source_key(paths):
    """A key of the sources that make the cached inputs (renderer, composer, readers): their tree at HEAD and any
    uncommitted change to them."""
    h = hashlib.sha1()
    for p in paths:
        h.update(git("rev-parse", "HEAD:" + p).encode())
    h.update(git("diff", "HEAD", "--", *paths).encode())
    return h.hexdigest()[:12]


def minutes(seconds):
    seconds = max(0, int(seconds))
    return "%dm%02ds" % divmod(seconds, 60) if seconds < 3600 else "%dh%02dm" % (seconds // 3600, seconds % 3600 // 60)


class Interrupted(Exception):
    pass


def tool_python():
    """The interpreter for tools/*.py, which need NumPy: this one if it has it, else Debian's python3 (where
    scripts/install-deps.sh installs python3-numpy; a python3 first on PATH, e.g. pyenv's, may lack it)."""
    for candidate in (sys.executable, "/usr/bin/python3"):
        if candidate and subprocess.run([candidate, "-c", "import numpy"], capture_output=True).returncode == 0:
            return candidate
    raise SystemExit("benchmark: no python3 with NumPy to run tools/*.py (scripts/install-deps.sh installs "
                     "python3-numpy for /usr/bin/python3)")


class Context:
    """What a case needs from the benchmark: the binary, data folders, the cache, running a command."""

    def __init__(self, args):
        self.bin = os.path.abspath(args.bin)
        self.repo = REPO
        self.python = tool_python()
        self.shared = os.path.abspath(args.shared)
        self.long_dir = args.long_drive
        self.long_kml = args.long_drive_gps
        self.long_osm = args.long_drive_osm
        self.out = os.path.abspath(args.out)
        self.cache = os.path.abspath(args.cache)
        self.quick = args.quick
        self.child = None
        self.cache_key = source_key(["src/semslam/sim", "src/semslam/io", "apps/semslam/cmd_synth.cc",
                                     "apps/semslam/cmd_compose.cc"])
        self.current_case = None
        self.display_names = []  # (folder, name) pairs display() shortens, e.g. the long drive's maps folder
        self.kitti00_lever_arm = bench_inputs.KITTI00_LEVER_ARM

    @staticmethod
    def clock():
        return time.monotonic()

    def timeout(self, case):
        return max(900, 6 * case.est_seconds)

    def call(self, command, out, timeout=None, env=None, cwd=None):
        """Runs one command, its output into the file `out`; on timeout or Ctrl-C it is asked to stop (SIGINT:
        semslam saves what it did), then killed."""
        self.child = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, cwd=cwd or self.repo,
                                      env=env, start_new_session=True)
        try:
            return self.child.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._stop_child()
            return "timeout after %d s" % timeout
        except BaseException:
            self._stop_child()
            raise
        finally:
            self.child = None

    def _stop_child(self):
        child = self.child
        if child is None or child.poll() is not None:
            return
        try:
            os.killpg(child.pid, signal.SIGINT)
            child.wait(timeout=30)
        except (subprocess.TimeoutExpired, ProcessLookupError):
            try:
                os.killpg(child.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            child.wait()

    def display(self, command, run_dir):
        """The command as the docs show it: the binary as `semslam`, folders by short names."""
        text = " ".join(shlex.quote(str(c)) for c in command[1:])
        text = text.replace(run_dir, "OUT")
        for path, name in ((self.cache, "$CACHE"), (self.shared, "../shared/data"), (self.repo + "/", "")):
            text = text.replace(path, name)
        if self.long_dir:
            text = text.replace(os.path.abspath(self.long_dir), "$SEMSLAM_LONG_DRIVE")
        for path, name in self.display_names:
            text = text.replace(path, name)
        return "semslam " + text

    def cached(self, key, make, source_dep=None):
        """CACHE/key-SOURCEKEY, made by make(tmp_folder) when it is not there yet (renamed into place when done)."""
        path = os.path.join(self.cache, "%s-%s" % (key, self.cache_key))
        if os.path.exists(os.path.join(path, ".bench-complete")):
            return path
        os.makedirs(self.cache, exist_ok=True)
        tmp = path + ".tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        print("  preparing %s ..." % os.path.basename(path), flush=True)
        start = time.monotonic()
        make(tmp)
        with open(os.path.join(tmp, ".bench-complete"), "w") as f:
            f.write("%s\n" % datetime.datetime.now(datetime.timezone.utc).isoformat())
        shutil.rmtree(path, ignore_errors=True)
        os.rename(tmp, path)
        print("  prepared %s in %.0f s" % (os.path.basename(path), time.monotonic() - start), flush=True)
        return path

    def first_output(self, run_dir, dry_run):
        """Clones HEAD, runs scripts/demo.sh there with an empty compiler cache and times it until report.html."""
        shutil.rmtree(run_dir, ignore_errors=True)
        os.makedirs(run_dir)
        clone = os.path.join(run_dir, "semslam")
        demo_out = os.path.join(run_dir, "demo")
        log_path = run_dir + ".log"
        env = dict(os.environ)
        for key in ("CCACHE_DISABLE", "CCACHE_BASEDIR", "SEMSLAM_BUILD_PRESET"):
            env.pop(key, None)
        if dry_run:
            env["CCACHE_DIR"] = os.path.join(os.path.expanduser("~"), ".cache", "ccache")
            env["CCACHE_BASEDIR"] = clone
            extra = ["--frames", "100", "--second-drive", "50"]
        else:
            env["CCACHE_DIR"] = os.path.join(run_dir, "ccache")  # empty: a new user's machine
            extra = []
        sha = git("rev-parse", "HEAD")
        with open(log_path, "w") as log:
            start = time.monotonic()
            for command in (["git", "clone", "--quiet", "--no-checkout", REPO, clone],
                            ["git", "-C", clone, "checkout", "--quiet", sha]):
                log.write("$ %s\n" % " ".join(command))
                log.flush()
                if self.call(command, log, timeout=600) != 0:
                    raise bench_inputs.RunFailed("%s failed" % " ".join(command[:3]))
            cloned = time.monotonic()
            command = [os.path.join(clone, "scripts", "demo.sh"), demo_out] + extra
            log.write("$ CCACHE_DIR=%s %s\n" % (env["CCACHE_DIR"], " ".join(command)))
            log.flush()
            report = os.path.join(demo_out, "run", "report.html")
            self.child = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=clone, env=env,
                                          start_new_session=True)
            report_at = None
            try:
                while self.child.poll() is None:
                    if report_at is None and os.path.exists(report):
                        report_at = time.monotonic()
                    if time.monotonic() - start > 7200:
                        self._stop_child()
                        raise bench_inputs.RunFailed("timeout after 2 h")
                    time.sleep(0.5)
            except BaseException:
                self._stop_child()
                raise
            finally:
                code = self.child.returncode if self.child else None
                self.child = None
        if report_at is None and os.path.exists(report):
            report_at = time.monotonic()
        if code != 0 or report_at is None:
            raise bench_inputs.RunFailed("scripts/demo.sh exit %s, report.html %s (log %s)" % (
                code, "written" if report_at else "missing", log_path))
        with open(log_path, errors="replace") as f:
            m = re.search(r"build \(semslam binary, [a-z]+\): (\d+) s", f.read())
        if not m:
            raise bench_inputs.RunFailed("no build time in the output of scripts/demo.sh (%s)" % log_path)
        build = float(m.group(1))
        figures = {"total_s": report_at - start, "clone_s": cloned - start, "build_s": build,
                   "demo_s": report_at - cloned - build}
        # The clone, its build and the demo's outputs (about 1 GB) are not kept.
        shutil.rmtree(run_dir, ignore_errors=True)
        return figures


class BusyCore:
    """One core kept busy by a process pinned to none, from before a run to after it."""

    def __init__(self, enabled):
        self.enabled = enabled
        self.process = None

    def __enter__(self):
        if self.enabled:
            self.process = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        return self

    def __exit__(self, *exc):
        if self.process is not None:
            self.process.kill()
            self.process.wait()
        return False


def plan_runs(cases, runs, busy_runs):
    """[(case, variant, index, count)] in the order they run: synchronous, quiet, busy."""
    plan = []
    for case in cases:
        wanted = {"synchronous": 1, "quiet": runs, "busy": busy_runs}
        for variant, n in (case.variants or {}).items():
            wanted[variant] = wanted[variant] if n is None else n
        for variant in bench_report.VARIANTS:
            for i in range(wanted[variant]):
                plan.append((case, variant, i, wanted[variant]))
    return plan


def estimate(case, variant):
    return case.sync_seconds if variant == "synchronous" else case.est_seconds


def run_benchmark(args, cases, command_text):
    ctx = Context(args)
    os.makedirs(ctx.out, exist_ok=True)
    plan = plan_runs(cases, args.runs, args.busy_runs)
    planned = sum(estimate(c, v) for c, v, _, _ in plan)
    print("benchmark: %d cases, %d runs planned, about %s (binary %s, out %s)" % (
        len(cases), len(plan), minutes(planned), ctx.bin, ctx.out), flush=True)
    started = time.monotonic()
    results = {"schema": SCHEMA, "version": SCHEMA_VERSION, "command": command_text, "quick": args.quick,
               "runs": args.runs, "busy_runs": args.busy_runs, "commit": commit_info(), "machine": machine_info(),
               "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
               "binary_version": subprocess.run([ctx.bin, "--version"], capture_output=True,
                                                text=True).stdout.strip(),
               "cases": {}}
    done_estimate, done_runs = 0.0, 0
    for case in cases:
        runs = [(c, v, i, n) for c, v, i, n in plan if c is case]
        entry = {"group": case.group, "title": case.title, "status": "ok", "failures": []}
        case_start = time.monotonic()
        try:
            prepared = case.prepare(ctx)
        except bench_inputs.Skip as e:
            entry.update(status="skipped", reason=str(e))
            print("[%s] skipped: %s" % (case.name, e), flush=True)
            results["cases"][case.name] = entry
            done_estimate += sum(estimate(c, v) for c, v, _, _ in runs)
            done_runs += len(runs)
            continue
        except bench_inputs.RunFailed as e:
            entry.update(status="failed", reason="preparing: %s" % e)
            print("[%s] FAILED preparing: %s" % (case.name, e), flush=True)
            results["cases"][case.name] = entry
            done_estimate += sum(estimate(c, v) for c, v, _, _ in runs)
            done_runs += len(runs)
            continue
        measured = []
        for _, variant, i, n in runs:
            run_dir = os.path.join(ctx.out, "runs", case.name, "%s-%d" % (variant, i + 1))
            t0 = time.monotonic()
            try:
                with BusyCore(variant == "busy"):
                    figures = case.run(ctx, prepared, run_dir, variant)
                measured.append((variant, figures))
                outcome = "ok"
            except bench_inputs.RunFailed as e:
                entry["failures"].append("%s run %d: %s" % (variant, i + 1, e))
                outcome = "FAILED: %s" % e
            seconds = time.monotonic() - t0
            done_runs += 1
            done_estimate += estimate(case, variant)
            elapsed = time.monotonic() - started
            remaining = (planned - done_estimate) * (elapsed / done_estimate if done_estimate else 1.0)
            print("[%3d/%d] %-22s %-11s %d/%d %6.1f s  %s | elapsed %s, ETA %s" % (
                done_runs, len(plan), case.name, variant, i + 1, n, seconds, outcome, minutes(elapsed),
                minutes(remaining)), flush=True)
        entry["command"] = case.command
        entry["seconds"] = time.monotonic() - case_start
        entry["figures"] = bench_report.aggregate(case.figures, measured)
        if not measured:
            entry.update(status="failed", reason="; ".join(entry["failures"])[:500])
        results["cases"][case.name] = entry
        results["seconds"] = time.monotonic() - started
        write_atomically(os.path.join(ctx.out, "results.partial.json"), json.dumps(results, indent=1) + "\n")
    results["seconds"] = time.monotonic() - started
    return results


def publish(args, results, markdown, stream=sys.stdout):
    """--update-baseline: the results (without their comparison) as bench/baseline.json; --write-docs: the
    Markdown as docs/results.md."""
    if args.update_baseline:
        baseline = {k: v for k, v in results.items() if k != "comparison"}
        write_atomically(args.baseline, json.dumps(baseline, indent=1) + "\n")
        print("benchmark: baseline written to %s" % args.baseline, file=stream)
    if args.write_docs:
        write_atomically(os.path.join(REPO, "docs", "results.md"), markdown + "\n")
        print("benchmark: docs/results.md written", file=stream)


def compare_with_baseline(args, results):
    """results["comparison"] against the baseline file args.baseline (which exists); returns the baseline."""
    with open(args.baseline, encoding="utf-8") as f:
        baseline = json.load(f)
    results["comparison"] = {"baseline": os.path.relpath(args.baseline, REPO),
                             "baseline_commit": baseline.get("commit", {}).get("short", "?"),
                             "findings": bench_report.compare(baseline, results)}
    return baseline


def judge_by_todays_bars(results):
    """Each figure's label, unit and bars as the cases define them now, its measured values kept: a page made
    again from older results is judged by today's bars, as it is compared with today's baseline."""
    cases = bench_cases.all_cases(bool(results.get("quick")), first_output=True)
    specs = {case.name: case.figures for case in cases}
    for name, case in results.get("cases", {}).items():
        for figure, entry in case.get("figures", {}).items():
            spec = specs.get(name, {}).get(figure)
            if spec:
                entry.update(spec)


def finish(args, results):
    baseline = None
    if args.update_baseline:
        pass
    elif os.path.exists(args.baseline):
        baseline = compare_with_baseline(args, results)
    else:
        # Absence means "no baseline yet": nothing to compare with, and the table says so.
        results["comparison"] = {"baseline": os.path.relpath(args.baseline, REPO), "baseline_commit": None,
                                 "findings": []}
    text = json.dumps(results, indent=1) + "\n"
    write_atomically(os.path.join(args.out, "results.json"), text)
    partial = os.path.join(args.out, "results.partial.json")
    if os.path.exists(partial):
        os.unlink(partial)
    markdown = bench_report.markdown(results, read_known_limits(args.known_limits))
    write_atomically(os.path.join(args.out, "results.md"), markdown + "\n")
    publish(args, results, markdown)
    print()
    print(markdown)
    print()
    if baseline is not None:
        worse = bench_report.worse_findings(results["comparison"]["findings"])
        print("benchmark: against %s (%s): %s" % (args.baseline, results["comparison"]["baseline_commit"],
                                                  "nothing got worse" if not worse else
                                                  "%d figure(s) worse:" % len(worse)))
        for f in worse:
            print("  " + f["text"])
    elif not args.update_baseline:
        print("benchmark: no baseline yet (%s does not exist): nothing compared" % args.baseline)
    print("benchmark: %s and %s written; the whole benchmark took %s" % (
        os.path.join(args.out, "results.json"), os.path.join(args.out, "results.md"),
        bench_report.duration_text(results["seconds"])))


def merge_results(loaded):
    """One results dict from several [(path, results)] of the same binary: their cases together, their commands
    and run counts named. Raises SystemExit when the binaries or the case names clash."""
    first_path, merged = loaded[0]
    merged = dict(merged)
    merged["cases"] = dict(merged.get("cases", {}))
    for path, results in loaded[1:]:
        if results.get("binary_version") != merged.get("binary_version"):
            raise SystemExit("benchmark: %s ran %r, %s ran %r: results of two binaries are not one table" % (
                first_path, merged.get("binary_version"), path, results.get("binary_version")))
        for name, case in results.get("cases", {}).items():
            if name in merged["cases"]:
                raise SystemExit("benchmark: case %s is in both %s and %s" % (name, first_path, path))
            merged["cases"][name] = case
        merged["seconds"] = merged.get("seconds", 0) + results.get("seconds", 0)
        merged["quick"] = merged.get("quick") or results.get("quick")
        comparison = results.get("comparison")
        if comparison:
            mine = merged.get("comparison")
            if not mine:
                merged["comparison"] = dict(comparison)
            elif mine.get("baseline_commit") != comparison.get("baseline_commit"):
                raise SystemExit("benchmark: %s and %s were compared with different baselines (%s, %s)" % (
                    first_path, path, mine.get("baseline_commit"), comparison.get("baseline_commit")))
            else:
                merged["comparison"] = dict(mine, findings=mine.get("findings", []) + comparison.get("findings", []))
    if len(loaded) > 1:
        merged["merged_from"] = len(loaded)
        merged["command"] = " ; ".join(r.get("command", "?") for _, r in loaded)
        merged["seconds_by_command"] = [r.get("seconds", 0) for _, r in loaded]
        for key in ("runs", "busy_runs"):
            values = [str(r.get(key, "?")) for _, r in loaded]
            merged[key] = values[0] if len(set(values)) == 1 else " or ".join(values) + " (by command)"
    return merged


def read_known_limits(path):
    if path and os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            return f.read()
    return ""


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="fewer and shorter cases, no busy runs")
    p.add_argument("--runs", type=int, help="realtime runs per case, quiet (default 2; some cases "
                   "fix their own: --list shows them)")
    p.add_argument("--busy-runs", type=int, help="realtime runs per case with a core kept busy (default 1, "
                   "compared with the baseline within the quiet runs' range; --quick 0)")
    p.add_argument("--out", default=os.path.join(REPO, "out", "benchmark"), help="output folder")
    p.add_argument("--cases", help="only the cases whose name matches this regular expression")
    p.add_argument("--long-drive", default=os.environ.get("SEMSLAM_LONG_DRIVE"),
                   help="KITTI odometry dataset folder holding sequences/00 and poses/00.txt (or a "
                   "folder holding kitti00/dataset): the long-drive cases, KITTI 00 frames 0-1699; default "
                   "$SEMSLAM_LONG_DRIVE, else they are skipped")
    p.add_argument("--long-drive-gps", default=os.environ.get("SEMSLAM_LONG_DRIVE_GPS"),
                   help="KITTI 00's RTK track, RTK_GPS_kitti_00.kml (default $SEMSLAM_LONG_DRIVE_GPS, else found "
                   "in osm/maps beside the dataset folder, as /work/data/osm/maps beside /work/data/kitti00)")
    p.add_argument("--long-drive-osm", default=os.environ.get("SEMSLAM_LONG_DRIVE_OSM"),
                   help="KITTI 00's OpenStreetMap extract, kitti_00.osm (default $SEMSLAM_LONG_DRIVE_OSM, else "
                   "found as the RTK track)")
    p.add_argument("--first-output", action="store_true",
                   help="also time scripts/demo.sh in a fresh clone with an empty compiler cache (~12 min)")
    p.add_argument("--first-output-dry-run", action="store_true",
                   help="the first-output case with the warm compiler cache and a 100-frame demo (checks the steps)")
    p.add_argument("--bin", default=os.path.join(REPO, "build", "release", "bin", "semslam"))
    p.add_argument("--shared", default=os.environ.get("SEMSLAM_SHARED_DATA", os.path.join(REPO, "..", "shared",
                                                                                          "data")))
    p.add_argument("--cache", default=os.environ.get("SEMSLAM_BENCH_CACHE", os.path.join(
        os.path.expanduser("~"), ".cache", "semslam-bench")), help="rendered towns and composed sequences")
    p.add_argument("--baseline", default=os.path.join(REPO, "bench", "baseline.json"))
    p.add_argument("--update-baseline", action="store_true", help="write the results as the new baseline")
    p.add_argument("--write-docs", action="store_true", help="write docs/results.md from the results")
    p.add_argument("--known-limits", default=os.path.join(REPO, "docs", "known_limits.md"))
    p.add_argument("--markdown", metavar="RESULTS", nargs="+",
                   help="print docs/results.md made from RESULTS (several: runs of one binary, e.g. --quick and "
                   "the long drive's cases, their cases together, compared anew with --baseline) and exit; with "
                   "--write-docs and --update-baseline also write docs/results.md and the baseline from them")
    p.add_argument("--list", action="store_true", help="list the planned runs and exit")
    args = p.parse_args(argv)
    if args.runs is None:
        args.runs = 2
    if args.busy_runs is None:
        args.busy_runs = 0 if args.quick else 1
    if args.runs < 1 or args.busy_runs < 0:
        p.error("--runs must be at least 1 and --busy-runs at least 0")
    if args.cases is not None:
        try:
            re.compile(args.cases)
        except re.error as e:
            p.error("--cases %r is not a regular expression: %s" % (args.cases, e))
    return args


def load_results(path):
    """A results.json for --markdown; SystemExit naming the file when it cannot be read or is not one."""
    try:
        with open(path, encoding="utf-8") as f:
            results = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit("benchmark: cannot read %s: %s" % (path, e))
    if not isinstance(results, dict) or not isinstance(results.get("cases"), dict):
        raise SystemExit("benchmark: %s is not a benchmark's results.json (no \"cases\")" % path)
    return results


def main(argv):
    args = parse_args(argv)
    if args.markdown:
        loaded = [(path, load_results(path)) for path in args.markdown]
        merged = merge_results(loaded)
        judge_by_todays_bars(merged)
        if os.path.exists(args.baseline):
            # The page is judged against the committed baseline by today's rules, not as each run was.
            compare_with_baseline(args, merged)
        markdown = bench_report.markdown(merged, read_known_limits(args.known_limits))
        publish(args, merged, markdown, stream=sys.stderr)  # stdout is the Markdown
        print(markdown)
        return 0
    cases = bench_cases.all_cases(args.quick, args.first_output, args.first_output_dry_run)
    if args.cases:
        cases = [c for c in cases if re.search(args.cases, c.name)]
    if not cases:
        print("benchmark: no case matches %r" % args.cases, file=sys.stderr)
        return 2
    if args.list:
        plan = plan_runs(cases, args.runs, args.busy_runs)
        for case, variant, i, n in plan:
            print("%-22s %-11s %d/%d  ~%d s  %s" % (case.name, variant, i + 1, n, estimate(case, variant), case.title))
        print("%d cases, %d runs, about %s of runs (estimates on a 2-core machine; preparing towns and composed "
              "sequences the first time adds to it)" % (len(cases), len(plan),
                                                         minutes(sum(estimate(c, v) for c, v, _, _ in plan))))
        return 0
    if not os.path.isfile(args.bin) or not os.access(args.bin, os.X_OK):
        print("benchmark: no semslam binary at %s (scripts/benchmark.sh builds it)" % args.bin, file=sys.stderr)
        return 2
    command_text = os.environ.get("SEMSLAM_BENCH_COMMAND") or "scripts/benchmark.py " + " ".join(
        shlex.quote(a) for a in argv)

    def on_term(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)
    try:
        results = run_benchmark(args, cases, command_text)
    except KeyboardInterrupt:
        print("\nbenchmark: interrupted; no results.json written (the cases done so far are in "
              "results.partial.json)", file=sys.stderr)
        return 130
    finish(args, results)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
