#!/usr/bin/env python3
"""The benchmark's comparison with its baseline, its bars, its Markdown and its geographic figures (pure functions,
no SLAM run)."""

import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))

import bench_inputs  # noqa: E402
import bench_city  # noqa: E402
import bench_geo  # noqa: E402
import bench_report as report  # noqa: E402
import benchmark  # noqa: E402


def figure(better="lower", kind="accuracy", sync=None, quiet=None, busy=None, bars=(), digits=3, unit="m"):
    return {"label": "x", "unit": unit, "better": better, "kind": kind, "digits": digits, "bars": list(bars),
            "synchronous": sync, "quiet": report.summarize(quiet or []), "busy": report.summarize(busy or [])}


def results(figures, status="ok", **extra):
    out = {"commit": {"sha": "0123456789abcdef", "short": "0123456789", "dirty": False},
           "machine": {"nproc": 2, "cpu": "Test CPU", "memory_gib": 8}, "date": "2026-01-01T00:00:00Z",
           "seconds": 754, "runs": 3, "busy_runs": 3, "command": "scripts/benchmark.sh",
           "cases": {"case_a": {"group": "real", "title": "case A", "status": status, "command": "semslam run",
                                "figures": figures, "failures": []}}}
    out.update(extra)
    return out


class Summaries(unittest.TestCase):
    def test_median_and_range(self):
        s = report.summarize([0.3, 0.1, 0.2, None])
        self.assertEqual((s["median"], s["min"], s["max"]), (0.2, 0.1, 0.3))
        self.assertEqual(s["values"], [0.3, 0.1, 0.2])
        self.assertIsNone(report.summarize([None]))

    def test_aggregate_splits_the_variants(self):
        specs = {"ate_m": {"label": "ATE", "better": "lower"}}
        runs = [("synchronous", {"ate_m": 0.5}), ("quiet", {"ate_m": 0.1}), ("quiet", {"ate_m": 0.3}),
                ("busy", {"other": 1})]
        f = report.aggregate(specs, runs)["ate_m"]
        self.assertEqual(f["synchronous"], 0.5)
        self.assertEqual(f["quiet"]["median"], 0.2)
        self.assertIsNone(f["busy"])
        self.assertEqual(f["label"], "ATE")


class Bars(unittest.TestCase):
    def test_median_or_every_run(self):
        median_bar = [{"op": "<=", "value": 0.3, "on": "quiet"}]
        self.assertTrue(report.check_bar(figure(quiet=[0.1, 0.2, 0.9], bars=median_bar)))
        every = [{"op": "<=", "value": 0.3, "on": "quiet", "every_run": True}]
        self.assertFalse(report.check_bar(figure(quiet=[0.1, 0.2, 0.9], bars=every)))

    def test_every_condition_must_hold(self):
        bars = [{"op": ">=", "value": 1690, "on": "quiet", "every_run": True},
                {"op": ">=", "value": 1615, "on": "busy", "every_run": True}]
        self.assertTrue(report.check_bar(figure("higher", quiet=[1699, 1695], busy=[1620], bars=bars)))
        self.assertFalse(report.check_bar(figure("higher", quiet=[1699, 1695], busy=[1600], bars=bars)))

    def test_nothing_measured_or_no_bar(self):
        self.assertIsNone(report.check_bar(figure(quiet=[1.0])))
        self.assertIsNone(report.check_bar(figure(bars=[{"op": "<=", "value": 1, "on": "busy"}], quiet=[2.0])))

    def test_absolute_and_synchronous(self):
        self.assertTrue(report.check_bar(figure(None, sync=-0.8, bars=[{"op": "abs<=", "value": 1.0,
                                                                        "on": "synchronous"}])))
        self.assertFalse(report.check_bar(figure(None, sync=-1.2, bars=[{"op": "abs<=", "value": 1.0,
                                                                         "on": "synchronous"}])))


