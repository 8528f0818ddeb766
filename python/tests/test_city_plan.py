#!/usr/bin/python3
"""Tests of semslam.city's pure parts (no Dask, no semslam process): finding a drive's GPS log and catalogue, the
city manifest and its errors, drive names, the merge tree, the CLI's arguments, and the task helpers' folder
handling."""

import contextlib
import io
import json
import os
import shutil
import socket
import tempfile
import time
import unittest

from semslam import city, city_tasks
from semslam.city_plan import (CityInputError, Drive, check_layout, discover_drive, merge_tree, read_manifest,
                               unique_names)


def touch(path, text=""):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def semslam_output(folder, run_json="{\"status\": \"ok\"}"):
    """A folder as a semslam command leaves it: its lock file and run.json (a finished one by default)."""
    touch(os.path.join(folder, ".semslam.lock"), "pid 1, semslam run\n")
    touch(os.path.join(folder, "run.json"), run_json)
    return folder


def synthetic_city(root):
    """The layout `semslam synth --out ROOT` writes (only the parts the city command looks at)."""
    os.makedirs(os.path.join(root, "sequences", "00", "image_0"))
    os.makedirs(os.path.join(root, "oxts", "data"))
    touch(os.path.join(root, "landmarks.csv"), "name,lat,lon\n")
    return os.path.join(root, "sequences", "00")


