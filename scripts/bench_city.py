"""Benchmark cases of many drives merged into one map (`semslam merge`): each case runs its drives one after
another at the case's pacing, merges their run folders, and reports the merged map against each drive's own run.
The engine case maps a city on Dask workers (`python3 -m semslam.city`); the memory case merges 1, 2, 4 and 8
drives."""

import filecmp
import os
import re
import resource
import shutil
import signal
import subprocess
import threading
import time

from bench_cases import Case, bar, spec
from bench_inputs import RunFailed, Skip, composed, drive0005, kitti07, read_json, run_slam, semslam

CITY_SEED = 7331  # a town no test uses


def route(ctx, seed, route_seed, frames):
    """A drive of town `seed` on route `route_seed` (`semslam synth --route-seed`, cached)."""
    return ctx.cached("route-%d-%d-%d" % (seed, route_seed, frames), lambda out: semslam(
        ctx, ["synth", "--out", out, "--frames", frames, "--seed", seed, "--route-seed", route_seed, "-q"],
        out + ".log"))


def merge_figures(merged_dir, drive_dirs):
    """The merged map against the drives' own runs."""
    run = read_json(os.path.join(merged_dir, "run.json"))
    maps = run["maps"]
    sessions = maps["sessions"]
    figures = {"sessions": len(sessions), "maps": maps["count"], "place_merges": maps["place_merges"],
               "gps_joins": len(maps["gps_joins"]), "merge_s": run.get("seconds"),
               "merge_rss_mib": run.get("peak_rss_mib"), "ate_city_m": run.get("ate_rmse_city")}
    frames = sum(s["frames"] for s in sessions)
    in_main = sum(s["frames_in_main_map"] for s in sessions)
    figures["frames_in_main_map_pct"] = 100.0 * in_main / frames if frames else None
    ratios, shape_ratios, own_ates, world = [], [], [], []
    for s, drive in zip(sessions, drive_dirs):
        own = read_json(os.path.join(drive, "run.json")).get("ate_rmse")
        if own and s.get("ate_rmse_city") is not None:
            ratios.append(s["ate_rmse_city"] / own)
            own_ates.append(own)
        # The drive aligned on its own in the merged map: what the merge did to its shape, apart from where
        # the city's one alignment puts it.
        if own and s.get("ate_rmse") is not None:
            shape_ratios.append(s["ate_rmse"] / own)
        if s.get("world_rmse_m") is not None:
            world.append(s["world_rmse_m"])
    figures["ate_ratio_max"] = max(ratios) if ratios else None
    figures["shape_ratio_max"] = max(shape_ratios) if shape_ratios else None
    figures["own_ate_max_m"] = max(own_ates) if own_ates else None
    figures["world_rmse_max_m"] = max(world) if world else None
    geo = run.get("geo") or {}
    figures["landmarks_placed"] = geo.get("landmarks")
    figures["landmark_error_median_m"] = (run.get("landmark_evaluation") or {}).get("landmark_error_median_m")
    figures["topology_nodes"] = geo.get("topology_nodes")
    figures["topology_revisited_nodes"] = geo.get("topology_revisited_nodes")
    return figures


def merge_case(name, group, title, drives, extra, figures, est_seconds, variants=None, sync_seconds=None):
    """drives(ctx) -> [(sequence, [run arguments])]: each run at the case's pacing, then `semslam merge`."""
    def prepare(ctx):
        return {"drives": drives(ctx)}

    def run(ctx, prepared, run_dir, pacing):
        drive_dirs = []
        for k, (sequence, args) in enumerate(prepared["drives"]):
            drive_dir = os.path.join(run_dir, "drive%d" % (k + 1))
            run_slam(ctx, case, sequence, drive_dir, pacing, args + extra)
            drive_dirs.append(drive_dir)
        merged = os.path.join(run_dir, "merged")
        command = semslam(ctx, ["merge", "--maps"] + drive_dirs + ["--out", merged, "--overwrite", "-q"],
                          merged + ".log", timeout=ctx.timeout(case))
        case.command = ctx.display(command, run_dir)
        return merge_figures(merged, drive_dirs)

    case = Case(name, group, title, prepare, run, figures, est_seconds, variants, sync_seconds)
    return case


