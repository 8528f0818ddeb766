#!/usr/bin/python3
"""Test of scripts/city.sbatch on a real Slurm cluster: the job starts a Dask scheduler and one worker per
Slurm task, and `python3 -m semslam.city` maps the three short synthetic drives of test_city.py through them
into one city.

The cluster is the one `sinfo` reaches (SLURM_CONF names its configuration; scripts/slurm-local.sh starts a
one-node cluster on this machine, as CI does). Without one the test is skipped, or fails where
SEMSLAM_REQUIRE_SLURM=1 says that there must be one.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

from test_city import (BIN, FRAMES, TIMEOUT_S, assert_complete_city, free_port, processes_mentioning,
                       render_drives)

SBATCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "city.sbatch")


def cluster_problem():
    """Why no Slurm cluster can take a job here, or None."""
    if shutil.which("sbatch") is None or shutil.which("sinfo") is None:
        return "no sbatch or sinfo on PATH (scripts/install-deps.sh --slurm)"
    result = subprocess.run(["sinfo", "--noheader", "--responding", "--format=%n %t"], capture_output=True,
                            text=True, timeout=60)
    if result.returncode != 0:
        return f"sinfo failed: {result.stderr.strip()} (scripts/slurm-local.sh start; export SLURM_CONF)"
    if not re.search(r"\b(idle|mix)\b", result.stdout):
        return f"no idle node: {result.stdout.strip()!r}"
    return None


class CityOnSlurmTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        problem = cluster_problem()
        if problem:
            if os.environ.get("SEMSLAM_REQUIRE_SLURM") == "1":
                raise RuntimeError(f"SEMSLAM_REQUIRE_SLURM=1, but {problem}")
            raise unittest.SkipTest(problem)
        base = os.environ.get("SEMSLAM_TEST_TMP") or tempfile.gettempdir()
        os.makedirs(base, exist_ok=True)
        cls.sequences = render_drives(base)
        cls.tmp = tempfile.mkdtemp(prefix="python_city_slurm_", dir=base)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_the_sbatch_script_maps_a_city_on_two_workers(self):
        out = os.path.join(self.tmp, "city")
        log = os.path.join(self.tmp, "job.log")
        # The job runs in its own folder: the module's path made absolute.
        python_path = os.pathsep.join(
            os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)
        env = dict(os.environ, CITY_OUT=out, CITY_DRIVES=" ".join(self.sequences), CITY_MODE="stereo",
                   CITY_PYTHON=sys.executable, CITY_DASK_PORT=str(free_port()), SEMSLAM_BIN=BIN,
                   PYTHONPATH=python_path)
        # One node, two one-core tasks: the job's two Dask workers (the options override the script's own).
        command = ["sbatch", "--wait", "--parsable", "--nodes=1", "--ntasks-per-node=2", "--cpus-per-task=1",
                   "--time=00:20:00", f"--output={log}", f"--chdir={self.tmp}", os.path.abspath(SBATCH)]
        try:
            job = subprocess.run(command, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired as e:
            printed = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
            job_id = printed.strip().split(";")[0]
            if job_id:
                subprocess.run(["scancel", job_id])
            raise
        self.assertTrue(os.path.isfile(log), f"sbatch: exit code {job.returncode}: {job.stderr}")
        with open(log, encoding="utf-8", errors="replace") as f:
            output = f.read()
        self.assertEqual(job.returncode, 0, f"{job.stderr}\n{output}")
        self.assertIn("merge city: done: 3 sessions", output)
        # One Dask worker per Slurm task, and the drives ran on them.
        registered = set(re.findall(r"Register worker <WorkerState '([^']+)'", output))
        self.assertEqual(len(registered), 2, output)
        running = set(re.findall(r"running on (\S+) \(pid", output))
        self.assertTrue(running and running <= registered, output)
        for sequence in self.sequences:
            name = os.path.basename(os.path.dirname(os.path.dirname(sequence)))
            self.assertRegex(output, rf"drive {name}: done: {FRAMES} frames")
        assert_complete_city(self, self.sequences, out, output)
        # The job leaves no scheduler file, and no scheduler or worker of it lives on.
        self.assertEqual([f for f in os.listdir(out) if f.startswith(".dask-scheduler")], [])
        self.assertEqual(processes_mentioning(out), [])


if __name__ == "__main__":
    unittest.main()
