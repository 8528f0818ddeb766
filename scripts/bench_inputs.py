"""What the benchmark's cases are made of: running semslam and reading a run's figures, and the inputs (real
drives found in their folders, synthetic towns and composed sequences made and cached). scripts/bench_cases.py
says what each case runs."""

import json
import os
import re
import shlex
import subprocess

import bench_geo


class Skip(Exception):
    """The case cannot run here (its data is missing): reported as skipped, not as a failure."""


class RunFailed(Exception):
    pass


# ---------------------------------------------------------------------------------------------------------------
# Running semslam


def semslam(ctx, args, log, timeout=None):
    """Runs `semslam ARGS`, its output into `log`; raises RunFailed with the last lines of its stderr."""
    command = [ctx.bin] + [str(a) for a in args]
    os.makedirs(os.path.dirname(log), exist_ok=True)
    with open(log, "w") as out:
        out.write("$ %s\n" % " ".join(shlex.quote(c) for c in command))
        out.flush()
        code = ctx.call(command, out, timeout)
    if code != 0:
        with open(log, errors="replace") as f:
            output = [line.strip() for line in f.readlines()[1:] if line.strip()]  # not the "$ command" line
        raise RunFailed("exit %s: %s (%s)" % (code, " | ".join(output[-3:])[-300:] or "no output", log))
    return command


def python_tool(ctx, args, timeout=600):
    """Runs a Python tool of the repository; returns its stdout."""
    result = subprocess.run([ctx.python] + [str(a) for a in args], capture_output=True, text=True,
                            timeout=timeout, cwd=ctx.repo)
    if result.returncode != 0:
        raise RunFailed("%s: %s" % (os.path.basename(str(args[0])), result.stderr.strip()[-300:]))
    return result.stdout


def read_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def run_slam(ctx, case, sequence, run_dir, pacing, extra):
    args = ["run", "--sequence", sequence, "--out", run_dir, "--overwrite", "-q"] + list(extra)
    if pacing == "synchronous":
        args += ["--pacing", "synchronous"]
    command = semslam(ctx, args, run_dir + ".log", timeout=ctx.timeout(case))
    case.command = ctx.display(command, run_dir)
    status = read_json(os.path.join(run_dir, "run.json")).get("status")
    if status != "complete":
        raise RunFailed("run.json status %r" % status)


def slam_figures(run_dir):
    """The figures every SLAM run gives: accuracy, frames with a pose, maps, keyframes, time and memory."""
    run = read_json(os.path.join(run_dir, "run.json"))
    frames = run.get("frames") or 0
    maps = run.get("maps", {})
    per_map = maps.get("frames_per_map", {}) or {}
    figures = {
        "ate_m": run.get("ate_rmse"),
        "with_pose": run.get("with_pose"),
        "with_pose_pct": 100.0 * run["with_pose"] / frames if frames and run.get("with_pose") is not None else None,
        "tracked": run.get("tracked"),
        "keyframes_per_100": 100.0 * run["keyframes_created"] / frames if frames else None,
        "loops": run.get("loops"),
        "maps_started": maps.get("started"),
        "maps": maps.get("count"),
        "merges": maps.get("merges"),
        "frames_in_one_map": max(per_map.values()) if per_map else 0,
        "peak_rss_mib": run.get("peak_rss_mib"),
        "path_m": run.get("path_length_m"),
    }
    if run.get("path_length_m") and run.get("ate_rmse") is not None:
        figures["ate_pct_path"] = 100.0 * run["ate_rmse"] / run["path_length_m"]
    timing_path = os.path.join(run_dir, "timing.json")
    if os.path.exists(timing_path):
        figures["tracking_ms"] = read_json(timing_path).get("tracking", {}).get("median_ms")
    for key, name in (("label_accuracy", "label_pct"), ("label_accuracy_3d", "label_3d_pct"),
                      ("label_accuracy_3d_global", "label_3d_global_pct"), ("label_accuracy_2d", "label_2d_pct")):
        if run.get(key) is not None:
            figures[name] = 100.0 * run[key]
    geo_eval = run.get("geo_evaluation") or {}
    if geo_eval:
        figures["landmark_error_median_m"] = geo_eval.get("landmark_error_median_m")
        figures["landmark_error_max_m"] = geo_eval.get("landmark_error_max_m")
        figures["wgs84_ate_m"] = geo_eval.get("trajectory_ate_rmse_m")
    geo = run.get("geo") or {}
    figures["landmarks_placed"] = geo.get("landmarks")
    shares = bench_geo.class_shares(run.get("classes") or {})
    if shares:
        figures["street_pct"] = 100.0 * shares["street"]
        figures["person_pct"] = 100.0 * shares["person"]
        figures["sky_pct"] = 100.0 * shares["sky"]
    return figures


# ---------------------------------------------------------------------------------------------------------------
# Inputs


def require(path, what):
    if not os.path.exists(path):
        raise Skip("%s not found (%s)" % (what, path))
    return path


