#!/usr/bin/python3
"""What a semslam run left behind, from Python: the map's points by class, its keyframes, landmarks and
topology, the trajectory's accuracy, and a second SLAM pass fed frame by frame.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/map_summary.py RUN_DIR [SEQUENCE_DIR]

RUN_DIR is a `semslam run --out` folder (e.g. out/demo/run); SEQUENCE_DIR, when given, is fed to semslam.System
for its first 50 frames (e.g. out/demo/city/sequences/00)."""

import os
import sys

import numpy as np

import semslam


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    run = sys.argv[1]
    m = semslam.load_map(os.path.join(run, "map.semslam"))
    print(f"semslam {semslam.__version__} ({semslam.commit}): {m}")

    # Points per class (labels are Cityscapes trainIds, -1 unlabeled).
    labels, counts = np.unique(m.labels, return_counts=True)
    for label, count in sorted(zip(labels, counts), key=lambda lc: -lc[1]):
        name = m.class_names[label] if label >= 0 else "unlabeled"
        print(f"  {name:14s} {count:7d} points, mean confidence {m.confidence[m.labels == label].mean():.2f}")

    # Keyframe camera centres (map frame) and the distance driven, in metres when the map is georeferenced.
    centres = m.keyframe_poses[:, :3, 3]
    length = np.linalg.norm(np.diff(centres, axis=0), axis=1).sum()
    scale = m.georeference["enu_from_map"]["scale"] if m.georeference else None
    if scale:
        print(f"{len(centres)} keyframes over {length * scale:.0f} m ({scale:.2f} m per map unit)")
    else:
        print(f"{len(centres)} keyframes over {length:.1f} map units (no georeference)")
    for landmark in m.landmarks:
        print(f"  landmark {landmark['name']}")
    if m.topology:
        print(f"topology: {len(m.topology['nodes'])} nodes, {len(m.topology['edges'])} edges")

    # Accuracy against the ground truth, as `semslam eval` computes it.
    if len(sys.argv) > 2:
        sequence = semslam.open_sequence(sys.argv[2])
        truth = sequence.ground_truth()
        stamps, poses = semslam.read_trajectory(os.path.join(run, "trajectory.tum"))
        if truth is not None:
            e = semslam.evaluate((stamps, poses), truth, align="sim3")
            print(f"ATE {e['ate_rmse']:.3f} m over {e['path_length_m']:.0f} m ({e['matched']} poses)")

        # Feed the first 50 frames to a new SLAM system.
        system = semslam.System(sequence.camera, mode="mono")
        for i in range(min(50, len(sequence))):
            result = system.process(sequence.image(i), sequence.timestamp(i))
            if i % 10 == 0:
                where = "-" if result["pose"] is None else np.array2string(result["pose"][:3, 3], precision=2)
                print(f"  frame {i:3d}: {result['state']:16s} {where}")
        system.finish()
        print("  ", system.statistics())


if __name__ == "__main__":
    main()