def city_figures(ate_ratio_bar=None, world_bar=None, landmark_bar=None):
    return {
        "sessions": spec("sessions", "", None, digits=0),
        "maps": spec("maps at the end", "", "lower", digits=0, bars=[bar("==", 1, "quiet", source="issue 43")]),
        "frames_in_main_map_pct": spec("frames in the merged map", "%", "higher", digits=1,
                                       bars=[bar(">=", 100.0, "quiet", source="issue 43")]),
        "place_merges": spec("maps merged by place recognition", "", None, digits=0),
        "gps_joins": spec("maps joined by GPS", "", None, digits=0),
        "ate_ratio_max": spec("ATE in the merged map (one alignment) / own ATE, worst drive", "x", "lower", digits=2,
                              bars=[ate_ratio_bar] if ate_ratio_bar else []),
        "shape_ratio_max": spec("ATE in the merged map (its own alignment) / own ATE, worst drive", "x", "lower",
                                digits=2),
        "own_ate_max_m": spec("own ATE, worst drive", "m", "lower", digits=3),
        "ate_city_m": spec("ATE of all drives, one alignment", "m", "lower", digits=3),
        "world_rmse_max_m": spec("WGS84 error, worst drive (no alignment)", "m", "lower", digits=2,
                                 bars=[world_bar] if world_bar else []),
        "landmarks_placed": spec("landmarks placed (each once)", "", None, digits=0),
        "landmark_error_median_m": spec("landmark error, median (through the nearest keyframe's true pose)", "m",
                                        "lower", digits=2, bars=[landmark_bar] if landmark_bar else []),
        "topology_nodes": spec("topological nodes", "", None, digits=0),
        "topology_revisited_nodes": spec("topological nodes passed more than once", "", None, digits=0),
        "merge_s": spec("merge time", "s", "lower", "resource", digits=1),
        "merge_rss_mib": spec("merge peak memory", "MiB", "lower", "resource", digits=0),
    }


def city_cases(frames):
    """Four drives (route seeds 1-4) of one town: mono with GPS every 30 frames (σ 1 m) and landmarks, mono
    without GPS, stereo without GPS."""
    def drives(with_gps):
        def make(ctx):
            out = []
            for r in (1, 2, 3, 4):
                town = route(ctx, CITY_SEED, r, frames)
                args = ["--segmenter", "truth-noisy:0.25"]
                if with_gps:
                    args += ["--gps", os.path.join(town, "oxts"), "--gps-every", "30",
                             "--landmarks", os.path.join(town, "landmarks.csv")]
                out.append((os.path.join(town, "sequences", "00"), args))
            return out
        return make

    # Once at the default pacing their bars judge, and once at synchronous pacing: a realtime city's ratios
    # spread between runs more than any change moves them (1.5x to 2.8x), the synchronous city repeats, and
    # its change is what a commit did. Measured here: each drive's realtime run takes its frames at 10 Hz and
    # a few seconds more, then the merge; a synchronous drive about 40 s (mono) or 60 s (stereo).
    variants = {"synchronous": 1, "quiet": 1, "busy": 0}
    est = {"mono": 4 * (frames / 10 + 5) + 60, "stereo": 4 * (frames / 10 + 8) + 80}
    sync = {"mono": 4 * 40 + 60, "stereo": 4 * 60 + 80}
    title = "town seed %d, route seeds 1-4, %d frames each, %%s" % (CITY_SEED, frames)
    return [
        merge_case("city_mono_gps", "city", title % "mono, GPS every 30 frames, landmarks", drives(True),
                   ["--mode", "mono"], city_figures(world_bar=bar("<=", 1.5, "quiet", source="issue 43"),
                                                landmark_bar=bar("<=", 1.0, "quiet", source="issue 43")),
                   est["mono"], variants, sync["mono"]),
        merge_case("city_mono", "city", title % "mono, no GPS", drives(False), ["--mode", "mono"],
                   city_figures(ate_ratio_bar=bar("<=", 1.5, "quiet", source="issue 43")), est["mono"], variants,
                   sync["mono"]),
        merge_case("city_stereo", "city", title % "stereo, no GPS", drives(False), ["--mode", "stereo"],
                   city_figures(ate_ratio_bar=bar("<=", 1.2, "quiet", source="issue 43")), est["stereo"], variants,
                   sync["stereo"]),
    ]


def real_merge_cases():
    """Real drives merged: KITTI 07 0-159 and the same frames reversed; drive 0005's colour and grey cameras."""
    figures = lambda: {k: v for k, v in city_figures(bar("<=", 1.5, "quiet", source="issue 43")).items()
                       if k not in ("world_rmse_max_m", "landmarks_placed", "landmark_error_median_m",
                                    "topology_nodes", "topology_revisited_nodes")}
    k07 = lambda ctx: [(kitti07(ctx), ["--frames", "0:160"]), (composed(ctx, kitti07(ctx), "159-0"), [])]
    d05 = lambda ctx: [(drive0005(ctx), ["--camera", "image_02"]), (drive0005(ctx), ["--camera", "image_00"])]
    return [
        merge_case("merge_k07_forth_back", "real", "KITTI 07 frames 0-159 and 159-0 as two drives, mono", k07,
                   ["--mode", "mono"], figures(), 35, sync_seconds=18),
        merge_case("merge_d05_colour_grey", "real", "drive 0005 colour (image_02) and grey (image_00) as two drives, "
                   "mono", d05, ["--mode", "mono"], figures(), 26, sync_seconds=16),
    ]