class CityPlanTest(unittest.TestCase):
    def setUp(self):
        base = os.environ.get("SEMSLAM_TEST_TMP")
        if base:
            os.makedirs(base, exist_ok=True)
        self.tmp = tempfile.mkdtemp(prefix="python_city_plan_", dir=base)

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def path(self, *parts):
        return os.path.join(self.tmp, *parts)

    def write_manifest(self, doc, name="city.json"):
        path = self.path(name)
        touch(path, doc if isinstance(doc, str) else json.dumps(doc))
        return path

    def test_a_synthetic_drive_finds_its_gps_and_landmarks(self):
        sequence = synthetic_city(self.path("drive_a"))
        for given in (sequence, self.path("drive_a")):  # sequences/00 or the city's folder itself
            d = discover_drive(given)
            self.assertEqual(d.name, "drive_a")
            self.assertEqual(d.sequence, given)
            self.assertEqual(d.gps, self.path("drive_a", "oxts"))
            self.assertEqual(d.landmarks, self.path("drive_a", "landmarks.csv"))
        self.assertEqual(d.run_args(), ["--sequence", d.sequence, "--gps", d.gps, "--landmarks", d.landmarks])

    def test_a_kitti_raw_drive_finds_its_oxts_and_nothing_else(self):
        drive = self.path("2011_09_26", "2011_09_26_drive_0005_sync")
        os.makedirs(os.path.join(drive, "image_00", "data"))
        os.makedirs(os.path.join(drive, "oxts", "data"))
        d = discover_drive(drive)
        self.assertEqual((d.name, d.gps, d.landmarks), ("2011_09_26_drive_0005_sync", os.path.join(drive, "oxts"),
                                                         None))

    def test_a_kitti_odometry_sequence_is_named_for_its_dataset_and_number(self):
        for number in ("00", "07"):
            os.makedirs(self.path("dataset", "sequences", number, "image_0"))
        d = discover_drive(self.path("dataset", "sequences", "07"))
        self.assertEqual((d.name, d.gps, d.landmarks), ("dataset_07", None, None))

    def test_a_relative_drive_is_made_absolute_and_a_missing_one_is_an_error(self):
        synthetic_city(self.path("rel"))
        cwd = os.getcwd()
        try:
            os.chdir(self.tmp)
            self.assertEqual(discover_drive("rel").sequence, self.path("rel"))
        finally:
            os.chdir(cwd)
        with self.assertRaisesRegex(CityInputError, r"nowhere: drive not found"):
            discover_drive(self.path("nowhere"))

    def test_manifest_paths_are_relative_to_it_and_null_means_none(self):
        synthetic_city(self.path("a"))
        synthetic_city(self.path("b"))
        touch(self.path("gps", "b.csv"), "t,lat,lon\n")
        manifest = self.write_manifest({"drives": [
            {"sequence": "a/sequences/00", "name": "north", "gps": None},
            {"sequence": self.path("b"), "gps": "gps/b.csv", "landmarks": None, "gps_lever_arm": [0, -1.5, 0.25],
             "camera_height_m": 1.2},
        ]})
        a, b = read_manifest(manifest)
        self.assertEqual((a.name, a.sequence, a.gps, a.landmarks, a.named_by_hand),
                         ("north", self.path("a", "sequences", "00"), None, self.path("a", "landmarks.csv"), True))
        self.assertEqual((b.name, b.gps, b.landmarks, b.gps_lever_arm, b.named_by_hand),
                         ("b", self.path("gps", "b.csv"), None, [0.0, -1.5, 0.25], False))
        self.assertEqual(b.run_args()[-4:], ["--gps-lever-arm", "0.0,-1.5,0.25", "--camera-height", "1.2"])
        self.assertNotIn("--camera-height", a.run_args())

    def test_bad_manifests_name_the_file_and_field(self):
        synthetic_city(self.path("a"))
        cases = [
            ("{\"drives\": [", r"city\.json:1: not JSON"),
            ({"drive": []}, r"city\.json: expected an object with a non-empty list \"drives\""),
            ({"drives": []}, r"non-empty list"),
            ({"drives": ["a"]}, r"drives\[0\]: expected an object"),
            ({"drives": [{"gps": "a/oxts"}]}, r"drives\[0\]: field 'sequence' is missing"),
            ({"drives": [{"sequence": "a", "lever": 1}]}, r"drives\[0\]: unknown field 'lever'"),
            ({"drives": [{"sequence": "a"}, {"sequence": "b"}]}, r"drives\[1\]\.sequence: .*/b not found"),
            ({"drives": [{"sequence": "a", "gps": 3}]}, r"drives\[0\]\.gps: expected a path"),
            ({"drives": [{"sequence": "a", "landmarks": "x.csv"}]}, r"drives\[0\]\.landmarks: .*x\.csv not found"),
            ({"drives": [{"sequence": "a", "gps_lever_arm": [1, 2]}]}, r"gps_lever_arm: expected \[x, y, z\]"),
            ({"drives": [{"sequence": "a", "gps_lever_arm": [1, 2, "3"]}]}, r"gps_lever_arm"),
            ({"drives": [{"sequence": "a", "name": "../up"}]}, r"drives\[0\]\.name: expected letters"),
            ({"drives": [{"sequence": "a", "camera_height_m": 0}]}, r"drives\[0\]\.camera_height_m: expected a"),
            ({"drives": [{"sequence": "a", "camera_height_m": "1.65"}]}, r"camera_height_m"),
        ]
        for doc, message in cases:
            with self.subTest(doc=doc):
                with self.assertRaisesRegex(CityInputError, message):
                    read_manifest(self.write_manifest(doc))
        with self.assertRaisesRegex(CityInputError, r"missing\.json: cannot read the manifest"):
            read_manifest(self.path("missing.json"))

    def test_clashing_names_get_suffixes_unless_both_were_set_by_hand(self):
        drives = [Drive("city", "/a"), Drive("city", "/b"), Drive("city", "/c")]
        unique_names(drives)
        self.assertEqual([d.name for d in drives], ["city", "city-2", "city-3"])
        drives = [Drive("city", "/a"), Drive("city", "/b", named_by_hand=True)]
        unique_names(drives)  # the name set by hand keeps it
        self.assertEqual([d.name for d in drives], ["city-2", "city"])
        with self.assertRaisesRegex(CityInputError, r"two drives are named 'x'"):
            unique_names([Drive("x", "/a", named_by_hand=True), Drive("x", "/b", named_by_hand=True)])
        with self.assertRaisesRegex(CityInputError, r"/a/: the same drive is given twice"):
            unique_names([Drive("x", "/a"), Drive("y", "/b"), Drive("z", "/a/")])

    def test_merge_tree(self):
        self.assertEqual(merge_tree(1), [])
        self.assertEqual(merge_tree(2), [[[0, 1]]])
        self.assertEqual(merge_tree(3), [[[0, 1], [2]], [[0, 1]]])
        self.assertEqual(merge_tree(4), [[[0, 1], [2, 3]], [[0, 1]]])
        self.assertEqual(merge_tree(5), [[[0, 1], [2, 3], [4]], [[0, 1], [2]], [[0, 1]]])
        self.assertEqual(merge_tree(7, 3), [[[0, 1, 2], [3, 4], [5, 6]], [[0, 1, 2]]])
        for n in range(1, 40):
            for k in (2, 3, 4):
                levels = merge_tree(n, k)
                count = n
                for groups in levels:  # every map of a level in exactly one group, in order, at most k
                    self.assertEqual([i for g in groups for i in g], list(range(count)))
                    self.assertTrue(all(1 <= len(g) <= k for g in groups))
                    count = len(groups)
                self.assertEqual(count, 1)
                depth = 0
                while k ** depth < n:
                    depth += 1
                self.assertEqual(len(levels), depth, (n, k))
        with self.assertRaises(ValueError):
            merge_tree(0)
        with self.assertRaises(ValueError):
            merge_tree(3, 1)

    def test_cli_arguments(self):
        args = city.parse_args(["--drives", "a", "b", "--out", "o", "--mode", "stereo", "--frames", "0:50", "--",
                                "--gps-every", "10"])
        self.assertEqual(args.drives, ["a", "b"])
        self.assertEqual(city.run_args_of(args), ["--mode", "stereo", "--frames", "0:50", "--pacing", "synchronous",
                                                  "--gps-every", "10"])
        args = city.parse_args(["--drives", "a", "--out", "o", "--", "--pacing", "fast"])
        self.assertEqual(city.run_args_of(args), ["--pacing", "fast"])
        for bad in (["--out", "o"], ["--drives", "a"], ["--drives", "a", "--out", "o", "--local-workers", "0"],
                    ["--drives", "a", "--out", "o", "--scheduler", "tcp://h:1", "--local-workers", "2"]):
            with self.subTest(argv=bad), self.assertRaises(SystemExit), contextlib.redirect_stderr(io.StringIO()):
                city.parse_args(bad)

    def test_main_refuses_bad_input_before_starting_dask(self):
        synthetic_city(self.path("a"))
        touch(self.path("file"))
        fake = self.path("fake_semslam")
        touch(fake, "#!/bin/sh\nexit 0\n")
        os.chmod(fake, 0o755)
        cases = [
            (["--drives", self.path("nowhere"), "--out", self.path("o"), "--semslam", fake], "drive not found"),
            (["--drives", self.path("a"), "--out", self.path("file"), "--semslam", fake], "is not a folder"),
            (["--drives", self.path("a"), "--out", self.path("o"), "--semslam", self.path("no_binary")],
             "not found or not executable"),
            (["--manifest", self.write_manifest({"drives": {}}), "--out", self.path("o"), "--semslam", fake],
             "non-empty list"),
        ]
        for argv, message in cases:
            with self.subTest(argv=argv):
                err = io.StringIO()
                with contextlib.redirect_stderr(err):
                    code = city.main(argv)
                self.assertEqual(code, 2)
                self.assertIn(message, err.getvalue())
        if os.geteuid() != 0:  # root writes anywhere
            os.makedirs(self.path("ro"))
            os.chmod(self.path("ro"), 0o555)
            with self.assertRaisesRegex(CityInputError, "cannot write the output folder"):
                city.prepare_out(self.path("ro", "out"))

    def test_an_output_is_renamed_into_place_and_stale_partials_go(self):
        final = self.path("out", "drives", "d1")
        stale = city_tasks.partial_prefix(final) + "dead"
        touch(os.path.join(stale, "run.log"))
        partial = city_tasks.new_partial(final)
        self.assertFalse(os.path.exists(stale))
        self.assertTrue(os.path.basename(partial).startswith(".d1.partial-"))
        semslam_output(partial, "{\"status\": \"complete\", \"frames\": 3}")
        self.assertFalse(city_tasks.is_complete(final))
        city_tasks.move_into_place(partial, final)
        self.assertTrue(city_tasks.is_complete(final))
        # A newer input makes an output stale; a folder that is replaced leaves nothing beside it.
        merged = self.path("out", "city")
        semslam_output(merged)
        os.utime(os.path.join(final, "run.json"), ns=(1, 1))
        self.assertTrue(city_tasks.is_complete(merged, [final]))
        os.utime(os.path.join(merged, "run.json"), ns=(0, 0))
        self.assertFalse(city_tasks.is_complete(merged, [final]))
        again = city_tasks.new_partial(merged)
        semslam_output(again)
        city_tasks.move_into_place(again, merged)
        self.assertEqual(sorted(os.listdir(self.path("out"))), ["city", "drives"])

    def test_the_city_is_current_only_for_the_drives_it_was_made_of(self):
        out = self.path("out")
        drives = [Drive("a", "/data/a"), Drive("b", "/data/b")]
        for d in drives:
            semslam_output(os.path.join(out, "drives", d.name), "{\"status\": \"complete\", \"frames\": 5}")
            os.utime(os.path.join(out, "drives", d.name, "run.json"), ns=(1, 1))
        semslam_output(os.path.join(out, "city"))
        self.assertFalse(city.city_is_current(out, drives))  # no city.json: not known what it holds
        city.write_city_json(out, drives, {"drive a": {"frames": 5}}, {"sessions": 2})
        self.assertTrue(city.city_is_current(out, drives))
        self.assertTrue(city.city_is_current(out, drives[::-1]))
        self.assertFalse(city.city_is_current(out, drives[:1]))
        self.assertFalse(city.city_is_current(out, [Drive("a", "/data/a"), Drive("b", "/data/other")]))
        with open(os.path.join(out, "city.json")) as f:
            self.assertEqual([d["frames"] for d in json.load(f)["drives"]], [5, None])
        os.utime(os.path.join(out, "drives", "b", "run.json"))  # drive b run again: the city is older
        self.assertFalse(city.city_is_current(out, drives))

    def fake_semslam(self):
        """A stand-in for the binary that writes a run.json (recording its command) and its lock file where `run` or
        `merge` is told to (--out), counts its calls in calls.txt, and fails with exit code $FAIL_SEMSLAM when that
        is set in its environment."""
        path = self.path("fake_semslam")
        touch(path, """#!/bin/sh
echo "$1" >> "$(dirname "$0")/calls.txt"
if [ -n "$FAIL_SEMSLAM" ]; then echo "$1: error: it broke" >&2; exit "$FAIL_SEMSLAM"; fi
command="\\"$0\\""
for arg in "$@"; do command="$command, \\"$arg\\""; done
while [ $# -gt 0 ]; do [ "$1" = --out ] && out="$2"; shift; done
mkdir -p "$out" && echo "pid $$, semslam" > "$out/.semslam.lock"
echo '{"status": "ok", "frames": 7, "maps": {"count": 1, "sessions": [{}, {}]}, '\\
'"provenance": {"command": ['"$command"']}}' > "$out/run.json"
""")
        os.chmod(path, 0o755)
        return path

    def calls(self):
        with open(self.path("calls.txt")) as f:
            return f.read().split()

    def test_tasks_run_their_command_once_and_leave_no_temporary_folder(self):
        fake = self.fake_semslam()
        drives_dir = self.path("out", "drives")
        drive = Drive("d1", self.path("seq"))
        result = city_tasks.run_drive(drive, drives_dir, fake, ["--mode", "stereo"])
        self.assertEqual((result["frames"], result["reused"], result["path"]),
                         (7, False, self.path(drives_dir, "d1")))
        self.assertTrue(city_tasks.run_drive(drive, drives_dir, fake, ["--mode", "stereo"])["reused"])
        self.assertEqual(self.calls(), ["run"])
        other = city_tasks.run_drive(Drive("d0", self.path("seq0")), drives_dir, fake, [])
        inputs = [result, other["path"]]  # a task's summary or a folder
        city_dir = self.path("out", "city")
        result = city_tasks.merge_runs("city", inputs, city_dir, fake)
        self.assertEqual((result["sessions"], result["maps"], result["reused"]), (2, 1, False))
        self.assertTrue(city_tasks.merge_runs("city", inputs, city_dir, fake)["reused"])
        self.assertFalse(city_tasks.merge_runs("city", inputs, city_dir, fake, reuse=False)["reused"])
        self.assertEqual(self.calls(), ["run", "run", "merge", "merge"])
        # One map: its run folder is copied, semslam merge is not needed.
        single = city_tasks.merge_runs("single", [other], self.path("out", "single"), fake)
        self.assertEqual((single["frames"], self.calls()[-1]), (7, "merge"))
        self.assertEqual(len(self.calls()), 4)
        shutil.rmtree(self.path("out", "single"))
        os.environ["FAIL_SEMSLAM"] = "4"
        try:
            with self.assertRaisesRegex(city_tasks.CityTaskError, r"(?s)drive d2 failed \(exit code 4\).*it broke"):
                city_tasks.run_drive(Drive("d2", self.path("seq")), drives_dir, fake, [])
            with self.assertRaisesRegex(city_tasks.CityTaskError, r"(?s)merge city failed.*merge: error: it broke"):
                city_tasks.merge_runs("city", inputs, city_dir, fake, reuse=False)
        finally:
            del os.environ["FAIL_SEMSLAM"]
        self.assertEqual(sorted(os.listdir(self.path("out"))), ["city", "drives"])  # the old city stays
        self.assertEqual(sorted(os.listdir(drives_dir)), ["d0", "d1"])

    def test_a_failed_command_reports_its_stderr_tail(self):
        with self.assertRaisesRegex(city_tasks.CityTaskError, r"(?s)drive x failed \(exit code 3\).*line 30"):
            city_tasks.run_command(["sh", "-c", "for i in $(seq 1 30); do echo line $i >&2; done; exit 3"],
                                   "drive x")
        with self.assertRaisesRegex(city_tasks.CityTaskError, r"cannot start"):
            city_tasks.run_command([self.path("no_binary")], "drive x")


    def run_main(self, argv):
        """city.main(argv): (exit code, stderr)."""
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = city.main(argv)
        return code, err.getvalue()

    def test_an_out_holding_a_drive_is_refused_and_nothing_is_removed(self):
        fake = self.fake_semslam()
        out = self.path("out")
        # The drive's sequence, GPS log or catalogue in a folder the command replaces, or OUT inside the drive.
        for where in (("drives", "a"), ("city",), ("merges", "m")):
            with self.subTest(where=where):
                sequence = synthetic_city(os.path.join(out, *where))
                code, err = self.run_main(["--drives", sequence, "--out", out, "--semslam", fake])
                self.assertEqual(code, 2, err)
                self.assertRegex(err, rf"its sequence .* lies in {out}/{where[0]}, which the city command writes")
                self.assertTrue(os.path.isdir(os.path.join(sequence, "image_0")))
                shutil.rmtree(out)
        sequence = synthetic_city(self.path("b"))
        touch(os.path.join(out, "city", "gps.csv"), "t,lat,lon\n")
        manifest = self.write_manifest({"drives": [{"sequence": sequence, "gps": "out/city/gps.csv"}]})
        code, err = self.run_main(["--manifest", manifest, "--out", out, "--semslam", fake])
        self.assertEqual(code, 2, err)
        self.assertIn("its GPS log", err)
        self.assertTrue(os.path.isfile(os.path.join(out, "city", "gps.csv")))
        for inside in (self.path("b", "out"), self.path("b", "sequences", "00", "out")):
            code, err = self.run_main(["--drives", sequence, "--out", inside, "--semslam", fake])
            self.assertEqual(code, 2, err)
            self.assertIn(f"--out lies in drive b's folder {self.path('b')}", err)
            self.assertFalse(os.path.exists(inside))
        # A folder where a drive's run would go that semslam did not write: refused, and never replaced.
        touch(self.path("out2", "drives", "b", "notes.txt"), "mine")
        code, err = self.run_main(["--drives", sequence, "--out", self.path("out2"), "--semslam", fake])
        self.assertEqual(code, 2, err)
        self.assertIn("drives/b: exists and is not a semslam output", err)

    def test_only_a_folder_semslam_wrote_is_replaced(self):
        touch(self.path("out2", "drives", "b", "notes.txt"), "mine")
        partial = city_tasks.new_partial(self.path("out2", "drives", "b"))
        semslam_output(partial)
        with self.assertRaisesRegex(city_tasks.CityTaskError, r"drives/b exists and is not a semslam output"):
            city_tasks.move_into_place(partial, self.path("out2", "drives", "b"))
        self.assertTrue(os.path.isfile(self.path("out2", "drives", "b", "notes.txt")))
        semslam_output(self.path("out3", "drives", "b"), "{\"status\": \"interrupted\"}")
        city_tasks.move_into_place(partial, self.path("out3", "drives", "b"))  # semslam's own: replaced
        with open(self.path("out3", "drives", "b", "run.json")) as f:
            self.assertEqual(json.load(f), {"status": "ok"})

    def test_an_unfinished_run_is_not_complete(self):
        for status in ("interrupted", "failed", None):
            with self.subTest(status=status):
                folder = semslam_output(self.path("run", str(status)), json.dumps({"status": status, "frames": 3}))
                self.assertFalse(city_tasks.is_complete(folder))
                merged = semslam_output(self.path("merged", str(status)))
                self.assertFalse(city_tasks.is_complete(merged, [folder]))

    def test_a_run_made_with_other_arguments_is_made_again(self):
        fake = self.fake_semslam()
        drives_dir = self.path("out", "drives")
        drive = Drive("d1", synthetic_city(self.path("d1")))
        city_tasks.run_drive(drive, drives_dir, fake, ["--frames", "0:20"])
        final = os.path.join(drives_dir, "d1")
        self.assertIsNone(city_tasks.made_otherwise(final, city_tasks.drive_command(drive, ["--frames", "0:20"])))
        self.assertEqual(city_tasks.made_otherwise(final, city_tasks.drive_command(drive, ["--frames", "0:30"])),
                         "made with other arguments (had --frames 0:20; now --frames 0:30)")
        self.assertTrue(city_tasks.run_drive(drive, drives_dir, fake, ["--frames", "0:20"])["reused"])
        self.assertFalse(city_tasks.run_drive(drive, drives_dir, fake, ["--frames", "0:30"])["reused"])
        # The same name for another sequence (a manifest's names swapped): made again too.
        other = Drive("d1", synthetic_city(self.path("d2")))
        self.assertIn(f"now --sequence {other.sequence}",
                      city_tasks.made_otherwise(final, city_tasks.drive_command(other, ["--frames", "0:30"])))
        self.assertFalse(city_tasks.run_drive(other, drives_dir, fake, ["--frames", "0:30"])["reused"])
        self.assertEqual(self.calls(), ["run", "run", "run"])
        # A run.json without the command: its sequence is compared.
        touch(os.path.join(final, "run.json"), json.dumps({"status": "complete", "config": {"sequence": "/x"}}))
        self.assertEqual(city_tasks.made_otherwise(final, city_tasks.drive_command(other, [])),
                         "made from another sequence (/x)")

    def test_the_city_is_not_current_once_a_drive_is_to_be_made_again(self):
        fake = self.fake_semslam()
        drives_dir = self.path("out", "drives")
        other = Drive("d1", synthetic_city(self.path("d2")))
        city_tasks.run_drive(other, drives_dir, fake, [])
        semslam_output(self.path("out", "city"))
        city.write_city_json(self.path("out"), [other], {}, {})
        self.assertTrue(city.city_is_current(self.path("out"), [other], []))
        self.assertFalse(city.city_is_current(self.path("out"), [other], ["--mode", "stereo"]))
        self.assertRegex(city.drive_redone_because(self.path("out"), other, ["--mode", "stereo"]),
                         r"now --mode stereo")

    def test_only_a_failure_that_may_not_repeat_is_tried_again(self):
        fake = self.fake_semslam()
        for code, runs in (("1", 1), ("2", 1), ("4", 3)):  # semslam's "failed" and "bad input" would repeat
            with self.subTest(code=code):
                os.environ["FAIL_SEMSLAM"] = code
                try:
                    with self.assertRaisesRegex(city_tasks.CityTaskError, rf"exit code {code}"):
                        city_tasks.run_drive(Drive("d", self.path("seq")), self.path("out", "drives"), fake, [])
                finally:
                    del os.environ["FAIL_SEMSLAM"]
                self.assertEqual(len(self.calls()), runs)
                os.remove(self.path("calls.txt"))
                self.assertEqual(os.listdir(self.path("out", "drives")), [])

    def test_a_second_command_on_the_same_out_is_refused(self):
        sequence = synthetic_city(self.path("a"))
        fake = self.fake_semslam()
        lock = city.lock_out(self.path("out"))
        try:
            code, err = self.run_main(["--drives", sequence, "--out", self.path("out"), "--semslam", fake])
        finally:
            os.close(lock)
        self.assertEqual(code, 2, err)
        self.assertIn(f"another semslam.city command is writing into this folder (pid {os.getpid()}, "
                      "semslam.city)", err)
        os.close(city.lock_out(self.path("out")))  # free again

    def test_drives_are_checked_before_a_cluster_starts(self):
        fake = self.fake_semslam()
        os.makedirs(self.path("empty"))
        os.makedirs(self.path("root", "sequences", "no_images"))
        for n in ("00", "01"):
            os.makedirs(self.path("two", "sequences", n, "image_0"))
        os.makedirs(self.path("raw", "image_00", "data"))
        os.makedirs(self.path("odometry", "image_0"))
        touch(self.path("calib_only", "calib.txt"))
        touch(self.path("images", "camera.yaml"))
        touch(self.path("cam.yaml"))
        touch(self.path("notes.txt"))
        for good in ("raw", "odometry", "calib_only", "images", "cam.yaml", "two/sequences/01"):
            check_layout(self.path(good))
        cases = [("empty", "not a sequence folder"), ("root", "holds no sequence folder with image_0"),
                 ("two", "holds 2 sequences; give each as a drive")]
        with self.assertRaisesRegex(CityInputError, "is a file, not a sequence"):
            check_layout(self.path("notes.txt"))
        for name, message in cases:
            with self.subTest(drive=name):
                with self.assertRaisesRegex(CityInputError, message):
                    check_layout(self.path(name))
                code, err = self.run_main(["--drives", self.path(name), "--out", self.path("o"), "--semslam", fake])
                self.assertEqual(code, 2, err)
                self.assertIn(message, err)
                self.assertFalse(os.path.exists(self.path("o")))

    def test_bad_arguments_are_refused_at_once(self):
        for bad in (["--frames", "10"], ["--frames", "a:b"], ["--frames", "-1:5"], ["--frames", "20:10"],
                    ["--", "--out", "x"], ["--", "--sequence=x"], ["--", "--map-in", "m.semslam"]):
            with self.subTest(argv=bad):
                err = io.StringIO()
                with self.assertRaises(SystemExit) as exit_, contextlib.redirect_stderr(err):
                    city.parse_args(["--drives", "a", "--out", "o", *bad])
                self.assertEqual(exit_.exception.code, 2)
        for good in ("0:50", ":50", "10:", ":"):
            self.assertEqual(city.parse_args(["--drives", "a", "--out", "o", "--frames", good]).frames, good)
        # An empty path would be the current folder.
        for bad in (["--drives", "", "--out", "o"], ["--drives", "a", "--out", ""],
                    ["--manifest", "", "--out", "o"]):
            with self.subTest(argv=bad), self.assertRaises(SystemExit), contextlib.redirect_stderr(io.StringIO()):
                city.parse_args(bad)
        with self.assertRaisesRegex(CityInputError, "empty path"):
            discover_drive("")

    def test_a_bad_scheduler_address_is_reported_at_once(self):
        with socket.socket() as s:  # a port nothing listens on
            s.bind(("127.0.0.1", 0))
            closed = s.getsockname()[1]
        cases = [("garbage", "expected tcp://HOST:PORT"), ("http://localhost:8786", "expected tcp://HOST:PORT"),
                 ("tcp://localhost", "expected tcp://HOST:PORT"), ("tcp://localhost:99999", "not in 1..65535"),
                 ("tcp://no-such-host.invalid:8786", "unknown host 'no-such-host.invalid'"),
                 (f"tcp://127.0.0.1:{closed}", "cannot connect: Connection refused")]
        for address, message in cases:
            with self.subTest(address=address):
                start = time.monotonic()
                with self.assertRaisesRegex(CityInputError, message):
                    city.check_scheduler(address)
                self.assertLess(time.monotonic() - start, city.CONNECT_TIMEOUT_S)
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            s.listen()
            port = s.getsockname()[1]
            self.assertEqual(city.check_scheduler(f"127.0.0.1:{port}"), f"tcp://127.0.0.1:{port}")
        sequence = synthetic_city(self.path("a"))
        code, err = self.run_main(["--drives", sequence, "--out", self.path("o"), "--semslam", self.fake_semslam(),
                                   "--scheduler", "http://localhost:8786"])
        self.assertEqual((code, os.path.exists(self.path("o"))), (2, False), err)

    def test_an_interruption_or_failure_before_any_output_leaves_no_new_out(self):
        sequence = synthetic_city(self.path("a"))
        fake = self.fake_semslam()
        real_connect = city.connect
        try:
            for raised, code in ((KeyboardInterrupt(), 130), (city.Terminated(), 143), (OSError("refused"), 2)):
                with self.subTest(raised=type(raised).__name__):
                    def connect(*_):
                        raise raised
                    city.connect = connect
                    for out in (self.path("new"), self.path("kept")):
                        os.makedirs(self.path("kept"), exist_ok=True)
                        got, err = self.run_main(["--drives", sequence, "--out", out, "--semslam", fake])
                        self.assertEqual(got, code, err)
                        self.assertNotIn("Traceback", err)
                    self.assertFalse(os.path.exists(self.path("new")))  # made by the command: removed
                    self.assertTrue(os.path.isdir(self.path("kept")))  # there before: kept
        finally:
            city.connect = real_connect

    def test_manifests_that_are_not_text_or_too_deep_name_the_file(self):
        path = self.path("binary.json")
        with open(path, "wb") as f:
            f.write(b"\xff\xfe{\"drives\": []}")
        with self.assertRaisesRegex(CityInputError, r"binary\.json: not UTF-8 text"):
            read_manifest(path)
        deep = self.write_manifest("{\"drives\": " + "[" * 100000 + "]" * 100000 + "}", "deep.json")
        with self.assertRaisesRegex(CityInputError, r"deep\.json: nested too deeply"):
            read_manifest(deep)

    def test_a_dataset_root_and_its_only_sequence_are_the_same_drive(self):
        sequence = synthetic_city(self.path("d1"))
        with self.assertRaisesRegex(CityInputError, r"the same drive is given twice \(--drives d1 and "):
            unique_names([discover_drive(self.path("d1"), "--drives d1"), discover_drive(sequence)])
        for n in ("00", "01"):  # a KITTI odometry dataset: each sequence a drive of its own
            os.makedirs(self.path("kitti", "sequences", n, "image_0"))
        unique_names([discover_drive(self.path("kitti", "sequences", n)) for n in ("00", "01")])

    def test_clashing_names_set_by_hand_name_their_manifest_entries(self):
        synthetic_city(self.path("a"))
        synthetic_city(self.path("b"))
        manifest = self.write_manifest({"drives": [{"sequence": "a", "name": "x"}, {"sequence": "b", "name": "x"}]})
        with self.assertRaisesRegex(CityInputError, r"two drives are named 'x' \(.*city\.json: drives\[0\] and "
                                                    r".*city\.json: drives\[1\]\)"):
            unique_names(read_manifest(manifest))


if __name__ == "__main__":
    unittest.main()