class Compare(unittest.TestCase):
    def test_realtime_worse_beyond_the_widened_range(self):
        old = results({"ate_m": figure(quiet=[0.10, 0.12, 0.14])})
        # New range 0.02 widens the old [0.10, 0.14] to [0.08, 0.16]: a median of 0.17 is worse.
        new = results({"ate_m": figure(quiet=[0.16, 0.17, 0.18])})
        findings = report.compare(old, new)
        self.assertEqual([(f["figure"], f["variant"], f["kind"]) for f in findings], [("ate_m", "quiet", "worse")])
        # A median of 0.155 lies within the widened range; one of 0.05 is better, not worse.
        self.assertEqual(report.compare(old, results({"ate_m": figure(quiet=[0.15, 0.155, 0.17])})), [])
        self.assertEqual(report.compare(old, results({"ate_m": figure(quiet=[0.05])})), [])
        # Runs that end in the same state, but for the last bits of a sum, are no change.
        same = results({"ate_m": figure(quiet=[0.14 + 1e-12, 0.14 + 1e-12])})
        self.assertEqual(report.compare(results({"ate_m": figure(quiet=[0.14, 0.14])}), same), [])
        # Nor is a median beyond the range by less than the page can show (half a unit of its last digit).
        self.assertEqual(report.compare(results({"t": figure(quiet=[0.0], digits=0, unit="s")}),
                                        results({"t": figure(quiet=[0.13], digits=0, unit="s")})), [])
        self.assertEqual(len(report.compare(results({"t": figure(quiet=[0.0], digits=0, unit="s")}),
                                            results({"t": figure(quiet=[0.6], digits=0, unit="s")}))), 1)

    def test_higher_is_better(self):
        old = results({"with_pose": figure("higher", quiet=[1699, 1700])})
        self.assertEqual(len(report.compare(old, results({"with_pose": figure("higher", quiet=[1690])}))), 1)
        self.assertEqual(report.compare(old, results({"with_pose": figure("higher", quiet=[1700])})), [])

    def test_one_busy_run_is_widened_by_the_quiet_range(self):
        old = results({"ate_m": figure(quiet=[0.10, 0.14], busy=[0.20])})
        # The quiet runs spread 0.05: a single busy run of 0.24 lies within 0.20 + 0.05, one of 0.26 does not.
        self.assertEqual(report.compare(old, results({"ate_m": figure(quiet=[0.10, 0.15], busy=[0.24])})), [])
        findings = report.compare(old, results({"ate_m": figure(quiet=[0.10, 0.15], busy=[0.26])}))
        self.assertEqual([f["variant"] for f in findings], ["busy"])

    def test_busy_compared_on_its_own(self):
        old = results({"ate_m": figure(quiet=[0.1], busy=[0.2])})
        findings = report.compare(old, results({"ate_m": figure(quiet=[0.1], busy=[0.3])}))
        self.assertEqual([f["variant"] for f in findings], ["busy"])

    def test_synchronous_any_change_is_reported(self):
        old = results({"ate_m": figure(sync=0.135)})
        self.assertEqual(report.compare(old, results({"ate_m": figure(sync=0.135 + 1e-12)})), [])
        better = report.compare(old, results({"ate_m": figure(sync=0.134)}))
        self.assertEqual([(f["kind"], f["direction"]) for f in better], [("changed", "better")])
        worse = report.compare(old, results({"ate_m": figure(sync=0.2)}))
        self.assertEqual([(f["kind"], f["direction"]) for f in worse], [("changed", "worse")])
        loops = report.compare(results({"loops": figure(None, sync=2)}), results({"loops": figure(None, sync=1)}))
        self.assertEqual([f["direction"] for f in loops], ["changed"])

    def test_worse_findings_leave_out_better_and_neutral_changes(self):
        old = results({"ate_m": figure(sync=0.2), "rmse": figure(sync=0.2), "loops": figure(None, sync=2)})
        new = results({"ate_m": figure(sync=0.3), "rmse": figure(sync=0.1), "loops": figure(None, sync=1)})
        findings = report.compare(old, new)
        self.assertEqual(len(findings), 3)
        self.assertEqual([f["figure"] for f in report.worse_findings(findings)], ["ate_m"])

    def test_resources_are_not_compared_at_synchronous_pacing(self):
        old = results({"rss": figure(kind="resource", sync=100.0)})
        self.assertEqual(report.compare(old, results({"rss": figure(kind="resource", sync=180.0)})), [])

    def test_a_failed_case_is_named_and_a_skipped_one_is_not(self):
        old = results({"ate_m": figure(quiet=[0.1])})
        failed = results({}, status="failed")
        failed["cases"]["case_a"]["reason"] = "exit 1"
        self.assertEqual([f["kind"] for f in report.compare(old, failed)], ["failed"])
        self.assertEqual(report.compare(old, results({}, status="skipped")), [])
        self.assertEqual(report.compare(None, results({"ate_m": figure(quiet=[0.1])})), [])

    def test_a_case_of_other_inputs_is_named_not_compared(self):
        old = results({"ate_m": figure(sync=0.1, quiet=[0.1])})
        new = results({"ate_m": figure(sync=0.9, quiet=[0.9])})
        new["cases"]["case_a"]["title"] = "case A, longer"
        findings = report.compare(old, new)
        self.assertEqual([f["kind"] for f in findings], ["not compared"])
        self.assertEqual(report.worse_findings(findings), [])
        new["comparison"] = {"baseline_commit": "abc", "findings": findings}
        text = report.markdown(new)
        self.assertIn("no figure got worse", text)
        self.assertIn("Not compared (other inputs under the same name):\n- case_a: not compared, the baseline ran "
                      "case A; this run case A, longer", text)
        failed = results({}, status="failed", cases={"case_a": dict(new["cases"]["case_a"], status="failed")})
        self.assertEqual([f["kind"] for f in report.compare(old, failed)], ["failed"])


