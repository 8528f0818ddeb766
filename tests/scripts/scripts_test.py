#!/usr/bin/env python3
"""The user-facing scripts of scripts/ with bad or unusual input: unknown options, relative paths, Ctrl-C. Each
script runs against fakes (a fake semslam, fake fuzz targets, fake Slurm daemons) in a temporary folder: no build,
no SLAM run, no root, standard library only."""

import json
import os
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import textwrap
import time
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPTS = os.path.join(REPO, "scripts")


def write_executable(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(textwrap.dedent(text).lstrip())
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return path


def run(command, cwd=None, env=None, timeout=60):
    return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def processes_with(marker, settle=0.0):
    """Pids of the processes whose command line holds `marker` (a temporary folder's name); with `settle`, those
    still there after up to that many seconds (a process killed a moment ago may not be gone yet)."""
    deadline = time.monotonic() + settle
    found = _processes_with(marker)
    while found and time.monotonic() < deadline:
        time.sleep(0.05)
        found = _processes_with(marker)
    return found


def _processes_with(marker):
    found = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                if marker.encode() in f.read():
                    found.append(int(pid))
        except OSError:
            pass
    return found


def fake_checkout(tmp, *scripts):
    """A checkout holding copies of the given scripts and a scripts/build.sh, scripts/install-deps.sh that only
    note they ran (in tmp/ran-build, tmp/ran-install-deps): a script that would build does nothing harmful."""
    root = os.path.join(tmp, "checkout")
    for name in scripts:
        with open(os.path.join(SCRIPTS, name)) as f:
            write_executable(os.path.join(root, "scripts", name), f.read())
    for name in ("build", "install-deps"):
        write_executable(os.path.join(root, "scripts", name + ".sh"), """
            #!/bin/bash
            echo "$0 $*" >>"%s/ran-%s"
            """ % (tmp, name))
    return root


def fake_semslam(path, body=""):
    """A fake semslam: `synth --out DIR` makes a sequence folder; the other commands run `body` (bash)."""
    return write_executable(path, """
        #!/bin/bash
        echo "$*" >>"$0.calls"
        if [ "$1" = synth ]; then
          while [ $# -gt 0 ]; do [ "$1" = --out ] && out=$2; shift; done
          mkdir -p "$out/sequences/00/image_0" "$out/oxts" "$out/poses"
          echo "name,lat,lon" >"$out/landmarks.csv"
          exit 0
        fi
        %s
        """ % body)


def interrupt_after(command, seconds, env=None, cwd=None, ready=None, timeout=30):
    """Runs the command in a session of its own and sends SIGINT to its whole process group (as Ctrl-C in a
    terminal does) after `seconds`, or once the file `ready` exists; returns (exit code, stdout, stderr, seconds
    from the signal to the exit)."""
    p = subprocess.Popen(command, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    deadline = time.monotonic() + timeout
    time.sleep(seconds)
    while ready and not os.path.exists(ready) and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGINT)
    signalled = time.monotonic()
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        raise AssertionError("%s did not stop within %d s of SIGINT: %s" % (command[0], timeout, err))
    return p.returncode, out, err, time.monotonic() - signalled


class Fuzz(unittest.TestCase):
    """scripts/fuzz.sh with fake libFuzzer targets (FUZZ_BUILD_DIR)."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="fuzz-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.build = os.path.join(self.tmp, "targets")
        names = sorted(os.listdir(os.path.join(REPO, "fuzz", "corpus")))
        for name in names:
            # As libFuzzer: the statistics at the end; SIGINT or SIGTERM end it with exit code 72.
            write_executable(os.path.join(self.build, "fuzz_" + name), """
                #!/bin/bash
                trap 'kill $sleeper 2>/dev/null; echo "libFuzzer: run interrupted; exiting"; exit 72' INT TERM
                touch "%s/started-$(basename "$0")"
                sleep "${FAKE_FUZZ_SLEEP:-0}" & sleeper=$!
                wait $sleeper
                echo "stat::number_of_executed_units: 12"
                """ % self.tmp)
        self.env = dict(os.environ, FUZZ_BUILD_DIR=self.build, FUZZ_SECONDS="1",
                        FUZZ_ARTIFACTS=os.path.join(self.tmp, "artifacts"))

    def test_every_target_runs(self):
        r = run([os.path.join(SCRIPTS, "fuzz.sh")], env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("executions in all", r.stdout)

    def test_relative_build_folder_is_the_callers(self):
        env = dict(self.env, FUZZ_BUILD_DIR="targets", FUZZ_ARTIFACTS="artifacts")
        r = run([os.path.join(SCRIPTS, "fuzz.sh")], env=env, cwd=self.tmp)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("artifacts in %s/artifacts" % self.tmp, r.stdout)

    def test_seconds_that_would_mean_no_limit_are_refused(self):
        for seconds in ("0", "five", "-1"):
            r = run([os.path.join(SCRIPTS, "fuzz.sh")], env=dict(self.env, FUZZ_SECONDS=seconds))
            self.assertEqual(r.returncode, 2, seconds)
            self.assertIn("FUZZ_SECONDS", r.stderr)
            self.assertFalse([f for f in os.listdir(self.tmp) if f.startswith("started-")])

    def test_arguments_are_refused(self):
        r = run([os.path.join(SCRIPTS, "fuzz.sh"), "--help"], env=self.env)
        self.assertEqual(r.returncode, 2)
        self.assertIn("usage", r.stderr)

    def test_ctrl_c_stops_at_once_without_blaming_the_target(self):
        env = dict(self.env, FAKE_FUZZ_SLEEP="30")
        code, out, err, seconds = interrupt_after([os.path.join(SCRIPTS, "fuzz.sh")], 0.2, env=env,
                                                 ready=os.path.join(self.tmp, "started-fuzz_camera_yaml"))
        self.assertEqual(code, 130, err)
        self.assertIn("fuzz: interrupted", err)
        self.assertNotIn("FAILED", err)
        self.assertLess(seconds, 5)
        self.assertEqual(processes_with(self.tmp, settle=2), [])
        self.assertEqual([f for f in os.listdir(self.tmp) if f.startswith("started-")],
                         ["started-fuzz_camera_yaml"])

    def test_a_signal_to_the_script_alone_stops_its_target(self):
        env = dict(self.env, FAKE_FUZZ_SLEEP="30")
        p = subprocess.Popen([os.path.join(SCRIPTS, "fuzz.sh")], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        ready = os.path.join(self.tmp, "started-fuzz_camera_yaml")
        while not os.path.exists(ready):
            time.sleep(0.05)
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=10)
        self.assertEqual(p.returncode, 143, err)
        self.assertEqual(processes_with(self.tmp, settle=2), [])


class CheckRobustness(unittest.TestCase):
    """scripts/check-robustness.sh, a copy in a fake checkout, with a fake semslam."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="robustness-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.root = fake_checkout(self.tmp, "check-robustness.sh")
        self.script = os.path.join(self.root, "scripts", "check-robustness.sh")
        # `run` in the background takes its time and, as there, ignores the SIGINT a non-interactive shell's
        # background job inherits ignored.
        self.bin = fake_semslam(os.path.join(self.tmp, "bin", "semslam"),
                               'touch "$0.running"; exec -a "$0-run" sleep 30')
        self.env = dict(os.environ, TMPDIR=os.path.join(self.tmp, "t"))
        os.makedirs(self.env["TMPDIR"])

    def test_a_binary_given_relative_to_the_callers_folder(self):
        write_executable(self.bin, "#!/bin/bash\nexit 3\n")  # synth fails: the script stops there
        r = run([self.script, "bin/semslam"], cwd=self.tmp, env=self.env)
        self.assertIn("synth failed", r.stdout)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-build")))

    def test_a_missing_binary_given_is_an_error_not_a_build(self):
        r = run([self.script, "no/such/semslam"], cwd=self.tmp, env=self.env)
        self.assertEqual(r.returncode, 2)
        self.assertIn("no/such/semslam is not an executable semslam binary", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-build")))

    def test_options_get_the_usage(self):
        for args in (["--help"], [self.bin, "extra"]):
            r = run([self.script] + args, env=self.env)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn("usage", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-build")))

    def test_ctrl_c_leaves_no_run_and_no_folder(self):
        code, out, err, seconds = interrupt_after([self.script, self.bin], 0, env=self.env,
                                                  ready=self.bin + ".running")
        self.assertEqual(code, 130, out + err)
        self.assertIn("check-robustness: interrupted", err)
        self.assertLess(seconds, 5)
        self.assertEqual(processes_with(self.tmp, settle=2), [])
        self.assertEqual(os.listdir(self.env["TMPDIR"]), [])


def fake_cmake(tmp):
    """A PATH whose cmake "builds" build/PRESET/bin/semslam for the `--preset PRESET` it is given: a fake that
    notes its arguments in tmp/semslam-calls and exits $FAKE_SEMSLAM_EXIT (0)."""
    write_executable(os.path.join(tmp, "path", "cmake"), """
        #!/bin/bash
        echo "cmake $*" >>"%s/ran-cmake"
        while [ $# -gt 0 ]; do [ "$1" = --preset ] && preset=$2; shift; done
        mkdir -p "build/$preset/bin"
        printf '#!/bin/bash\\necho "$*" >>%s/semslam-calls\\nexit ${FAKE_SEMSLAM_EXIT:-0}\\n' \\
          >"build/$preset/bin/semslam"
        chmod +x "build/$preset/bin/semslam"
        """ % (tmp, tmp))
    return os.path.join(tmp, "path") + ":" + os.environ["PATH"]


class Demo(unittest.TestCase):
    """scripts/demo.sh in a fake checkout with a fake cmake: where its outputs go."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="demo-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.root = fake_checkout(self.tmp, "demo.sh")
        self.env = dict(os.environ, PATH=fake_cmake(self.tmp), CCACHE_DIR=os.path.join(self.tmp, "ccache"))
        self.cwd = os.path.join(self.tmp, "cwd")
        os.makedirs(self.cwd)

    def demo(self, *args):
        r = run([os.path.join(self.root, "scripts", "demo.sh")] + list(args), cwd=self.cwd, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(self.tmp, "semslam-calls")) as f:
            call = f.read().splitlines()[-1]
        return call

    def test_outputs_in_the_checkout_by_default(self):
        self.assertEqual(self.demo(), "demo --out out/demo")
        self.assertEqual(self.demo(""), "demo --out out/demo")

    def test_a_folder_given_relative_to_the_callers_folder(self):
        self.assertEqual(self.demo("my demo", "--frames", "100"), "demo --out %s/my demo --frames 100" % self.cwd)

    def test_options_alone_go_to_semslam_demo(self):
        self.assertEqual(self.demo("--frames", "100"), "demo --out out/demo --frames 100")


class Build(unittest.TestCase):
    def test_an_argument_is_refused_not_ignored(self):
        with tempfile.TemporaryDirectory() as tmp:
            root = fake_checkout(tmp)
            with open(os.path.join(SCRIPTS, "build.sh")) as f:  # the real one over the fake
                write_executable(os.path.join(root, "scripts", "build.sh"), f.read())
            r = run([os.path.join(root, "scripts", "build.sh"), "debug"], env=dict(os.environ, PATH=fake_cmake(tmp)))
            self.assertEqual(r.returncode, 2)
            self.assertIn("SEMSLAM_BUILD_PRESET", r.stderr)
            self.assertEqual(sorted(os.listdir(tmp)), ["checkout", "path"])  # no install-deps, no cmake


class Benchmark(unittest.TestCase):
    """scripts/benchmark.sh in a fake checkout: a fake cmake "builds" a fake semslam that fails every run."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="benchmark-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        names = [n for n in os.listdir(SCRIPTS) if n.startswith("bench") and n.endswith((".py", ".sh"))]
        self.root = fake_checkout(self.tmp, *names)
        self.cwd = os.path.join(self.tmp, "cwd")
        os.makedirs(self.cwd)
        # The fake semslam notes its calls and fails: every case fails at once.
        self.env = dict(os.environ, PATH=fake_cmake(self.tmp), FAKE_SEMSLAM_EXIT="1",
                        SEMSLAM_BENCH_CACHE=os.path.join(self.tmp, "cache"))
        self.script = os.path.join(self.root, "scripts", "benchmark.sh")

    def test_a_mistyped_option_costs_no_build(self):
        for args in (["--runz", "1"], ["--cases", "("], ["--runs", "0"]):
            r = run([self.script] + args, cwd=self.cwd, env=self.env)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn("error:", r.stderr)
            self.assertNotIn("Traceback", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-cmake")))
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-install-deps")))

    def test_out_relative_to_the_callers_folder(self):
        r = run([self.script, "--cases", "^demo$", "--runs", "1", "--out", "my out"], cwd=self.cwd, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(self.cwd, "my out", "results.json")) as f:
            results = json.load(f)
        self.assertEqual(results["command"], "scripts/benchmark.sh --cases \\^demo\\$ --runs 1 --out my\\ out")
        self.assertEqual(results["cases"]["demo"]["status"], "failed")
        self.assertEqual(sorted(os.listdir(self.root)), ["build", "scripts"])

    def test_markdown_of_a_results_file_relative_to_the_callers_folder(self):
        r = run([self.script, "--cases", "^demo$", "--runs", "1", "--out", "out"], cwd=self.cwd, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        r = run([self.script, "--markdown", "out/results.json"], cwd=self.cwd, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("demo", r.stdout)
        for bad, why in (("missing.json", "No such file"), ("out/results.md", "Expecting value")):
            r = run([self.script, "--markdown", bad], cwd=self.cwd, env=self.env)
            self.assertEqual(r.returncode, 1, bad)
            self.assertIn("benchmark: cannot read %s" % bad, r.stderr)
            self.assertIn(why, r.stderr)


class Soak(unittest.TestCase):
    """scripts/soak.sh (a copy in a fake checkout, with soak_report.py) with a fake semslam; soak_report.py."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="soak-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.root = fake_checkout(self.tmp, "soak.sh", "soak_report.py")
        write_executable(os.path.join(self.tmp, "bin", "semslam"), """
            #!/bin/bash
            echo "$*" >>"$0.calls"
            command=$1
            while [ $# -gt 0 ]; do
              case "$1" in --out) out=$2 ;; --frames) frames=$2 ;; esac
              shift
            done
            if [ "$command" = synth ]; then
              mkdir -p "$out/sequences/00" "$out/poses"
              seq "$frames" >"$out/sequences/00/times.txt"
              for i in $(seq "$frames"); do echo "1 0 0 $i 0 1 0 0 0 0 1 0"; done >"$out/poses/00.txt"
            else
              mkdir -p "$out"
              printf 'frame,rss_mib,keyframes,map_points\\n0,100,1,10\\n1,101.5,2,20\\n' >"$out/tracking.csv"
              echo '{"frames": 2}' >"$out/run.json"
            fi
            """)
        self.env = dict(os.environ, SEMSLAM_BIN="bin/semslam")
        self.script = os.path.join(self.root, "scripts", "soak.sh")
        self.report = os.path.join(SCRIPTS, "soak_report.py")

    def test_folders_relative_to_the_callers_folder(self):
        r = run([self.script, "3", "soak out", "plot.svg"], cwd=self.tmp, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(os.path.exists(os.path.join(self.tmp, "soak out", "run", "tracking.csv")))
        self.assertIn("plot: %s/plot.svg" % self.tmp, r.stdout)
        self.assertEqual(sorted(os.listdir(self.root)), ["scripts"])
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-build")))

    def test_bad_arguments_run_nothing(self):
        for args in (["abc"], ["0"], ["--frames", "10"], ["1", "2", "3", "4"]):
            r = run([self.script] + args, cwd=self.tmp, env=self.env)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn("usage", r.stderr)
        r = run([self.script, "3"], cwd=self.tmp, env=dict(self.env, SEMSLAM_BIN="no/semslam"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("not an executable semslam binary", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "bin", "semslam.calls")))
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "ran-build")))

    def test_report_names_the_bad_input_without_a_traceback(self):
        csv_path = os.path.join(self.tmp, "tracking.csv")
        with open(csv_path, "w") as f:
            f.write("frame,rss_mib\n0,100\nx,101\n")
        for args, expected in (([os.path.join(self.tmp, "missing.csv")], "No such file"),
                               ([csv_path], "tracking.csv:3: not a tracking.csv row"),
                               ([csv_path, "--rows", "0"], "--rows must be at least 1")):
            r = run([sys.executable, self.report] + args)
            self.assertNotEqual(r.returncode, 0, args)
            self.assertIn(expected, r.stderr)
            self.assertNotIn("Traceback", r.stderr)

    def test_report_plot_replaced_whole(self):
        csv_path = os.path.join(self.tmp, "tracking.csv")
        with open(csv_path, "w") as f:
            f.write("frame,rss_mib,keyframes,map_points\n0,0,0,0\n1,0,0,0\n")  # no memory measured: no 1/0
        svg = os.path.join(self.tmp, "out", "plot.svg")
        os.makedirs(os.path.dirname(svg))
        with open(svg, "w") as f:
            f.write("the previous plot")
        r = run([sys.executable, self.report, csv_path, "--svg", svg])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(os.listdir(os.path.dirname(svg)), ["plot.svg"])
        with open(svg) as f:
            self.assertTrue(f.read().startswith("<svg"))


class MakeVocabulary(unittest.TestCase):
    """scripts/make-vocabulary.sh (a copy in a fake checkout) with a fake semslam (--build)."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="vocabulary-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.root = fake_checkout(self.tmp, "make-vocabulary.sh")
        # The second town's render (seed 7) takes FAKE_EVAL_SECONDS and exits FAKE_EVAL_EXIT; Ctrl-C: exit 130.
        write_executable(os.path.join(self.tmp, "build", "bin", "semslam"), """
            #!/bin/bash
            echo "$*" >>"$0.calls"
            case "$*" in
              *"--seed 7"*)
                touch "$0.evaluating"
                trap 'kill $sleeper; echo "semslam: synth: interrupted by SIGINT" >&2; exit 130' INT
                sleep "${FAKE_EVAL_SECONDS:-0}" & sleeper=$!
                wait $sleeper
                exit "${FAKE_EVAL_EXIT:-0}" ;;
            esac
            """)
        self.command = [os.path.join(self.root, "scripts", "make-vocabulary.sh"), "--build", "build",
                        "--source", "procedural"]

    def test_a_failed_render_is_an_error_not_a_missing_renderer(self):
        r = run(self.command, cwd=self.tmp, env=dict(os.environ, FAKE_EVAL_EXIT="1"))
        self.assertEqual(r.returncode, 1)
        self.assertNotIn("no synthetic city renderer", r.stdout)

    def test_ctrl_c_while_evaluating(self):
        code, out, err, seconds = interrupt_after(self.command, 0, cwd=self.tmp,
                                                  env=dict(os.environ, FAKE_EVAL_SECONDS="30"),
                                                  ready=os.path.join(self.tmp, "build", "bin", "semslam.evaluating"))
        self.assertEqual(code, 130, out + err)
        self.assertIn("make-vocabulary.sh: interrupted", err)
        self.assertNotIn("no synthetic city renderer", out)
        self.assertLess(seconds, 5)

    def test_an_option_without_its_value(self):
        r = run(self.command + ["--k"], cwd=self.tmp)
        self.assertEqual(r.returncode, 2)
        self.assertIn("--k needs a value", r.stderr)
        self.assertNotIn("unbound", r.stderr)


@unittest.skipIf(subprocess.run(["/usr/bin/python3", "-c", "import numpy"], capture_output=True).returncode != 0,
                 "Debian's python3 has no NumPy (python3-numpy)")
class KittiDynamics(unittest.TestCase):
    """scripts/kitti-dynamics.py (Debian's python3 with NumPy) on folders that are not the data."""

    def kitti_dynamics(self, *args):
        return run(["/usr/bin/python3", os.path.join(SCRIPTS, "kitti-dynamics.py")] + list(args))

    def test_a_folder_without_the_data_is_an_error(self):
        with tempfile.TemporaryDirectory() as tmp:
            for folder, expected in ((os.path.join(tmp, "missing"), "is not a folder"),
                                     (tmp, "holds no kitti_odom_gt_poses")):
                r = self.kitti_dynamics(folder)
                self.assertEqual(r.returncode, 1, folder)
                self.assertIn(expected, r.stderr)
                self.assertEqual(r.stdout, "")

    def test_bad_poses_and_options(self):
        with tempfile.TemporaryDirectory() as tmp:
            os.makedirs(os.path.join(tmp, "kitti_odom_gt_poses"))
            with open(os.path.join(tmp, "kitti_odom_gt_poses", "00.txt"), "w") as f:
                f.write("1 0 0 0\n0 1 0 0\n")
            r = self.kitti_dynamics(tmp)
            self.assertEqual(r.returncode, 1)
            self.assertIn("00.txt: not KITTI poses", r.stderr)
            self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(self.kitti_dynamics("--bogus").returncode, 2)


class InstallDeps(unittest.TestCase):
    def test_without_root_or_sudo_it_says_so(self):
        with tempfile.TemporaryDirectory() as tmp:
            # Only bash and grep from the system: no sudo, whatever this machine has; not root; nothing installed.
            fake = os.path.join(tmp, "bin")
            os.makedirs(fake)
            for tool in ("bash", "grep"):
                os.symlink(subprocess.run(["bash", "-c", "command -v " + tool], capture_output=True,
                                          text=True).stdout.strip(), os.path.join(fake, tool))
            write_executable(os.path.join(fake, "id"), "#!/bin/sh\necho 1000\n")
            write_executable(os.path.join(fake, "dpkg-query"), "#!/bin/sh\nexit 1\n")
            write_executable(os.path.join(fake, "apt-get"), "#!/bin/sh\ntouch \"$(dirname \"$0\")/ran-apt\"\n")
            result = run([os.path.join(SCRIPTS, "install-deps.sh")], env={"PATH": fake})
            self.assertEqual(result.returncode, 1, result.stderr)
            self.assertIn("needs root, and there is no sudo here", result.stderr)
            self.assertFalse(os.path.exists(os.path.join(fake, "ran-apt")))


class SlurmLocal(unittest.TestCase):
    """scripts/slurm-local.sh with fake munged and Slurm daemons (perl processes whose command line is the
    daemon's), a fake sudo and `id -u` 1000: the real daemons and /run/munge are never touched."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="slurm-test-")
        self.addCleanup(lambda: subprocess.run(["rm", "-rf", self.tmp]))
        self.addCleanup(lambda: [os.kill(pid, signal.SIGKILL) for pid in processes_with(self.tmp)])
        fake = os.path.join(self.tmp, "fake")
        # A daemon: a detached perl process whose command line is "NAME ARGUMENTS" (pgrep finds it so).
        daemon = ('echo "%s $*" >>' + fake + '/calls\n'
                  'setsid perl -e \'$0 = join(" ", @ARGV); sleep 300\' %s "$@" </dev/null >/dev/null 2>&1 &\n')
        tools = {
            "id": '[ "$1" = -u ] && { echo 1000; exit 0; }; exec /usr/bin/id "$@"',
            # The /run/munge steps are the machine's: not done.
            "sudo": 'case "$*" in *" /run/munge") exit 0 ;; esac; exec "$@"',
            "runuser": 'while [ "$1" != -- ]; do shift; done; shift; exec "$@"',
            "munged": ('if [ "$1" = --stop ]; then\n'
                       '  echo "munged --stop" >>{0}/calls; kill "$(cat {0}/munged.pid)"; rm {0}/munged.pid; exit\n'
                       'fi\n'.format(fake) + daemon % ("munged", "munged " + fake) + "echo $! >%s/munged.pid" % fake),
            "munge": '[ -n "${FAKE_MUNGE_OK:-}" ] || [ -e %s/munged.pid ]' % fake,
            "unmunge": 'cat >/dev/null; [ -n "${FAKE_MUNGE_OK:-}" ] || [ -e %s/munged.pid ]' % fake,
            "slurmctld": daemon % ("slurmctld", "slurmctld"),
            "slurmd": '[ -z "${FAKE_SLURMD_DIES:-}" ] || exit 0\n' + daemon % ("slurmd", "slurmd"),
            # Idle once both daemons of $SLURM_CONF run.
            "sinfo": 'echo "sinfo $*" >>%s/calls\n'
                     '[ "$(ps -eo args | grep -cxF -e "slurmctld -f $SLURM_CONF" -e "slurmd -f $SLURM_CONF")" = 2 ] '
                     '&& echo "local up 1 idle $(hostname -s)"' % fake,
        }
        for name, body in tools.items():
            write_executable(os.path.join(fake, name), "#!/bin/bash\n" + body + "\n")
        self.fake = fake
        self.env = dict(os.environ, PATH=fake + ":" + os.environ["PATH"])
        self.script = os.path.join(SCRIPTS, "slurm-local.sh")

    def calls(self):
        with open(os.path.join(self.fake, "calls")) as f:
            return f.read()

    def test_start_and_stop_in_a_relative_folder_with_regex_characters(self):
        held = socket.socket()
        try:
            held.bind(("127.0.0.1", 6917))
            held.listen()
        except OSError:
            pass  # taken already: the script must skip it all the same
        self.addCleanup(held.close)
        r = run([self.script, "start", "slurm+1.d"], cwd=self.tmp, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        conf = os.path.join(self.tmp, "slurm+1.d", "slurm.conf")
        self.assertIn("export SLURM_CONF=%s" % conf, r.stdout)
        with open(conf) as f:
            settings = dict(line.split("=", 1) for line in f.read().splitlines())
        ports = {int(settings["SlurmctldPort"]), int(settings["SlurmdPort"])}
        self.assertEqual(len(ports), 2)
        self.assertFalse(ports & {6817, 6818, 6917}, ports)
        self.assertIn("--partition=local", self.calls())
        self.assertEqual(len(processes_with(self.tmp)), 3)  # munged, slurmctld, slurmd
        # Started again: the first daemons are found (their folder's name has a '+') and stopped first.
        r = run([self.script, "start", conf[:-len("/slurm.conf")]], env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(len(processes_with(self.tmp)), 3)
        r = run([self.script, "stop", "slurm+1.d"], cwd=self.tmp, env=self.env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(processes_with(self.tmp, settle=2), [])
        self.assertIn("munged --stop", self.calls())
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "slurm+1.d", "munged.started")))

    def test_a_running_munged_is_left_alone(self):
        env = dict(self.env, FAKE_MUNGE_OK="1")
        dir = os.path.join(self.tmp, "cluster")
        self.assertEqual(run([self.script, "start", dir], env=env).returncode, 0)
        self.assertEqual(run([self.script, "stop", dir], env=env).returncode, 0)
        self.assertNotIn("munged", self.calls())
        self.assertEqual(processes_with(self.tmp, settle=2), [])

    def test_a_daemon_that_ends_is_reported_at_once_and_nothing_is_left(self):
        start = time.monotonic()
        r = run([self.script, "start", os.path.join(self.tmp, "cluster")], env=dict(self.env, FAKE_SLURMD_DIES="1"))
        self.assertEqual(r.returncode, 1)
        self.assertIn("a daemon ended while starting", r.stderr)
        self.assertLess(time.monotonic() - start, 20)
        self.assertEqual(processes_with(self.tmp, settle=2), [])

    def test_bad_arguments(self):
        for args in (["start", os.path.join(self.tmp, "a b")], ["stop", "x", "y"], ["restart"], []):
            r = run([self.script] + args, env=self.env)
            self.assertEqual(r.returncode, 2, args)
        self.assertFalse(os.path.exists(os.path.join(self.fake, "calls")))


if __name__ == "__main__":
    unittest.main()
