"""The benchmark's cases: what each runs and which figures it takes from the run's files.

A case is a Case: `prepare(ctx)` makes its inputs (composed or rendered sequences, from the cache when they are
there) and returns them, or raises Skip with the reason when its data is missing; `run(ctx, inputs, run_dir,
pacing)` runs it once and returns its figures ({name: number}). `variants` says which runs it gets: synchronous
pacing once, realtime pacing on the quiet machine and with one core kept busy (scripts/benchmark.py runs them).
"""

import json
import os
import re

import bench_geo
from bench_inputs import (KITTI00_LEVER_ARM, LONG_DRIVE_FRAMES, RunFailed, composed, drive0005, kitti07, long_drive,
                          python_tool, read_json, require, run_slam, semslam, slam_figures, straight_drive, town)


def bar(op, value, on="quiet", every_run=False, source=""):
    return {"op": op, "value": value, "on": on, "every_run": every_run, "source": source}


def spec(label, unit="", better=None, kind="accuracy", digits=3, bars=()):
    return {"label": label, "unit": unit, "better": better, "kind": kind, "digits": digits, "bars": list(bars)}


class Case:
    def __init__(self, name, group, title, prepare, run, figures, est_seconds, variants=None, sync_seconds=None):
        self.name, self.group, self.title = name, group, title
        self.prepare, self.run, self.figures = prepare, run, figures
        self.est_seconds = est_seconds            # one realtime run, on this 2-core machine
        self.sync_seconds = sync_seconds or est_seconds
        self.variants = variants                  # {variant: runs}; None: the benchmark's defaults
        self.command = ""                         # the last command run, for the docs


# Figure specs used by several cases.
ATE = spec("ATE", "m", "lower", digits=3)
WITH_POSE = spec("frames with a pose", "", "higher", digits=0)
KEYFRAMES = spec("keyframes per 100 frames", "", None, digits=1)
TRACKING = spec("tracking, median per frame", "ms", "lower", "resource", digits=1)
RSS = spec("peak memory", "MiB", "lower", "resource", digits=0)
LOOPS = spec("loops closed", "", None, digits=0)
MAPS_STARTED = spec("maps started", "", None, digits=0)
MERGES = spec("merges", "", None, digits=0)


def with_bars(base, *bars):
    copy = dict(base)
    copy["bars"] = list(bars)
    return copy


# ---------------------------------------------------------------------------------------------------------------
# Cases


def slam_case(name, group, title, inputs, extra, figures, est_seconds, variants=None, more=None, sync_seconds=None):
    """A case that is one `semslam run` (inputs(ctx) -> {'sequence': ..., ...}); `more(ctx, inputs, run_dir)`
    adds figures of its own."""
    def prepare(ctx):
        return inputs(ctx)

    def run(ctx, prepared, run_dir, pacing):
        run_slam(ctx, case, prepared["sequence"], run_dir, pacing,
                 extra(prepared) if callable(extra) else extra)
        out = slam_figures(run_dir)
        if more is not None:
            out.update(more(ctx, prepared, run_dir))
        return out

    case = Case(name, group, title, prepare, run, figures, est_seconds, variants, sync_seconds)
    return case


def d05_stereo_path(ctx, prepared, run_dir):
    est = bench_geo.tum_path_length(os.path.join(run_dir, "trajectory.tum"))
    truth = bench_geo.oxts_forward_distance(prepared["drive"], 0, 80)
    return {"path_error_pct": 100.0 * (est / truth - 1.0) if truth > 0 else None}


def d05_geo(ctx, prepared, run_dir):
    out = {}
    text = python_tool(ctx, [os.path.join(ctx.repo, "tools", "georef_against_oxts.py"), run_dir, prepared["drive"],
                             "--camera", "image_02", "--gps-every", "30"])
    m = re.search(r"tracked frames: (\d+) frames, horizontal RMSE ([\d.]+) m \(max [\d.]+\), 3D RMSE ([\d.]+) m",
                  text)
    if not m:
        raise RunFailed("georef_against_oxts.py: unexpected output %r" % text[-200:])
    out["wgs84_rmse_m"] = float(m.group(3))
    out["wgs84_horizontal_rmse_m"] = float(m.group(2))
    geojson = os.path.join(run_dir, "landmarks.geojson")
    if os.path.exists(geojson):
        features = bench_geo.read_geojson_features(geojson)
        considered, right, _ = bench_geo.landmarks_with_right_keyframe(
            features, bench_geo.read_oxts_track(prepared["drive"]))
        out["landmarks_right_pct"] = 100.0 * right / considered if considered else None
    return out