def city_drives(ctx, frames, route_seeds):
    return [os.path.join(route(ctx, CITY_SEED, r, frames), "sequences", "00") for r in route_seeds]


def children_cpu_s():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def python_package(ctx):
    """build/<preset>/python beside the binary's build/<preset>/bin, with python3-distributed to run it."""
    package = os.path.join(os.path.dirname(os.path.dirname(ctx.bin)), "python")
    if not os.path.isfile(os.path.join(package, "semslam", "city.py")):
        raise Skip("no Python package beside the binary (%s)" % package)
    if subprocess.run([ctx.python, "-c", "import distributed"], capture_output=True).returncode != 0:
        raise Skip("%s has no Dask distributed (python3-distributed)" % ctx.python)
    return package


class WorkerKiller(threading.Thread):
    """Reads a `semslam.city` log as it grows; 10 s after the first drive starts (well into its run) SIGKILLs the
    worker running it, so that Dask runs the drive again elsewhere."""

    PATTERN = re.compile(r"^\s*drive (\S+): running on \S+ \(pid (\d+)\)", re.M)

    def __init__(self, log_path):
        super().__init__(daemon=True)
        self.log_path = log_path
        self.done = threading.Event()  # set when the city has ended
        self.killed = None             # the drive whose worker was killed

    def run(self):
        while not self.done.wait(0.2):
            with open(self.log_path, errors="replace") as f:
                m = self.PATTERN.search(f.read())
            if m is None:
                continue
            if not self.done.wait(10):
                try:
                    os.kill(int(m.group(2)), signal.SIGKILL)
                    self.killed = m.group(1)
                except ProcessLookupError:
                    pass
            return


class CityProcess:
    """`python3 -m semslam.city` on a local cluster of `workers`, run and stopped as every benchmark command is
    (ctx.call); `kill_first_drive` kills the worker of the first drive that starts (WorkerKiller)."""

    def __init__(self, ctx, package, drives, out, workers, args, kill_first_drive=False):
        self.command = [ctx.python, "-m", "semslam.city", "--drives"] + drives + [
            "--out", out, "--local-workers", str(workers), "--semslam", ctx.bin] + args
        log_path = out + ".log"
        killer = WorkerKiller(log_path) if kill_first_drive else None
        with open(log_path, "w") as log:
            log.write("$ %s\n" % " ".join(self.command))
            log.flush()
            start = time.monotonic()
            if killer:
                killer.start()
            try:
                code = ctx.call(self.command, log, timeout=3600, env=dict(os.environ, PYTHONPATH=package))
            finally:
                if killer:
                    killer.done.set()
                    killer.join()
            self.seconds = time.monotonic() - start
        self.killed = killer.killed if killer else None
        with open(log_path, errors="replace") as f:
            self.output = f.read()
        if code != 0:
            raise RunFailed("semslam.city exit %s (%s)" % (code, log_path))


def same_outputs(a, b, names):
    """Whether two cities hold the same bytes where they say where the frames and points are: each drive's run
    and the merged city (synchronous pacing is reproducible, so a drive run again must give the same)."""
    parts = [os.path.join("drives", n, f) for n in names for f in ("trajectory.tum", "semantic_map.ply")]
    parts.append(os.path.join("city", "semantic_map.ply"))
    sessions = os.path.join(a, "city", "sessions")
    parts += [os.path.join("city", "sessions", s, "trajectory.tum") for s in sorted(os.listdir(sessions))]
    return all(os.path.exists(os.path.join(b, p)) and filecmp.cmp(os.path.join(a, p), os.path.join(b, p),
                                                                  shallow=False) for p in parts)


