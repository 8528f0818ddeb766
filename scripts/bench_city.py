"""Benchmark cases of many drives merged into one map (`semslam merge`): each case runs its drives one after
another at the case's pacing, merges their run folders, and reports the merged map against each drive's own run."""

import os

from bench_cases import Case, bar, composed, drive0005, kitti07, read_json, run_slam, semslam, spec

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
    ratios, own_ates, world = [], [], []
    for s, drive in zip(sessions, drive_dirs):
        own = read_json(os.path.join(drive, "run.json")).get("ate_rmse")
        if own and s.get("ate_rmse_city") is not None:
            ratios.append(s["ate_rmse_city"] / own)
            own_ates.append(own)
        if s.get("world_rmse_m") is not None:
            world.append(s["world_rmse_m"])
    figures["ate_ratio_max"] = max(ratios) if ratios else None
    figures["own_ate_max_m"] = max(own_ates) if own_ates else None
    figures["world_rmse_max_m"] = max(world) if world else None
    geo = run.get("geo") or {}
    figures["landmarks_placed"] = geo.get("landmarks")
    figures["landmark_error_median_m"] = (run.get("landmark_evaluation") or {}).get("landmark_error_median_m")
    figures["topology_nodes"] = geo.get("topology_nodes")
    figures["topology_revisited_nodes"] = geo.get("topology_revisited_nodes")
    return figures


def merge_case(name, group, title, drives, extra, figures, est_seconds, variants=None):
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

    case = Case(name, group, title, prepare, run, figures, est_seconds, variants)
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


def city_cases(frames, est):
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

    variants = {"synchronous": 1, "quiet": 1, "busy": 0}
    title = "town seed %d, route seeds 1-4, %d frames each, %%s" % (CITY_SEED, frames)
    return [
        merge_case("city_mono_gps", "city", title % "mono, GPS every 30 frames, landmarks", drives(True),
                   ["--mode", "mono"], city_figures(world_bar=bar("<=", 1.5, "quiet", source="issue 43"),
                                                landmark_bar=bar("<=", 1.0, "quiet", source="issue 43")),
                   est["mono"], variants),
        merge_case("city_mono", "city", title % "mono, no GPS", drives(False), ["--mode", "mono"],
                   city_figures(ate_ratio_bar=bar("<=", 1.5, "quiet", source="issue 43")), est["mono"], variants),
        merge_case("city_stereo", "city", title % "stereo, no GPS", drives(False), ["--mode", "stereo"],
                   city_figures(ate_ratio_bar=bar("<=", 1.2, "quiet", source="issue 43")), est["stereo"], variants),
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
                   ["--mode", "mono"], figures(), 50),
        merge_case("merge_d05_colour_grey", "real", "drive 0005 colour (image_02) and grey (image_00) as two drives, "
                   "mono", d05, ["--mode", "mono"], figures(), 50),
    ]