def wgs84_against_rtk(ctx, prepared, wgs84_csv):
    """tools/wgs84_against_rtk.py's figures ({rmse_m, frames, ...}) of a t,lat,lon,alt file of KITTI 00."""
    result = json.loads(python_tool(ctx, [
        os.path.join(ctx.repo, "tools", "wgs84_against_rtk.py"), wgs84_csv, prepared["rtk"],
        os.path.join(prepared["sequence"], "times.txt"), prepared["poses"],
        # One argument: a value starting with '-' would be read as an option.
        "--lever-arm=" + ctx.kitti00_lever_arm, "--json"]))
    if not result.get("frames"):
        raise RunFailed("wgs84_against_rtk.py: no row of %s matched a frame of times.txt" % wgs84_csv)
    return result


def straight_geo(ctx, prepared, run_dir):
    """KITTI 04's WGS84 against its RTK track, and its landmarks' nearest keyframes."""
    wgs84 = os.path.join(run_dir, "trajectory_wgs84.csv")
    run = read_json(os.path.join(run_dir, "run.json"))
    rows = bench_geo.count_csv_rows(wgs84) if os.path.exists(wgs84) else 0
    out = {"wgs84_missing": (run.get("with_pose") or 0) - rows}
    if rows:
        out["wgs84_rmse_m"] = wgs84_against_rtk(ctx, prepared, wgs84)["rmse_m"]
    geojson = os.path.join(run_dir, "landmarks.geojson")
    if os.path.exists(geojson):
        considered, right, _ = bench_geo.landmarks_with_right_keyframe(
            bench_geo.read_geojson_features(geojson), bench_geo.read_kml_track(prepared["rtk"]))
        out["landmarks_placed"] = considered
        out["landmarks_right"] = right
    return out


def kitti00_geo(ctx, prepared, run_dir):
    """WGS84 of the GPS run against the RTK track, its street corners, and `localize` on the revisit."""
    out = {}
    wgs84 = os.path.join(run_dir, "trajectory_wgs84.csv")
    run = read_json(os.path.join(run_dir, "run.json"))
    rows = bench_geo.count_csv_rows(wgs84) if os.path.exists(wgs84) else 0
    out["wgs84_frames"] = rows
    # Every frame with a pose, in whichever map, should be in the world (issue 41).
    out["wgs84_missing"] = (run.get("with_pose") or 0) - rows
    out["maps_in_world"] = sum(1 for m in (run.get("geo") or {}).get("maps", []) if m.get("in_world"))
    if rows:
        out["wgs84_rmse_m"] = wgs84_against_rtk(ctx, prepared, wgs84)["rmse_m"]
    geojson = os.path.join(run_dir, "landmarks.geojson")
    if os.path.exists(geojson):
        considered, right, _ = bench_geo.landmarks_with_right_keyframe(
            bench_geo.read_geojson_features(geojson), bench_geo.read_kml_track(prepared["rtk"]), category="corner")
        out["corners"] = considered
        out["corners_right"] = right
    # Localization on the revisit against this run's map (every map of the file is searched; a WGS84 position
    # only from a map the file puts in the world).
    loc_dir = run_dir + "-localize"
    semslam(ctx, ["localize", "--map", os.path.join(run_dir, "map.semslam"), "--sequence", prepared["sequence"],
                  "--frames", LOCALIZE_FRAMES, "--out", loc_dir, "--overwrite", "-q"], loc_dir + ".log",
            timeout=1800)
    report = read_json(os.path.join(loc_dir, "localize.json"))
    frames = max(1, report.get("frames") or 0)
    out["localized_pct"] = 100.0 * (report.get("localized") or 0) / frames
    out["localized_in_world_pct"] = 100.0 * (report.get("in_world") or 0) / frames
    unreferenced = {m["map"] for m in report.get("maps", []) if m.get("georeference") == "none"}
    loc_rows, wrong = bench_geo.localization_wgs84(os.path.join(loc_dir, "localization.csv"), unreferenced)
    out["localized_wgs84_unreferenced"] = wrong
    if len(loc_rows) != (report.get("in_world") or 0):
        raise RunFailed("localize: localization.csv has %d WGS84 rows, localize.json in_world says %s" % (
            len(loc_rows), report.get("in_world")))
    if loc_rows:
        loc_csv = os.path.join(loc_dir, "localization_wgs84.csv")
        bench_geo.write_wgs84_csv(loc_csv, loc_rows)
        out["localized_wgs84_rmse_m"] = wgs84_against_rtk(ctx, prepared, loc_csv)["rmse_m"]
    return out