class Markdown(unittest.TestCase):
    def test_table_with_bars_and_verdicts(self):
        r = results({
            "ate_m": figure(sync=0.135, quiet=[0.131, 0.142, 0.135], busy=[0.15],
                            bars=[{"op": "<=", "value": 0.3, "on": "quiet", "source": "SPEC"}]),
            "tracked": figure("higher", quiet=[100], bars=[{"op": ">=", "value": 150, "on": "quiet"}], digits=0,
                              unit=""),
        }, quick=True)
        text = report.markdown(r, "## Known limits\n\n- one limit\n")
        self.assertIn("`0123456789`", text)
        self.assertIn("A quick run", text)
        self.assertIn("| `case_a` | x (m) | ≤ 0.300 m (quiet) | 0.135 | 0.135 [0.131–0.142] | 0.150 | pass |", text)
        self.assertIn("**FAIL**", text)
        self.assertIn("12 min 34 s", text)
        self.assertTrue(text.rstrip().endswith("- one limit"))

    def test_every_group_has_a_section(self):
        r = results({"ate_m": figure(quiet=[0.1])})
        for name, group in (("city_a", "city"), ("odd_a", "a group without a title")):
            r["cases"][name] = dict(r["cases"]["case_a"], group=group)
        text = report.markdown(r)
        self.assertIn("## Many drives, one city map\n", text)
        self.assertIn("## a group without a title\n", text)
        self.assertIn("| `city_a` |", text)
        self.assertIn("| `odd_a` |", text)

    def test_skipped_case_says_why_and_comparison_is_listed(self):
        r = results({}, status="skipped")
        r["cases"]["case_a"]["reason"] = "no long-drive folder"
        r["comparison"] = {"baseline_commit": "abc", "findings": [
            {"kind": "worse", "text": "case_a ate_m (quiet): worse"},
            {"kind": "changed", "direction": "better", "text": "case_a ate_m (synchronous): 0.2 -> 0.1 (better)"}]}
        text = report.markdown(r)
        self.assertIn("**skipped**: no long-drive folder", text)
        self.assertIn("(commit `abc`): 1 figure(s) worse", text)
        self.assertIn("- case_a ate_m (quiet): worse", text)
        self.assertIn("not for the worse:\n- case_a ate_m (synchronous): 0.2 -> 0.1 (better)", text)
        self.assertNotIn("A quick run", text)

    def test_findings_and_changes_one_line_per_case(self):
        old = results({"ate_m": figure(sync=0.1, quiet=[0.1, 0.1], busy=[0.1]),
                       "rmse": figure(sync=0.2), "loops": figure(None, sync=1)})
        new = results({"ate_m": figure(sync=0.2, quiet=[0.2, 0.2], busy=[0.2]),
                       "rmse": figure(sync=0.1), "loops": figure(None, sync=2)})
        new["comparison"] = {"baseline_commit": "abc", "findings": report.compare(old, new)}
        lines = report.markdown(new).splitlines()
        worse = [line for line in lines if line.startswith("- case_a: ")]
        self.assertEqual(len(worse), 1)
        self.assertEqual([part.split(":")[0] for part in worse[0][len("- case_a: "):].split("; ")],
                         ["ate_m quiet", "ate_m busy", "ate_m synchronous"])
        self.assertIn("- case_a (synchronous): rmse 0.2000 -> 0.1000 m (better); loops 1.0000 -> 2.0000 m (changed)",
                      lines)

    def test_no_baseline_yet(self):
        r = results({"ate_m": figure(quiet=[0.1])})
        r["comparison"] = {"baseline": "bench/baseline.json", "baseline_commit": None, "findings": []}
        self.assertIn("No baseline yet (`bench/baseline.json` does not exist): nothing compared", report.markdown(r))
        self.assertNotIn("baseline", report.markdown(results({"ate_m": figure(quiet=[0.1])})))

    def test_stays_short(self):
        figures = {"f%d" % i: figure(quiet=[1.0, 2.0]) for i in range(10)}
        r = results(figures)
        for i in range(25):
            r["cases"]["case_%d" % i] = dict(r["cases"]["case_a"], group=("real", "synthetic", "long")[i % 3])
        self.assertLess(len(report.markdown(r).splitlines()), 400)


