#!/usr/bin/python3
"""Yaw rate and lateral acceleration of the KITTI drives: the figures behind the synthetic route's limits
(src/semslam/sim/route.cc). Reads ../shared/data (or the folder given) with Debian's numpy:

    /usr/bin/python3 scripts/kitti-dynamics.py [DATA_DIR]

Odometry ground truth (poses/XX.txt, camera 0, 10 Hz): the heading is that of the camera's forward axis in the
ground plane (x-z, y down), the yaw rate its change per frame, the lateral acceleration speed x yaw rate. Raw
drives: the OXTS yaw rate wz, forward speed vf and leftward acceleration al.
"""
import glob
import os
import sys

import numpy as np


def odometry(path):
    poses = np.loadtxt(path).reshape(-1, 3, 4)
    forward = poses[:, :, 2]
    yaw = np.arctan2(forward[:, 0], forward[:, 2])
    step = np.abs(np.remainder(np.diff(yaw) + np.pi, 2 * np.pi) - np.pi)  # rad per frame
    speed = np.linalg.norm(np.diff(poses[:, :, 3], axis=0), axis=1) * 10.0
    return step, step * 10.0 * speed


def main():
    data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")
    steps, laterals = [], []
    for path in sorted(glob.glob(os.path.join(data, "kitti_odom_gt_poses", "*.txt"))):
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
        records = np.array([np.loadtxt(f) for f in sorted(glob.glob(os.path.join(oxts, "*.txt")))])
        vf, al, wz = records[:, 8], records[:, 15], records[:, 19]
        print(f"raw {oxts.split(os.sep)[-3]}: {len(records)} records, yaw rate max "
              f"{np.degrees(np.abs(wz).max()):.1f} deg/s, vf x wz max {np.abs(vf * wz).max():.2f} m/s^2, "
              f"|al| max {np.abs(al).max():.2f} m/s^2, speed max {vf.max():.1f} m/s")


if __name__ == "__main__":
    main()