LOCALIZE_FRAMES = "1550:1700"


def share_pct(value):
    """A demo.json share (0..1) in percent; its -1 (not measured) as no figure."""
    return None if value is None or value < 0 else 100.0 * value


def demo_case(frames, second_drive, variants):
    def prepare(ctx):
        return {}

    def run(ctx, prepared, run_dir, pacing):
        args = ["demo", "--out", run_dir, "-q", "--frames", frames, "--second-drive", second_drive]
        if pacing == "synchronous":
            args += ["--pacing", "synchronous"]
        start = ctx.clock()
        command = semslam(ctx, args, run_dir + ".log", timeout=ctx.timeout(case))
        wall = ctx.clock() - start
        case.command = ctx.display(command, run_dir)
        demo = read_json(os.path.join(run_dir, "demo.json"))
        out = slam_figures(os.path.join(run_dir, "run"))
        out.update({"wall_s": wall,
                    "localized_within_1m_pct": share_pct(demo.get("localized_within_1m")),
                    "nearest_landmark_right_pct": share_pct(demo.get("nearest_landmark_right")),
                    "report": 1 if os.path.exists(os.path.join(run_dir, "run", "report.html")) else 0})
        return out

    figures = {
        "ate_m": ATE,
        "ate_pct_path": spec("ATE / path", "%", "lower", digits=4, bars=[bar("<=", 0.3, "quiet", source="SPEC")]),
        "loops": LOOPS,
        "label_pct": spec("map labels right (run.json label_accuracy)", "%", "higher", digits=1,
                          bars=[bar(">=", 93.0, "quiet", source="SPEC")]),
        "landmark_error_max_m": spec("landmark error, max", "m", "lower", digits=2,
                                     bars=[bar("<=", 2.0, "quiet", source="SPEC")]),
        "localized_within_1m_pct": spec("second drive localized within 1 m", "%", "higher", digits=1,
                                        bars=[bar(">=", 95.0, "quiet", source="SPEC")]),
        "nearest_landmark_right_pct": spec("nearest landmark right", "%", "higher", digits=1),
        "report": spec("report.html written", "", "higher", digits=0, bars=[bar("==", 1, "quiet")]),
        "wall_s": spec("wall time", "s", "lower", "resource", digits=0),
    }
    # Measured here: the demo renders its town (~17 frames/s), then runs the drives (at 10 Hz when realtime).
    drive_frames = frames + second_drive
    case = Case("demo", "demo", "`semslam demo` (%s frames, second drive %s)" % (frames, second_drive), prepare,
                run, figures, drive_frames / 17 + drive_frames / 10 + 10, variants,
                sync_seconds=drive_frames / 17 + 0.1 * drive_frames)
    return case