def engine_case(frames):
    """Four drives on one Dask worker, then on two, then on two with the first drive's worker killed."""
    def prepare(ctx):
        return {"package": python_package(ctx), "drives": city_drives(ctx, frames, (1, 2, 3, 4))}

    def run(ctx, prepared, run_dir, pacing):
        shutil.rmtree(run_dir, ignore_errors=True)  # semslam.city would take an earlier city's drives as done
        os.makedirs(run_dir)
        drives, package = prepared["drives"], prepared["package"]
        mode, run_args = ["--mode", "mono"], ["--segmenter", "truth-noisy:0.25"]
        args = mode + ["--"] + run_args  # semslam.city passes what follows -- to every run
        # One drive alone, to know how many cores one semslam run keeps busy (the bound on what a second worker
        # can add on a machine of two cores).
        alone = os.path.join(run_dir, "alone")
        cpu0, t0 = children_cpu_s(), time.monotonic()
        run_slam(ctx, case, drives[0], alone, "synchronous", mode + run_args)
        cores = (children_cpu_s() - cpu0) / (time.monotonic() - t0)
        one = CityProcess(ctx, package, drives, os.path.join(run_dir, "workers1"), 1, args)
        two = CityProcess(ctx, package, drives, os.path.join(run_dir, "workers2"), 2, args)
        killed = CityProcess(ctx, package, drives, os.path.join(run_dir, "killed"), 2, args, kill_first_drive=True)
        case.command = "python3 " + ctx.display(two.command, run_dir)[len("semslam "):]
        names = sorted(os.listdir(os.path.join(run_dir, "workers2", "drives")))
        redone = killed.killed is not None and len(re.findall(
            r"drive %s: running on .*attempt 2" % re.escape(killed.killed), killed.output)) == 1
        return {"wall_1_s": one.seconds, "wall_2_s": two.seconds, "wall_ratio": two.seconds / one.seconds,
                "cores_one_run": cores, "killed_redone": 1 if redone else 0,
                "killed_same": 1 if same_outputs(os.path.join(run_dir, "workers2"),
                                                 os.path.join(run_dir, "killed"), names) else 0,
                "same_1_2": 1 if same_outputs(os.path.join(run_dir, "workers1"),
                                              os.path.join(run_dir, "workers2"), names) else 0}

    figures = {
        "wall_1_s": spec("4 drives and their merges on 1 worker", "s", "lower", "resource", digits=0),
        "wall_2_s": spec("the same on 2 workers", "s", "lower", "resource", digits=0),
        "wall_ratio": spec("2 workers / 1 worker", "x", "lower", "resource", digits=2,
                           bars=[bar("<=", 0.65, "quiet", source="issue 43")]),
        "cores_one_run": spec("cores one drive's run keeps busy (CPU time / wall time)", "", None, "resource",
                              digits=2),
        "killed_redone": spec("a killed worker's drive run again", "", "higher", digits=0,
                              bars=[bar("==", 1, "quiet", source="issue 43")]),
        "killed_same": spec("outputs with the kill = without (bytes)", "", "higher", digits=0,
                            bars=[bar("==", 1, "quiet", source="issue 43")]),
        "same_1_2": spec("outputs on 1 worker = on 2 (bytes)", "", "higher", digits=0,
                         bars=[bar("==", 1, "quiet")]),
    }
    title = ("town seed %d, route seeds 1-4, %d frames each, mono, on a local Dask cluster "
             "(`python3 -m semslam.city`)" % (CITY_SEED, frames))
    case = Case("city_engine", "city", title, prepare, run, figures, 780,
                variants={"synchronous": 0, "quiet": 1, "busy": 0})
    return case


def merge_memory_case(frames):
    """`semslam merge` of the first 1, 2, 4 and 8 of eight short drives: its peak memory against their number."""
    counts = (1, 2, 4, 8)

    def prepare(ctx):
        return {"drives": city_drives(ctx, frames, range(1, counts[-1] + 1))}

    def run(ctx, prepared, run_dir, pacing):
        drive_dirs = []
        for k, sequence in enumerate(prepared["drives"]):
            drive_dirs.append(os.path.join(run_dir, "drive%d" % (k + 1)))
            run_slam(ctx, case, sequence, drive_dirs[-1], "synchronous", ["--mode", "mono"])
        out = {}
        for n in counts:
            merged = os.path.join(run_dir, "merged%d" % n)
            command = semslam(ctx, ["merge", "--maps"] + drive_dirs[:n] + ["--out", merged, "--overwrite", "-q"],
                              merged + ".log", timeout=ctx.timeout(case))
            run = read_json(os.path.join(merged, "run.json"))
            out["merge_rss_%d_mib" % n] = run.get("peak_rss_mib")
            out["merge_%d_s" % n] = run.get("seconds")
        case.command = ctx.display(command, run_dir)
        return out

    figures = {}
    for n in counts:
        figures["merge_rss_%d_mib" % n] = spec("merge peak memory, %d drive%s" % (n, "" if n == 1 else "s"), "MiB",
                                               "lower", "resource", digits=0)
    for n in counts:
        figures["merge_%d_s" % n] = spec("merge time, %d drive%s" % (n, "" if n == 1 else "s"), "s", "lower",
                                         "resource", digits=1)
    title = "town seed %d, route seeds 1-8, %d frames each, mono: `semslam merge` of 1, 2, 4, 8" % (CITY_SEED, frames)
    case = Case("merge_memory", "city", title, prepare, run, figures, 230,
                variants={"synchronous": 1, "quiet": 0, "busy": 0})
    return case
