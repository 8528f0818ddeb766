#!/usr/bin/python3
"""Tests of the Python module `semslam` (run by CTest with Debian's /usr/bin/python3).

Makes a small synthetic city with the semslam binary ($SEMSLAM_BIN), maps it once with `semslam run` (stereo, GPS,
landmarks, a segmenter) and once from Python through semslam.System, and checks what the module reads."""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import semslam

BIN = os.environ.get("SEMSLAM_BIN", "semslam")
FRAMES = 150  # the city turns after ~120 frames: GPS along one straight line would not fix the map's heading


def run(*args):
    result = subprocess.run([BIN, *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"semslam {' '.join(args)} failed ({result.returncode}): {result.stderr[-2000:]}")
    return result


class SemslamModuleTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        base = os.environ.get("SEMSLAM_TEST_TMP")
        if base:
            os.makedirs(base, exist_ok=True)
        cls.tmp = tempfile.mkdtemp(prefix="python_semslam_", dir=base)
        cls.data = os.path.join(cls.tmp, "city")
        cls.out = os.path.join(cls.tmp, "run")
        run("synth", "--out", cls.data, "--frames", str(FRAMES), "--seed", "1", "-q")
        cls.sequence = os.path.join(cls.data, "sequences", "00")
        run("run", "--sequence", cls.sequence, "--out", cls.out, "--mode", "stereo", "--pacing", "synchronous",
            "--gps", os.path.join(cls.data, "oxts"), "--gps-every", "10", "--landmarks",
            os.path.join(cls.data, "landmarks.csv"), "--segmenter", "truth-noisy:0.25", "-q")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_version(self):
        self.assertRegex(semslam.__version__, r"^\d+\.\d+\.\d+$")
        self.assertTrue(semslam.commit)

    def test_load_map_gives_numpy_arrays_of_the_right_shapes(self):
        m = semslam.load_map(os.path.join(self.out, "map.semslam"))
        run_json = json.load(open(os.path.join(self.out, "run.json")))
        n = m.points.shape[0]
        self.assertEqual(n, run_json["points"])
        self.assertEqual(m.points.shape, (n, 3))
        self.assertEqual(m.points.dtype, np.float64)
        self.assertEqual(m.labels.shape, (n,))
        self.assertEqual(m.confidence.shape, (n,))
        self.assertTrue(np.all(np.isfinite(m.points)))
        self.assertTrue(np.all((m.labels >= -1) & (m.labels < len(m.class_names))))
        self.assertGreater(np.count_nonzero(m.labels >= 0), n // 2)  # segmented keyframes labeled the points
        self.assertTrue(np.all((m.confidence >= 0) & (m.confidence <= 1)))
        k = m.keyframe_poses.shape[0]
        self.assertEqual(k, run_json["keyframes"])
        self.assertEqual(m.keyframe_poses.shape, (k, 4, 4))
        rotations = m.keyframe_poses[:, :3, :3]
        np.testing.assert_allclose(rotations @ rotations.transpose(0, 2, 1), np.broadcast_to(np.eye(3), (k, 3, 3)),
                                   atol=1e-9)
        np.testing.assert_allclose(m.keyframe_poses[:, 3, :], np.broadcast_to([0, 0, 0, 1], (k, 4)))
        # Keyframe poses are those of keyframes.tum.
        stamps, poses = semslam.read_trajectory(os.path.join(self.out, "keyframes.tum"))
        np.testing.assert_allclose(np.sort(m.keyframe_timestamps), stamps, atol=1e-6)
        # The camera of each map: a stereo map keeps the sequence's.
        self.assertEqual(len(m.cameras), run_json["maps"]["count"])
        for camera in m.cameras.values():
            self.assertFalse(camera["refined"])
            self.assertEqual(camera["camera"], camera["nominal"])
            self.assertGreater(camera["camera"]["fx"], 0)
        # GPS and landmarks: placed landmarks and the topological map.
        self.assertGreater(len(m.landmarks), 0)
        self.assertIn("name", m.landmarks[0])
        self.assertIsNotNone(m.topology)
        self.assertGreater(len(m.topology["nodes"]), 0)
        self.assertIn("edges", m.topology)
        self.assertIsNotNone(m.georeference)
        self.assertIn(m.georeference, list(m.georeferences.values()))

    def test_read_trajectory_and_evaluate(self):
        stamps, poses = semslam.read_trajectory(os.path.join(self.out, "trajectory.tum"))
        self.assertEqual(poses.shape, (len(stamps), 4, 4))
        kitti_stamps, kitti = semslam.read_trajectory(os.path.join(self.out, "trajectory.kitti"))
        self.assertEqual(kitti.shape, (FRAMES, 4, 4))  # one line per frame
        truth = os.path.join(self.data, "poses", "00.txt")
        times = os.path.join(self.sequence, "times.txt")
        from_files = semslam.evaluate(os.path.join(self.out, "trajectory.tum"), truth, align="se3", times=times)
        run_json = json.load(open(os.path.join(self.out, "run.json")))
        self.assertAlmostEqual(from_files["ate_rmse"], run_json["ate_rmse"], places=4)
        self.assertLess(from_files["ate_rmse"], 0.5)
        # Arrays evaluate the same as files.
        truth_stamps, truth_poses = semslam.read_trajectory(truth, times=times)
        from_arrays = semslam.evaluate((stamps, poses), (truth_stamps, truth_poses), align="se3")
        self.assertAlmostEqual(from_arrays["ate_rmse"], from_files["ate_rmse"], places=9)
        # A KITTI file with a frame missing is refused with the reason.
        with open(os.path.join(self.out, "trajectory.kitti")) as f:
            lines = f.readlines()
        short = os.path.join(self.tmp, "short.kitti")
        with open(short, "w") as f:
            f.writelines(lines[:1] + lines[2:])
        with self.assertRaisesRegex(ValueError, "one line per frame"):
            semslam.evaluate(short, truth)

    def test_system_fed_from_python_tracks_the_city(self):
        sequence = semslam.open_sequence(self.sequence)
        self.assertEqual(len(sequence), FRAMES)
        camera = sequence.camera
        self.assertIn("baseline", camera)
        system = semslam.System(camera, mode="stereo")
        states = []
        for i in range(30):
            result = system.process(sequence.image(i, 0), sequence.timestamp(i), right=sequence.image(i, 1))
            states.append(result["state"])
            if result["pose"] is not None:
                self.assertEqual(result["pose"].shape, (4, 4))
        system.finish()
        self.assertEqual(states.count("ok"), 30)
        stamps, poses = system.trajectory()
        self.assertEqual(poses.shape, (30, 4, 4))
        truth_stamps, truth_poses = sequence.ground_truth()
        errors = semslam.evaluate((stamps, poses), (truth_stamps, truth_poses), align="se3")
        self.assertLess(errors["ate_rmse"], 0.3)
        self.assertEqual(system.statistics()["frames"], 30)

    def test_bad_inputs_raise_value_error_naming_the_file(self):
        bad = os.path.join(self.tmp, "bad.tum")
        with open(bad, "w") as f:
            f.write("0 0 0 0 0 0 0 1\n1 0 0\n")
        with self.assertRaisesRegex(ValueError, "bad.tum:2"):
            semslam.read_trajectory(bad)
        with self.assertRaises(ValueError):
            semslam.load_map(bad)
        with self.assertRaises(ValueError):
            semslam.System({"width": 10}, mode="mono")
        with self.assertRaisesRegex(ValueError, "integers"):
            semslam.System({"width": 1241.5, "height": 376, "fx": "abc", "fy": 1, "cx": 1, "cy": 1})
        with self.assertRaisesRegex(ValueError, "empty path"):
            semslam.load_map("")

    def test_system_refuses_frames_it_cannot_use(self):
        sequence = semslam.open_sequence(self.sequence)
        camera = sequence.camera
        mono_camera = {k: v for k, v in camera.items() if k != "baseline"}
        with self.assertRaisesRegex(ValueError, "baseline"):
            semslam.System(mono_camera, mode="stereo")
        with self.assertRaisesRegex(ValueError, "baseline"):
            semslam.System(dict(camera, baseline=-0.5), mode="stereo")
        with self.assertRaisesRegex(ValueError, "number"):
            semslam.System(dict(camera, baseline="x"), mode="stereo")
        system = semslam.System(mono_camera, mode="mono")
        image = sequence.image(0, 0)
        with self.assertRaisesRegex(ValueError, "10 x 10 pixels, but the camera is"):
            system.process(np.zeros((10, 10), np.uint8), 0.0)
        with self.assertRaisesRegex(ValueError, "monocular"):
            system.process(image, 0.0, right=image)
        with self.assertRaisesRegex(ValueError, "finite"):
            system.process(image, float("nan"))
        system.process(image, 1.0)
        with self.assertRaisesRegex(ValueError, "does not follow"):
            system.process(image, 1.0)
        self.assertEqual(system.statistics()["frames"], 1)  # the refused frames were not counted
        with self.assertRaisesRegex(ValueError, "folder"):
            system.save_map(self.tmp)
        stereo = semslam.System(camera, mode="stereo")
        with self.assertRaisesRegex(ValueError, "right image"):
            stereo.process(image, 0.0)
        with self.assertRaisesRegex(ValueError, "right: 10 x 10"):
            stereo.process(image, 0.0, right=np.zeros((10, 10), np.uint8))

    def test_threads_sharing_a_system_take_turns(self):
        import threading
        sequence = semslam.open_sequence(self.sequence)
        camera = {k: v for k, v in sequence.camera.items() if k != "baseline"}
        system = semslam.System(camera, mode="mono")
        frames = list(range(40))
        lock = threading.Lock()  # hands out frames in order; the system serializes the calls themselves
        errors = []

        def feed():
            while True:
                with lock:
                    if not frames:
                        return
                    i = frames.pop(0)
                    image, stamp = sequence.image(i, 0), sequence.timestamp(i)
                try:
                    system.process(image, stamp)
                except ValueError as e:  # a later frame overtook this one: refused, not a crash
                    errors.append(str(e))
                system.statistics()

        threads = [threading.Thread(target=feed) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        system.finish()
        self.assertTrue(all("does not follow" in e for e in errors), errors)
        self.assertEqual(system.statistics()["frames"] + len(errors), 40)

    def test_evaluate_refuses_arrays_that_are_not_poses(self):
        stamps, poses = semslam.read_trajectory(os.path.join(self.out, "trajectory.tum"))
        with self.assertRaisesRegex(ValueError, "apply to trajectory files"):
            semslam.evaluate((stamps, poses), (stamps, poses), frames=(0, 3))
        with self.assertRaisesRegex(ValueError, "apply to trajectory files"):
            semslam.evaluate((stamps, poses), (stamps, poses), times=os.path.join(self.sequence, "times.txt"))
        bad = poses.copy()
        bad[2, :3, :3] *= 2.0
        with self.assertRaisesRegex(ValueError, r"poses\[2\].*not a rotation"):
            semslam.evaluate((stamps, bad), (stamps, poses))
        bad = poses.copy()
        bad[1, 3, 0] = 5.0
        with self.assertRaisesRegex(ValueError, r"poses\[1\].*bottom row"):
            semslam.evaluate((stamps, bad), (stamps, poses))
        bad = poses.copy()
        bad[0, 0, 3] = np.nan
        with self.assertRaisesRegex(ValueError, r"poses\[0\].*not finite"):
            semslam.evaluate((stamps, bad), (stamps, poses))


if __name__ == "__main__":
    unittest.main(verbosity=2)