class Merge(unittest.TestCase):
    def test_cases_of_one_binary_make_one_table(self):
        a = results({"ate_m": figure(quiet=[0.1])}, binary_version="semslam 1 (abc)", quick=True)
        b = results({"ate_m": figure(quiet=[0.2])}, binary_version="semslam 1 (abc)", runs=3, busy_runs=3,
                    command="scripts/benchmark.py --cases kitti00")
        b["cases"] = {"case_b": dict(b["cases"]["case_a"], title="case B")}
        a["runs"], a["busy_runs"] = 2, 0
        merged = benchmark.merge_results([("a.json", a), ("b.json", b)])
        self.assertEqual(sorted(merged["cases"]), ["case_a", "case_b"])
        self.assertEqual(merged["seconds"], 2 * 754)
        self.assertEqual(merged["runs"], "2 or 3 (by command)")
        self.assertIn("kitti00", merged["command"])
        self.assertIn("case B", report.markdown(merged))
        self.assertIn("the benchmark took 25 min 08 s (by command: 12 min 34 s, 12 min 34 s)", report.markdown(merged))

    def test_merged_results_keep_every_comparison(self):
        def compared(case, text, commit="abc"):
            r = results({"ate_m": figure(quiet=[0.1])}, binary_version="semslam 1 (abc)")
            r["cases"] = {case: r["cases"]["case_a"]}
            r["comparison"] = {"baseline_commit": commit, "findings": [{"kind": "worse", "text": text}]}
            return r
        merged = benchmark.merge_results([("a.json", compared("case_a", "a worse")),
                                          ("b.json", compared("case_b", "b worse"))])
        self.assertEqual([f["text"] for f in merged["comparison"]["findings"]], ["a worse", "b worse"])
        self.assertIn("2 figure(s) worse", report.markdown(merged))
        with self.assertRaises(SystemExit):
            benchmark.merge_results([("a.json", compared("case_a", "a")), ("c.json", compared("case_c", "c", "def"))])

    def test_the_page_is_compared_anew_with_the_baseline_given(self):
        run = results({"ate_m": figure(sync=0.5, quiet=[0.5])}, binary_version="semslam 1 (abc)")
        run["comparison"] = {"baseline_commit": "old", "findings": []}  # as the run compared itself
        base = results({"ate_m": figure(sync=0.1, quiet=[0.1])}, commit={"short": "base"})
        with tempfile.TemporaryDirectory() as tmp:
            paths = {name: os.path.join(tmp, name + ".json") for name in ("run", "base")}
            for name, data in (("run", run), ("base", base)):
                with open(paths[name], "w") as f:
                    json.dump(data, f)
            page, log = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(page), contextlib.redirect_stderr(log):
                code = benchmark.main(["--markdown", paths["run"], "--baseline", paths["base"]])
            text = page.getvalue()
        self.assertEqual(code, 0)
        self.assertIn("(commit `base`): 2 figure(s) worse", text)

    def test_the_page_is_judged_by_todays_bars(self):
        run = results({"label_3d_global_pct": figure(better="higher", quiet=[90.0], unit="%"),
                       "label_3d_pct": figure(better="higher", quiet=[95.0], unit="%",
                                              bars=[{"op": ">=", "value": 93.0, "on": "quiet"}]),
                       "retired": figure(quiet=[1.0], bars=[{"op": "<=", "value": 0.5, "on": "quiet"}])})
        run["cases"] = {"town5153_mono": run["cases"]["case_a"]}
        benchmark.judge_by_todays_bars(run)
        figures = run["cases"]["town5153_mono"]["figures"]
        self.assertFalse(report.check_bar(figures["label_3d_global_pct"]))  # today's bar, the measured value
        self.assertEqual(figures["label_3d_global_pct"]["quiet"]["median"], 90.0)
        self.assertIsNone(report.check_bar(figures["label_3d_pct"]))
        self.assertFalse(report.check_bar(figures["retired"]))  # a figure no case defines keeps its own

    def test_two_binaries_or_one_case_twice_are_refused(self):
        a = results({"ate_m": figure(quiet=[0.1])}, binary_version="semslam 1 (abc)")
        other = results({"ate_m": figure(quiet=[0.1])}, binary_version="semslam 1 (def)")
        with self.assertRaises(SystemExit):
            benchmark.merge_results([("a.json", a), ("b.json", other)])
        same = results({"ate_m": figure(quiet=[0.1])}, binary_version="semslam 1 (abc)")
        with self.assertRaises(SystemExit):
            benchmark.merge_results([("a.json", a), ("c.json", same)])