def composed(ctx, source, frames, black=None, stereo=False):
    """A `semslam compose` of source (cached: composing copies every image)."""
    args = ["--frames", frames] + (["--black", black] if black else []) + (["--stereo"] if stereo else [])
    key = "compose-" + re.sub(r"[^A-Za-z0-9]+", "_", "%s-%s" % (os.path.basename(os.path.normpath(source)),
                                                                "-".join(args)))
    return ctx.cached(key, lambda out: semslam(
        ctx, ["compose", "--sequence", source, "--out", out, "-q"] + args, out + ".log"), source_dep=source)


def town(ctx, seed, frames):
    """A synthetic town rendered by `semslam synth` (cached)."""
    return ctx.cached("town-%d-%d" % (seed, frames), lambda out: semslam(
        ctx, ["synth", "--out", out, "--frames", frames, "--seed", seed, "-q"], out + ".log"))


def kitti07(ctx):
    return require(os.path.join(ctx.shared, "kitti_odom_07_3dv", "sequences", "07"), "KITTI 07")


def drive0005(ctx):
    return require(os.path.join(ctx.shared, "kitti_raw_2011_09_26_drive_0005", "2011_09_26",
                                "2011_09_26_drive_0005_sync"), "KITTI raw drive 0005")


LONG_DRIVE_FRAMES = "0:1700"  # KITTI 00 frames 0-1699: the long real drive of issue 41
KITTI00_KML = "RTK_GPS_kitti_00.kml"
# The GPS unit (the OXTS) in KITTI 00's camera 0 frame (x right, y down, z forward), metres: 0.7 m below and 1.1 m
# behind the camera, as KITTI raw's calib_imu_to_velo and calib_velo_to_cam place it (2011_09_26's give
# -0.329,0.712,-1.090).
KITTI00_LEVER_ARM = "-0.314,0.719,-1.089"
KITTI00_OSM = "kitti_00.osm"


def find_long_drive(folder, kml=None, osm=None):
    """The long drive's files from its folder: a KITTI odometry dataset folder (sequences/00, poses/00.txt) or a
    folder holding kitti00/dataset; the RTK track and the OpenStreetMap extract given, else beside it
    (FOLDER/osm/maps, or ../../osm/maps of the dataset folder as in /work/data). Missing: Skip naming it."""
    folder = os.path.abspath(folder)
    dataset = folder
    if not os.path.isdir(os.path.join(dataset, "sequences", "00")) and os.path.isdir(
            os.path.join(folder, "kitti00", "dataset")):
        dataset = os.path.join(folder, "kitti00", "dataset")

    def beside(name, given, what):
        if given:
            return require(os.path.abspath(given), what)
        candidates = [os.path.join(folder, "osm", "maps", name),
                      os.path.join(os.path.dirname(os.path.dirname(dataset)), "osm", "maps", name),
                      os.path.join(dataset, name)]
        for c in candidates:
            if os.path.exists(c):
                return c
        raise Skip("%s not found (looked in %s)" % (what, ", ".join(os.path.dirname(c) for c in candidates)))

    return {"sequence": require(os.path.join(dataset, "sequences", "00"), "KITTI 00"),
            "poses": require(os.path.join(dataset, "poses", "00.txt"), "KITTI 00 poses"),
            "rtk": beside(KITTI00_KML, kml, "KITTI 00 RTK track (%s)" % KITTI00_KML),
            "osm": beside(KITTI00_OSM, osm, "KITTI 00 OpenStreetMap extract (%s)" % KITTI00_OSM)}


KITTI04_KML = "RTK_GPS_kitti_04.kml"
KITTI04_OSM = "kitti_04.osm"


def straight_drive(ctx):
    """KITTI 04 (271 frames, 394 m nearly straight: the GPS fixes lie on one line) from the long drive's dataset
    folder, its RTK track and OpenStreetMap extract beside KITTI 00's. KITTI 04 was never tuned on."""
    found = long_drive(ctx)
    dataset = os.path.dirname(os.path.dirname(found["sequence"]))
    maps = os.path.dirname(found["rtk"])
    return {"sequence": require(os.path.join(dataset, "sequences", "04"), "KITTI 04 (beside KITTI 00)"),
            "poses": require(os.path.join(dataset, "poses", "04.txt"), "KITTI 04 poses"),
            "rtk": require(os.path.join(maps, KITTI04_KML), "KITTI 04 RTK track (beside KITTI 00's)"),
            "osm": require(os.path.join(os.path.dirname(found["osm"]), KITTI04_OSM),
                           "KITTI 04 OpenStreetMap extract (beside KITTI 00's)")}


def long_drive(ctx):
    if not ctx.long_dir:
        raise Skip("no long-drive folder (--long-drive DIR or SEMSLAM_LONG_DRIVE)")
    found = find_long_drive(ctx.long_dir, ctx.long_kml, ctx.long_osm)
    # The docs show the maps' folder as $MAPS (the OSM extract's as $OSM when it is elsewhere).
    for key, name in (("rtk", "$MAPS"), ("osm", "$OSM")):
        folder = os.path.dirname(found[key])
        known = [f for f, _ in ctx.display_names]
        if not folder.startswith(os.path.abspath(ctx.long_dir)) and folder not in known:
            ctx.display_names.append((folder, name))
    return found
