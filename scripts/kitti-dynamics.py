#!/usr/bin/python3
"""Yaw rate and lateral acceleration of the KITTI drives: the figures behind the synthetic route's limits
(src/semslam/sim/route.cc). Reads ../shared/data (or the folder given) with Debian's numpy:

    /usr/bin/python3 scripts/kitti-dynamics.py [DATA_DIR]

Odometry ground truth (poses/XX.txt, camera 0, 10 Hz): the heading is that of the camera's forward axis in the
ground plane (x-z, y down), the yaw rate its change per frame, the lateral acceleration speed x yaw rate. Raw
drives: the OXTS yaw rate wz, forward speed vf and leftward acceleration al.
"""
import argparse
import glob
import os

import numpy as np


def odometry(path):
    try:
        poses = np.loadtxt(path, ndmin=2)
    except ValueError as e:
        raise SystemExit(f"kitti-dynamics: {path}: {e}")
    if poses.shape[1] != 12 or len(poses) < 2:
        raise SystemExit(f"kitti-dynamics: {path}: not KITTI poses (12 numbers a line, at least two lines)")
    poses = poses.reshape(-1, 3, 4)
    forward = poses[:, :, 2]
    yaw = np.arctan2(forward[:, 0], forward[:, 2])
    step = np.abs(np.remainder(np.diff(yaw) + np.pi, 2 * np.pi) - np.pi)  # rad per frame
    speed = np.linalg.norm(np.diff(poses[:, :, 3], axis=0), axis=1) * 10.0
    return step, step * 10.0 * speed


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    default = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")
    parser.add_argument("data", nargs="?", default=default,
                        help="the folder holding kitti_odom_gt_poses/ and kitti_raw_*/ (default ../shared/data)")
    data = parser.parse_args().data
    if not os.path.isdir(data):
        raise SystemExit(f"kitti-dynamics: {data} is not a folder")
    found = False
    steps, laterals = [], []
    for path in sorted(glob.glob(os.path.join(data, "kitti_odom_gt_poses", "*.txt"))):
        found = True
        step, lateral = odometry(path)
        steps.append(step)
        laterals.append(lateral)
        print(f"odometry {os.path.basename(path)[:2]}: yaw rate max {np.degrees(step.max()) * 10:.1f} deg/s "
              f"({np.degrees(step.max()):.2f} deg per frame, frame {step.argmax()}), "
              f"lateral acceleration max {lateral.max():.2f} m/s^2 (frame {lateral.argmax()})")
    if steps:
        step, lateral = np.concatenate(steps), np.concatenate(laterals)
        print(f"odometry 00-10: 99.9th percentile {np.degrees(np.percentile(step, 99.9)):.2f} deg per frame, "
              f"{np.percentile(lateral, 99.9):.2f} m/s^2")
    for oxts in sorted(glob.glob(os.path.join(data, "kitti_raw_*", "**", "oxts", "data"), recursive=True)):
        files = sorted(glob.glob(os.path.join(oxts, "*.txt")))
        if not files:
            continue
        found = True
        try:
            records = np.array([np.loadtxt(f) for f in files], ndmin=2)
        except ValueError as e:
            raise SystemExit(f"kitti-dynamics: {oxts}: {e}")
        if records.shape[1] < 20:
            raise SystemExit(f"kitti-dynamics: {oxts}: not OXTS records (30 numbers a file)")
        vf, al, wz = records[:, 8], records[:, 15], records[:, 19]
        print(f"raw {oxts.split(os.sep)[-3]}: {len(records)} records, yaw rate max "
              f"{np.degrees(np.abs(wz).max()):.1f} deg/s, vf x wz max {np.abs(vf * wz).max():.2f} m/s^2, "
              f"|al| max {np.abs(al).max():.2f} m/s^2, speed max {vf.max():.1f} m/s")
    # A folder without either (a wrong path) must not pass for one measured.
    if not found:
        raise SystemExit(f"kitti-dynamics: {data} holds no kitti_odom_gt_poses/*.txt and no kitti_raw_*/**/oxts/data")


if __name__ == "__main__":
    main()