class Geo(unittest.TestCase):
    # A track going east along the equator, 1 m a frame, then back west: a revisit of every place.
    TRACK = [(0.0, k / 111319.49, 0.0) for k in range(100)] + [(0.0, (99 - k) / 111319.49, 0.0) for k in range(100)]

    def landmark(self, east_m, keyframe, category="shop"):
        return {"geometry": {"coordinates": [east_m / 111319.49, 20.0 / 111319.49]},
                "properties": {"name": "L%d" % east_m, "category": category,
                               "nearest_keyframe": {"frame_index": keyframe}}}

    def test_nearest_approach_includes_the_revisit(self):
        frames, distance = bench_geo.nearest_approach_frames(self.TRACK, (20.0 / 111319.49, 30 / 111319.49))
        self.assertEqual(frames, [30, 169])
        self.assertAlmostEqual(distance, 20.0, delta=0.05)

    def test_right_nearest_keyframe(self):
        features = [self.landmark(30, 35), self.landmark(30, 165), self.landmark(30, 50),
                    self.landmark(60, 60, "corner"), self.landmark(60, None, "corner")]
        considered, right, details = bench_geo.landmarks_with_right_keyframe(features, self.TRACK)
        self.assertEqual((considered, right), (5, 3))
        self.assertEqual([d["right"] for d in details], [True, True, False, True, False])
        self.assertEqual(bench_geo.landmarks_with_right_keyframe(features, self.TRACK, category="corner")[:2], (2, 1))

    def test_localization_rows_of_maps_without_georeference(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "localization.csv")
            with open(path, "w") as f:
                f.write("frame,t,status,map,x,y,z,qx,qy,qz,qw,lat,lon,alt,heading_deg\n"
                        "1,0.1,localized,0,0,0,0,0,0,0,1,49.0,8.4,110,90\n"
                        "2,0.2,localized,1,0,0,0,0,0,0,1,,,,\n"
                        "3,0.3,localized,1,0,0,0,0,0,0,1,49.1,8.5,111,90\n"
                        "4,0.4,lost,,,,,,,,,,,,\n")
            rows, wrong = bench_geo.localization_wgs84(path, {1})
            self.assertEqual(len(rows), 2)
            self.assertEqual(wrong, 1)
            out = os.path.join(tmp, "wgs84.csv")
            bench_geo.write_wgs84_csv(out, rows)
            with open(out) as f:
                self.assertEqual(f.read().splitlines(), ["t,lat,lon,alt", "0.1,49.0,8.4,110", "0.3,49.1,8.5,111"])
            self.assertEqual(bench_geo.count_csv_rows(out), 2)

    def test_class_shares(self):
        shares = bench_geo.class_shares({"road": 60, "building": 20, "person": 10, "sky": 10, "unlabeled": 50})
        self.assertAlmostEqual(shares["street"], 0.8)
        self.assertAlmostEqual(shares["person"], 0.1)
        self.assertIsNone(bench_geo.class_shares({"unlabeled": 5}))