def synthetic_cases(seeds, frames, blackout_modes, variants=None):
    """Each seed's town mono and stereo, with GPS every 30 frames, landmarks and 25 %-noisy labels; a 2 s
    black-out in the middle of the first seed's town (one run per mode in blackout_modes)."""
    cases = []
    # Measured here: a realtime run takes its frames at 10 Hz and a few seconds more; a synchronous one about
    # 100 ms a frame (mono) or 160 ms (stereo).
    est = frames / 10 + 8
    sync_est = {"mono": 0.1 * frames, "stereo": 0.16 * frames}
    geo_args = lambda p: ["--gps", os.path.join(p["town"], "oxts"), "--gps-every", "30", "--landmarks",
                          os.path.join(p["town"], "landmarks.csv"), "--segmenter", "truth-noisy:0.25"]
    for seed in seeds:
        for mode in ("mono", "stereo"):
            figures = {
                "ate_m": ATE,
                "ate_pct_path": spec("ATE / path", "%", "lower", digits=4,
                                     bars=[bar("<=", 0.3, "quiet", source="SPEC")] if mode == "mono" else []),
                "loops": LOOPS,
                "with_pose": WITH_POSE,
                # SPEC's 93 % judges the headline, the user's measure (issue 42): each point against the
                # surface it lies on where the map puts it in the world.
                "label_3d_pct": spec("map labels right, 3D, per keyframe", "%", "higher", digits=1),
                "label_3d_global_pct": spec("map labels right, 3D, one alignment (the headline)", "%", "higher",
                                            digits=1, bars=[bar(">=", 93.0, "quiet", source="SPEC")]),
                "label_2d_pct": spec("map labels right, 2D (keypoints)", "%", "higher", digits=1,
                                     bars=[bar(">=", 95.0, "quiet", source="SPEC")]),
                "landmark_error_median_m": spec("landmark error, median", "m", "lower", digits=2),
                "landmark_error_max_m": spec("landmark error, max", "m", "lower", digits=2,
                                             bars=[bar("<=", 2.0, "quiet", source="SPEC")]),
                "wgs84_ate_m": spec("WGS84 trajectory error (RMSE)", "m", "lower", digits=2),
                "keyframes_per_100": KEYFRAMES,
                "tracking_ms": TRACKING,
                "peak_rss_mib": RSS,
            }
            cases.append(slam_case(
                "town%d_%s" % (seed, mode), "synthetic",
                "town seed %d, %d frames, %s, GPS every 30 frames, landmarks, labels truth-noisy:0.25" % (
                    seed, frames, mode),
                lambda ctx, s=seed: {"sequence": town(ctx, s, frames), "town": town(ctx, s, frames)},
                lambda p, m=mode: ["--mode", m] + geo_args(p), figures, est, variants,
                sync_seconds=sync_est[mode]))
    seed = seeds[0]
    black = "%d:%d" % (frames // 2, frames // 2 + 20)
    for mode in blackout_modes:
        figures = {
            "ate_m": ATE,
            "with_pose": WITH_POSE,
            "maps_started": MAPS_STARTED,
            "merges": MERGES,
            "maps": spec("maps at the end", "", "lower", digits=0, bars=[bar("==", 1, "quiet", True, "issue 9")]),
            "loops": LOOPS,
            "keyframes_per_100": KEYFRAMES,
        }

        def inputs(ctx, s=seed):
            source = os.path.join(town(ctx, s, frames), "sequences", "00")
            return {"sequence": composed(ctx, source, "0-%d" % (frames - 1), black=black, stereo=True)}

        cases.append(slam_case(
            "town%d_blackout_%s" % (seed, mode), "synthetic",
            "town seed %d, frames %s black (2 s), %s" % (seed, black.replace(":", "-"), mode), inputs,
            ["--mode", mode], figures, est, variants, sync_seconds=sync_est[mode]))
    return cases


def real_cases(quick):
    cases = []
    k07_figures = {
        "ate_m": with_bars(ATE, bar("<=", 0.3, "quiet", source="SPEC"), bar("<=", 0.3, "busy", source="SPEC")),
        "with_pose": WITH_POSE,
        "keyframes_per_100": KEYFRAMES,
        "tracking_ms": with_bars(TRACKING, bar("<=", 40.0, "quiet", source="SPEC")),
        "peak_rss_mib": RSS,
    }
    cases.append(slam_case("kitti07_mono", "real", "KITTI 07 frames 0-159, mono",
                           lambda ctx: {"sequence": kitti07(ctx)}, ["--mode", "mono", "--frames", "0:160"],
                           k07_figures, 18, sync_seconds=9))
    d05 = lambda ctx: {"sequence": drive0005(ctx), "drive": drive0005(ctx)}
    # Issue 41: "no worse than today (154/154 at 0.30 m)", to two digits; the drive measured 0.302-0.315 m then.
    cases.append(slam_case(
        "d05_image02_mono", "real", "drive 0005 colour camera (image_02), 154 frames, mono", d05,
        ["--camera", "image_02", "--mode", "mono"],
        {"ate_m": with_bars(ATE, bar("<=", 0.305, "quiet", source="issue 41")),
         "with_pose": with_bars(WITH_POSE, bar(">=", 154, "quiet", source="issue 41")),
         "tracked": spec("frames tracked", "", "higher", digits=0),
         "keyframes_per_100": KEYFRAMES, "tracking_ms": TRACKING}, 18, sync_seconds=11))
    cases.append(slam_case(
        "d05_image00_mono", "real", "drive 0005 grey camera (image_00), frames 0-79, mono", d05,
        ["--camera", "image_00", "--mode", "mono", "--frames", "0:80"],
        {"ate_m": ATE, "with_pose": WITH_POSE, "tracked": spec("frames tracked", "", "higher", digits=0),
         "keyframes_per_100": KEYFRAMES}, 10, sync_seconds=5))
    cases.append(slam_case(
        "d05_stereo", "real", "drive 0005 grey stereo (image_00/01), frames 0-79", d05,
        ["--mode", "stereo", "--frames", "0:80"],
        {"ate_m": ATE, "with_pose": WITH_POSE,
         "path_error_pct": spec("path against the OXTS forward speed", "%", None, digits=2,
                                bars=[bar("abs<=", 1.0, "quiet", source="issue 41")]),
         "keyframes_per_100": KEYFRAMES}, 10, more=d05_stereo_path, sync_seconds=6))
    osm = lambda ctx: require(os.path.join(ctx.shared, "kitti_raw_2011_09_26_drive_0005_osm",
                                           "2011_09_26_drive_0005_sync.osm"), "drive 0005 OpenStreetMap extract")

    def d05_gps_inputs(ctx):
        weights = os.path.join(ctx.shared, "segmentation_weights")
        require(weights, "segmentation weights")
        return {"sequence": drive0005(ctx), "drive": drive0005(ctx), "osm": osm(ctx)}

    cases.append(slam_case(
        "d05_gps_landmarks", "real",
        "drive 0005 colour, SINet labels, GPS every 30 frames, its OpenStreetMap extract as landmarks",
        d05_gps_inputs,
        lambda p: ["--camera", "image_02", "--mode", "mono", "--segmenter", "auto", "--gps",
                   os.path.join(p["drive"], "oxts"), "--gps-every", "30", "--landmarks", p["osm"]],
        {"landmarks_placed": spec("landmarks placed", "", "higher", digits=0,
                                  bars=[bar(">=", 22, "quiet", source="issue 41")]),
         "landmarks_right_pct": spec("landmarks with the right nearest keyframe (±%d frames)" %
                                     bench_geo.RIGHT_KEYFRAME_FRAMES, "%", "higher", digits=1,
                                     bars=[bar(">=", 90.0, "quiet", source="issue 41")]),
         "wgs84_rmse_m": spec("WGS84 against the OXTS track (RMSE, 3D)", "m", "lower", digits=2,
                              bars=[bar("<=", 1.5, "quiet", source="issue 41")]),
         "ate_m": ATE,
         "street_pct": spec("map points of street classes", "%", "higher", digits=1,
                            bars=[bar(">=", 75.0, "quiet", source="issue 10")]),
         "person_pct": spec("map points 'person'", "%", "lower", digits=1,
                            bars=[bar("<=", 5.0, "quiet", source="issue 10")]),
         "sky_pct": spec("map points 'sky'", "%", "lower", digits=1,
                         bars=[bar("<=", 2.0, "quiet", source="issue 10")])},
        19, more=d05_geo, sync_seconds=28))
    composed_figures = lambda with_pose_bars: {
        "with_pose_pct": spec("frames with a pose", "%", "higher", digits=1, bars=with_pose_bars),
        "ate_m": ATE, "maps_started": MAPS_STARTED, "merges": MERGES,
        "maps": spec("maps at the end", "", "lower", digits=0), "keyframes_per_100": KEYFRAMES}
    cases.append(slam_case(
        "k07_pp", "real", "KITTI 07 composed forth, back, forth with a 20-frame cut, back (617 frames)",
        lambda ctx: {"sequence": composed(ctx, kitti07(ctx), "0-159,158-0,1-59,80-159,158-0")}, ["--mode", "mono"],
        composed_figures([bar(">=", 99.0, "quiet", source="issue 9"), bar(">=", 95.0, "busy", source="issue 9")]),
        66, sync_seconds=31))
    cases.append(slam_case(
        "k07_cut3", "real", "KITTI 07 composed 0-59, 80-159 (a 2 s gap), back 158-0 (299 frames): a new map, merged",
        lambda ctx: {"sequence": composed(ctx, kitti07(ctx), "0-59,80-159,158-0")}, ["--mode", "mono"],
        composed_figures([]), 33, sync_seconds=15))
    cases.append(slam_case(
        "k07_third", "real", "KITTI 07 frames 0-159, every third (54 frames): a third of the frame rate",
        lambda ctx: {"sequence": composed(ctx, kitti07(ctx), ",".join(str(f) for f in range(0, 160, 3)))},
        ["--mode", "mono"], composed_figures([]), 20, sync_seconds=6))
    return cases


def long_cases():
    figures = {
        "frames_in_one_map": spec("frames with a pose in one map", "", "higher", digits=0,
                                  bars=[bar(">=", 1690, "quiet", True, "SPEC"), bar(">=", 1615, "busy", True, "SPEC")]),
        "ate_m": with_bars(ATE, bar("<=", 3.0, "quiet", True, "SPEC"), bar("<=", 5.0, "busy", True, "SPEC")),
        "keyframes_per_100": KEYFRAMES,
        "peak_rss_mib": RSS,
        "tracking_ms": with_bars(TRACKING, bar("<=", 40.0, "quiet", source="SPEC")),
        "loops": LOOPS, "maps_started": MAPS_STARTED, "merges": MERGES,
    }
    mono = slam_case("kitti00_mono", "long", "KITTI 00 frames 0-1699, mono", long_drive,
                     ["--mode", "mono", "--frames", LONG_DRIVE_FRAMES], figures, 192, sync_seconds=100,
                     variants={"synchronous": 1, "quiet": 3, "busy": 3})  # its bars judge every one of 3 runs
    gps_figures = {
        "frames_in_one_map": spec("frames with a pose in one map", "", "higher", digits=0),
        "ate_m": ATE,
        "wgs84_missing": spec("frames with a pose but no WGS84 row", "", "lower", digits=0,
                              bars=[bar("==", 0, "quiet", True, "issue 41")]),
        "wgs84_rmse_m": spec("WGS84 against the RTK track (RMSE)", "m", "lower", digits=2,
                             bars=[bar("<=", 3.0, "quiet", True, "SPEC")]),
        "maps_in_world": spec("maps in the world (run.json geo.maps in_world)", "", None, digits=0),
        "corners": spec("street corners placed", "", None, digits=0),
        "corners_right": spec("corners with the right nearest keyframe (±%d frames)" %
                              bench_geo.RIGHT_KEYFRAME_FRAMES, "", "higher", digits=0,
                              bars=[bar(">=", 12, "quiet", True, "issue 41")]),
        "localized_pct": spec("localize 1550-1699: frames localized", "%", "higher", digits=1,
                              bars=[bar(">=", 90.0, "quiet", True, "issue 41")]),
        "localized_in_world_pct": spec("localize: frames with a WGS84 position", "%", "higher", digits=1),
        "localized_wgs84_rmse_m": spec("localize: WGS84 against the RTK track (RMSE)", "m", "lower", digits=2,
                                       bars=[bar("<=", 3.0, "quiet", True, "issue 41")]),
        "localized_wgs84_unreferenced": spec("localize: WGS84 rows from a map without georeference", "", "lower",
                                             digits=0, bars=[bar("==", 0, "quiet", True, "issue 41")]),
    }
    gps = slam_case(
        "kitti00_gps", "long",
        "KITTI 00 frames 0-1699, mono, RTK GPS every 30 frames, kitti_00.osm as landmarks; localize 1550-1699",
        long_drive,
        lambda p: ["--mode", "mono", "--frames", LONG_DRIVE_FRAMES, "--gps", p["rtk"], "--gps-every", "30",
                   "--landmarks", p["osm"], "--gps-lever-arm=" + KITTI00_LEVER_ARM],
        gps_figures, 185, variants={"synchronous": 1, "quiet": None, "busy": 0}, more=kitti00_geo, sync_seconds=130)
    # Held out: a straight drive, whose fixes lie on one line.
    straight = slam_case("kitti04_mono", "long", "KITTI 04 (271 frames, 394 m straight), mono", straight_drive,
                         ["--mode", "mono"],
                         {"frames_in_one_map": with_bars(figures["frames_in_one_map"]), "ate_m": ATE,
                          "keyframes_per_100": KEYFRAMES, "tracking_ms": TRACKING}, 30, sync_seconds=12)
    straight_gps = slam_case(
        "kitti04_gps", "long", "KITTI 04, mono, RTK GPS every 30 frames (on one line), kitti_04.osm as landmarks",
        straight_drive,
        lambda p: ["--mode", "mono", "--gps", p["rtk"], "--gps-every", "30", "--landmarks", p["osm"],
                   "--gps-lever-arm=" + KITTI00_LEVER_ARM],
        {"wgs84_missing": gps_figures["wgs84_missing"],
         "wgs84_rmse_m": spec("WGS84 against the RTK track (RMSE)", "m", "lower", digits=2),
         "landmarks_placed": spec("landmarks placed", "", None, digits=0),
         "landmarks_right": spec("landmarks with the right nearest keyframe (±%d frames)" %
                                 bench_geo.RIGHT_KEYFRAME_FRAMES, "", "higher", digits=0)},
        31, variants={"synchronous": 1, "quiet": None, "busy": 0}, more=straight_geo, sync_seconds=13)
    return [mono, gps, straight, straight_gps]


def first_output_case(dry_run):
    """`git clone` of HEAD into a temporary folder, `scripts/demo.sh` there with an empty compiler cache, timed
    until report.html exists. Dry run: the warm shared cache and a 100-frame demo (checks the steps, not the
    figure)."""
    def prepare(ctx):
        return {}

    def run(ctx, prepared, run_dir, pacing):
        return ctx.first_output(run_dir, dry_run)

    figures = {
        "total_s": spec("clone to report.html", "s", "lower", "resource", digits=0),
        "clone_s": spec("git clone", "s", "lower", "resource", digits=0),
        "build_s": spec("build (semslam binary, empty compiler cache)", "s", "lower", "resource", digits=0),
        "demo_s": spec("demo", "s", "lower", "resource", digits=0),
    }
    title = "scripts/demo.sh in a fresh clone, empty compiler cache" + (" (DRY RUN: warm cache, 100 frames)"
                                                                         if dry_run else "")
    return Case("first_output", "first_output", title, prepare, run, figures, 120 if dry_run else 700,
                variants={"synchronous": 0, "quiet": 1, "busy": 0})


def all_cases(quick, first_output=False, first_output_dry_run=False):
    """The benchmark's cases in the order they run. quick: shorter towns, one seed, a shorter demo, no long drive,
    no first output.

    The full benchmark is to take under two hours on a 2-core machine, and a realtime run takes its frames at
    10 Hz, so the runs go where the user's figures are. Real drives get the default runs, quiet and busy, and KITTI 00
    the three of each its bars ask; the synthetic towns, the demo and the merged cities (ours, and reproducible
    at synchronous pacing) are not run with a core busy, the demo once at each pacing, the cities once at the
    default pacing, which their bars judge."""
    import bench_city  # it builds on this module's helpers
    cases = real_cases(quick) + bench_city.real_merge_cases()
    if quick:
        cases += synthetic_cases([5153], 400, ["mono"])
        cases.append(demo_case(400, 100, variants={"synchronous": 1, "quiet": 1, "busy": 0}))
    else:
        cases += long_cases()
        cases += synthetic_cases([5153, 9241], 600, ["mono", "stereo"], variants={"busy": 0})
        cases.append(demo_case(1200, 300, variants={"synchronous": 1, "quiet": 1, "busy": 0}))
        cases += bench_city.city_cases(600)
        cases += [bench_city.engine_case(600), bench_city.merge_memory_case(200)]
    if first_output or first_output_dry_run:
        cases.append(first_output_case(first_output_dry_run and not first_output))
    return cases
