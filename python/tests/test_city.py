#!/usr/bin/python3
"""Tests of `python3 -m semslam.city` on a real Dask cluster: a scheduler and two worker processes on localhost
(`dask scheduler`, `dask worker`, as on a cluster), the semslam binary ($SEMSLAM_BIN) and three short synthetic drives
through one town (route seeds 1, 2, 3).

- the city of three drives: one session per drive, every drive's run folder complete, no temporary folder left, and
  the same command again redoes nothing;
- a worker killed while it maps a drive: the drive is run again on a worker and the city still completes;
- a drive that fails and a merge that fails: exit code 1, the command's stderr in the message, nothing half-written.
"""

import json
import os
import queue
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import distributed  # python3-distributed (scripts/install-deps.sh)

BIN = os.path.abspath(shutil.which(os.environ.get("SEMSLAM_BIN", "semslam")) or "semslam")
FRAMES = 40
ROUTE_SEEDS = (1, 2, 3)
TOWN_SEED = 1
TIMEOUT_S = 600  # a hang fails the test instead of CTest's timeout killing it without a word


def semslam(*args):
    result = subprocess.run([BIN, *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"semslam {' '.join(args)} failed ({result.returncode}): {result.stderr[-2000:]}")


def render_drives(base):
    """The three drives (`semslam synth`), rendered once into SEMSLAM_TEST_TMP under a name that holds their
    arguments; returns their sequence folders."""
    sequences = []
    for route in ROUTE_SEEDS:
        folder = os.path.join(base, f"city_drive_seed{TOWN_SEED}_route{route}_frames{FRAMES}")
        if not os.path.isfile(os.path.join(folder, "scene.json")):
            partial = folder + ".partial"
            shutil.rmtree(partial, ignore_errors=True)
            semslam("synth", "--out", partial, "--seed", str(TOWN_SEED), "--route-seed", str(route), "--frames",
                    str(FRAMES), "-q")
            shutil.rmtree(folder, ignore_errors=True)
            os.rename(partial, folder)
        sequences.append(os.path.join(folder, "sequences", "00"))
    return sequences


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def dask_command(what):
    """`dask scheduler` / `dask worker` (python3-distributed's commands), of this interpreter's installation."""
    beside = os.path.join(os.path.dirname(sys.executable), "dask")
    return [beside, what] if os.access(beside, os.X_OK) else [sys.executable, "-m", f"distributed.cli.dask_{what}"]


def read_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def partials_under(folder):
    return [os.path.join(root, d) for root, dirs, _ in os.walk(folder) for d in dirs if ".partial-" in d]


def processes_mentioning(text):
    """Pids of the processes whose command line holds `text` (the semslam run writing into a folder)."""
    pids = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if text.encode() in f.read():
                    pids.append(int(pid))
        except OSError:
            pass
    return pids


def alive(pid):
    """Whether process `pid` runs (a zombie, dead but not yet reaped, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def assert_complete_city(test, sequences, out, output):
    """The city `semslam.city` wrote into `out` from `sequences`: every drive's run complete, one session per drive,
    nothing half-written (`output`: the command's output, shown when an assertion fails)."""
    names = [os.path.basename(os.path.dirname(os.path.dirname(s))) for s in sequences]
    test.assertEqual(sorted(os.listdir(os.path.join(out, "drives"))), sorted(names), output)
    for name in names:
        run = read_json(os.path.join(out, "drives", name, "run.json"))
        test.assertEqual(run["status"], "complete")
        test.assertEqual(run["frames"], FRAMES)
        with open(os.path.join(out, "drives", name, "trajectory.kitti")) as f:
            test.assertEqual(sum(1 for line in f if line.strip()), FRAMES)
    city = read_json(os.path.join(out, "city", "run.json"))
    sessions = city["maps"]["sessions"]
    test.assertEqual(len(sessions), len(sequences), sessions)
    # A session per drive: named after its sequence folder (sequences/00), its source the folder itself.
    test.assertEqual(sorted(os.path.realpath(s["source"]) for s in sessions),
                     sorted(os.path.realpath(s) for s in sequences))
    test.assertEqual([s["name"] for s in sessions], ["00"] * len(sequences))
    test.assertTrue(os.path.isfile(os.path.join(out, "city", "map.semslam")))
    made_of = read_json(os.path.join(out, "city.json"))
    test.assertEqual(sorted(d["sequence"] for d in made_of["drives"]), sorted(sequences))
    test.assertEqual([d["frames"] for d in made_of["drives"]], [FRAMES] * len(sequences))
    test.assertEqual(partials_under(out), [])
    test.assertFalse(os.path.exists(os.path.join(out, "merges")))


class CityRun:
    """`python3 -m semslam.city` as a process whose output lines are read as they come."""

    def __init__(self, args, cwd, binary=BIN):
        self.lines = []
        self.queue = queue.Queue()
        self.process = subprocess.Popen([sys.executable, "-m", "semslam.city", *args, "--semslam", binary], cwd=cwd,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.process.stdout:
            self.queue.put(line.rstrip("\n"))
        self.queue.put(None)

    def wait_for_line(self, predicate, timeout=TIMEOUT_S):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.queue.get(timeout=1)
            except queue.Empty:
                continue
            if line is None:
                return None
            self.lines.append(line)
            if predicate(line):
                return line
        return None

    def finish(self):
        self.wait_for_line(lambda _: False)
        self.process.wait(timeout=60)
        self.process.stdout.close()
        return self.process.returncode, "\n".join(self.lines)


class CityOnDaskTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        base = os.environ.get("SEMSLAM_TEST_TMP") or tempfile.gettempdir()
        os.makedirs(base, exist_ok=True)
        cls.sequences = render_drives(base)
        cls.tmp = tempfile.mkdtemp(prefix="python_city_", dir=base)
        cls.address = f"tcp://127.0.0.1:{free_port()}"
        cls.log = log = open(os.path.join(cls.tmp, "dask.log"), "w")
        cls.processes = [subprocess.Popen(
            dask_command("scheduler") +
            ["--host", "127.0.0.1", "--port", cls.address.rsplit(":", 1)[1], "--no-dashboard"],
            cwd=cls.tmp, stdout=log, stderr=log)]
        for i in range(2):  # with their nannies, which start a worker again when it dies
            cls.processes.append(subprocess.Popen(
                dask_command("worker") +
                [cls.address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard", "--name", f"w{i}",
                 "--local-directory", cls.tmp], cwd=cls.tmp, stdout=log, stderr=log))
        cls.client = distributed.Client(cls.address, timeout=60)
        cls.client.wait_for_workers(2, timeout=120)
        cls.first = None

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        for p in reversed(cls.processes):
            p.terminate()
        for p in reversed(cls.processes):
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
        cls.log.close()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def require_merge(self):
        """The city's merges need `semslam merge`: say so plainly when the binary has none."""
        result = subprocess.run([BIN, "--help"], capture_output=True, text=True)
        self.assertTrue(re.search(r"(?m)^\s+merge\s", result.stdout), f"{BIN} has no `merge` command (--help)")

    def city(self, out, drives=None, extra=()):
        return CityRun(["--scheduler", self.address, "--drives", *(drives or self.sequences), "--out", out,
                        "--mode", "stereo", *extra], cwd=self.tmp)

    def first_city(self):
        """The city of the three drives, made once for the tests that need one."""
        if CityOnDaskTest.first is None:
            out = os.path.join(self.tmp, "city")
            code, output = self.city(out).finish()
            CityOnDaskTest.first = (out, code, output)
        return CityOnDaskTest.first

    def test_a_city_of_three_drives(self):
        self.require_merge()
        out, code, output = self.first_city()
        self.assertEqual(code, 0, output)
        assert_complete_city(self, self.sequences, out, output)
        for name in ("route1", "route2", "route3"):
            self.assertRegex(output, rf"drive city_drive_seed1_{name}_frames{FRAMES}: done: {FRAMES} frames")
        self.assertIn("merge city: done: 3 sessions", output)
        # The same command again finds everything made.
        city_mtime = os.stat(os.path.join(out, "city", "run.json")).st_mtime_ns
        code, again = self.city(out).finish()
        self.assertEqual(code, 0, again)
        self.assertEqual(again.count(": already complete"), 4, again)
        self.assertNotIn("running on", again)
        self.assertEqual(os.stat(os.path.join(out, "city", "run.json")).st_mtime_ns, city_mtime)

    def test_a_killed_worker_has_its_drive_run_again(self):
        self.require_merge()
        out = os.path.join(self.tmp, "city_killed")
        run = self.city(out)
        started = run.wait_for_line(lambda line: ": running on " in line and line.lstrip().startswith("drive "))
        self.assertIsNotNone(started, "\n".join(run.lines))
        drive = started.split(":")[0].split()[-1]
        worker, pid = started.split("running on ")[1].split(" (pid ")
        pid = int(pid.rstrip(")"))
        self.assertEqual(self.client.run(os.getpid, workers=[worker])[worker], pid)
        # Kill the worker once its semslam process writes the drive's temporary folder.
        deadline = time.monotonic() + 120
        partial = []
        while not partial and time.monotonic() < deadline:
            partial = [p for p in partials_under(os.path.join(out, "drives")) if f".{drive}.partial-" in p]
            time.sleep(0.05)
        self.assertTrue(partial, f"no temporary folder of drive {drive}")
        self.assertFalse(os.path.exists(os.path.join(out, "drives", drive)))
        orphans = processes_mentioning(partial[0])
        self.assertTrue(orphans, f"no process writes {partial[0]}")
        os.kill(pid, signal.SIGKILL)
        # The next news of the drive: it runs again (not: done, which would mean it finished before the kill).
        again = run.wait_for_line(lambda line: line.lstrip().startswith(f"drive {drive}: "))
        code, output = run.finish()
        self.assertIsNotNone(again, output)
        self.assertIn(f"drive {drive}: running on ", again)
        self.assertNotIn(f"running on {worker} ", again)  # a new worker (a new address) or the other one
        self.assertEqual(code, 0, output)
        self.assertEqual([p for p in orphans if alive(p)], [],
                         "the killed worker's semslam process lived on")
        self.assertFalse(os.path.exists(partial[0]))
        assert_complete_city(self, self.sequences, out, output)
        self.assertRegex(output, rf"drive {drive}: done: {FRAMES} frames")

    def out_with_drives_made(self, name):
        """A new OUT holding the first city's drive runs (made already: not run again)."""
        self.require_merge()
        first, code, output = self.first_city()
        self.assertEqual(code, 0, output)
        out = os.path.join(self.tmp, name)
        shutil.copytree(os.path.join(first, "drives"), os.path.join(out, "drives"))
        return out

    def test_only_the_merges_it_made_are_removed(self):
        out = self.out_with_drives_made("city_own_merges")
        mine = os.path.join(out, "merges", "mine", "notes.txt")
        os.makedirs(os.path.dirname(mine))
        with open(mine, "w") as f:
            f.write("not the city command's")
        code, output = self.city(out).finish()
        self.assertEqual(code, 0, output)
        self.assertIn("merge 1-0: done", output)
        self.assertEqual(os.listdir(os.path.join(out, "merges")), ["mine"])
        self.assertTrue(os.path.isfile(mine))

    def test_a_failing_drive_fails_the_city_with_its_error(self):
        # A folder that is no drive at all is refused before any task (exit code 2, bad input).
        empty = os.path.join(self.tmp, "not_a_drive")
        os.makedirs(empty, exist_ok=True)
        out = os.path.join(self.tmp, "city_bad_drive")
        code, output = self.city(out, drives=[empty]).finish()
        self.assertEqual(code, 2, output)
        self.assertIn("not_a_drive: not a sequence folder", output)
        self.assertFalse(os.path.exists(out))
        # One that looks like a sequence but has no images fails in semslam, once (it would fail again).
        bad = os.path.join(self.tmp, "no_images")
        os.makedirs(os.path.join(bad, "image_0"), exist_ok=True)
        code, output = self.city(out, drives=[bad]).finish()
        self.assertEqual(code, 1, output)
        self.assertRegex(output, r"drive no_images: FAILED: drive no_images failed \(exit code [12]\)")
        self.assertIn("no .png images", output)  # semslam's stderr
        self.assertNotIn("attempt 2", output)
        self.assertFalse(os.path.exists(out))  # made by the command and left empty: removed

    def test_a_failing_merge_fails_the_city_with_its_stderr(self):
        out = self.out_with_drives_made("city_bad_merge")
        broken = os.path.join(self.tmp, "broken_merge.sh")
        with open(broken, "w") as f:
            f.write(f"#!/bin/sh\nif [ \"$1\" = merge ]; then echo 'merge: error: a broken map' >&2; exit 3; fi\n"
                    f"exec {BIN} \"$@\"\n")
        os.chmod(broken, 0o755)
        run = CityRun(["--scheduler", self.address, "--drives", *self.sequences, "--out", out], self.tmp, broken)
        code, output = run.finish()
        self.assertEqual(code, 1, output)
        self.assertRegex(output, r"merge 1-0: FAILED: merge 1-0 failed \(exit code 3\)")
        self.assertIn("merge: error: a broken map", output)
        self.assertIn("merge city: not done", output)
        self.assertFalse(os.path.exists(os.path.join(out, "city")))
        self.assertEqual(partials_under(out), [])


if __name__ == "__main__":
    unittest.main()