class LongDrive(unittest.TestCase):
    def make(self, root, files):
        for f in files:
            os.makedirs(os.path.dirname(os.path.join(root, f)), exist_ok=True)
            open(os.path.join(root, f), "w").close()

    def test_dataset_folder_with_the_maps_beside_it(self):
        # As /work/data: kitti00/dataset/{sequences/00,poses/00.txt} and osm/maps/ two levels up.
        with tempfile.TemporaryDirectory() as tmp:
            self.make(tmp, ["kitti00/dataset/sequences/00/times.txt", "kitti00/dataset/poses/00.txt",
                            "osm/maps/RTK_GPS_kitti_00.kml", "osm/maps/kitti_00.osm"])
            for folder in (os.path.join(tmp, "kitti00", "dataset"), tmp):
                found = bench_inputs.find_long_drive(folder)
                self.assertEqual(found["sequence"], os.path.join(tmp, "kitti00", "dataset", "sequences", "00"))
                self.assertEqual(found["poses"], os.path.join(tmp, "kitti00", "dataset", "poses", "00.txt"))
                self.assertEqual(found["rtk"], os.path.join(tmp, "osm", "maps", "RTK_GPS_kitti_00.kml"))
                self.assertEqual(found["osm"], os.path.join(tmp, "osm", "maps", "kitti_00.osm"))

    def test_given_files_and_what_is_missing(self):
        with tempfile.TemporaryDirectory() as tmp:
            self.make(tmp, ["d/sequences/00/times.txt", "d/poses/00.txt", "elsewhere/track.kml"])
            with self.assertRaisesRegex(bench_inputs.Skip, "kitti_00.osm"):
                bench_inputs.find_long_drive(os.path.join(tmp, "d"), kml=os.path.join(tmp, "elsewhere/track.kml"))
            self.make(tmp, ["elsewhere/x.osm"])
            found = bench_inputs.find_long_drive(os.path.join(tmp, "d"), os.path.join(tmp, "elsewhere/track.kml"),
                                                os.path.join(tmp, "elsewhere/x.osm"))
            self.assertEqual(found["rtk"], os.path.join(tmp, "elsewhere", "track.kml"))
            with self.assertRaisesRegex(bench_inputs.Skip, "KITTI 00"):
                bench_inputs.find_long_drive(os.path.join(tmp, "elsewhere"))


class CityFigures(unittest.TestCase):
    def write(self, path, content):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            json.dump(content, f)

    def test_each_drive_against_its_own_run(self):
        # Drive 1 is placed badly by the city's one alignment but keeps its shape; drive 2's shape got worse.
        with tempfile.TemporaryDirectory() as tmp:
            drives = [os.path.join(tmp, "drive1"), os.path.join(tmp, "drive2")]
            self.write(os.path.join(drives[0], "run.json"), {"ate_rmse": 0.05})
            self.write(os.path.join(drives[1], "run.json"), {"ate_rmse": 0.10})
            self.write(os.path.join(tmp, "merged", "run.json"), {
                "maps": {"count": 1, "place_merges": 1, "gps_joins": [], "sessions": [
                    {"frames": 100, "frames_in_main_map": 100, "ate_rmse": 0.05, "ate_rmse_city": 0.12},
                    {"frames": 50, "frames_in_main_map": 25, "ate_rmse": 0.13, "ate_rmse_city": 0.14}]},
                "ate_rmse_city": 0.13})
            f = bench_city.merge_figures(os.path.join(tmp, "merged"), drives)
        self.assertAlmostEqual(f["ate_ratio_max"], 2.4)
        self.assertAlmostEqual(f["shape_ratio_max"], 1.3)
        self.assertAlmostEqual(f["own_ate_max_m"], 0.10)
        self.assertAlmostEqual(f["frames_in_main_map_pct"], 125 / 150 * 100)
        self.assertEqual(f["sessions"], 2)
        self.assertIsNone(f["world_rmse_max_m"])


class Plan(unittest.TestCase):
    def test_runs_in_order_with_case_overrides(self):
        class C:
            def __init__(self, name, variants):
                self.name, self.variants = name, variants

        plan = benchmark.plan_runs([C("a", None), C("b", {"busy": 0, "quiet": None, "synchronous": 1})], 3, 2)
        self.assertEqual([(c.name, v, i) for c, v, i, _ in plan],
                         [("a", "synchronous", 0), ("a", "quiet", 0), ("a", "quiet", 1), ("a", "quiet", 2),
                          ("a", "busy", 0), ("a", "busy", 1),
                          ("b", "synchronous", 0), ("b", "quiet", 0), ("b", "quiet", 1), ("b", "quiet", 2)])

    def test_atomic_write_leaves_no_temporary_file(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "results.json")
            benchmark.write_atomically(path, json.dumps({"a": 1}))
            self.assertEqual(os.listdir(tmp), ["results.json"])


if __name__ == "__main__":
    unittest.main()
