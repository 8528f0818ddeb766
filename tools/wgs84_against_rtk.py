#!/usr/bin/env python3
"""A WGS84 trajectory (semslam's trajectory_wgs84.csv: t,lat,lon,alt of each frame's camera) against an RTK GPS
track of the same drive, the way a user sees it: horizontal and 3D errors in metres, without any alignment.

The RTK track gives the GPS unit's position; the camera sits beside it. The true camera positions come from the
drive's ground-truth camera poses placed in the world by the lever-arm-aware fit of their GPS-unit points onto
the track (one rigid transform for the whole drive): the RTK track is the truth, moved to the camera.

Usage: wgs84_against_rtk.py TRAJECTORY_WGS84.csv RTK.kml TIMES.txt POSES.txt --lever-arm X,Y,Z [--json]
  RTK.kml: one lon,lat,alt per frame (frame k = point k), as iralabdisco/ira_open_street_map's tracks;
  POSES.txt: KITTI poses (camera 0, world = first camera); --lever-arm: the GPS unit in the camera frame, metres.
"""
import argparse
import json
import math
import re
import sys

import numpy as np

A = 6378137.0
F = 1.0 / 298.257223563
E2 = F * (2 - F)


def ecef(lat, lon, alt):
    la, lo = math.radians(lat), math.radians(lon)
    n = A / math.sqrt(1 - E2 * math.sin(la) ** 2)
    return np.array([(n + alt) * math.cos(la) * math.cos(lo), (n + alt) * math.cos(la) * math.sin(lo),
                     (n * (1 - E2) + alt) * math.sin(la)])


class Enu:
    def __init__(self, lat, lon, alt):
        self.origin = ecef(lat, lon, alt)
        la, lo = math.radians(lat), math.radians(lon)
        self.r = np.array([[-math.sin(lo), math.cos(lo), 0],
                           [-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la)],
                           [math.cos(la) * math.cos(lo), math.cos(la) * math.sin(lo), math.sin(la)]])

    def __call__(self, lat, lon, alt):
        return self.r @ (ecef(lat, lon, alt) - self.origin)


def read_kml(path):
    text = open(path).read()
    points = []
    for block in re.findall(r"<coordinates>(.*?)</coordinates>", text, re.S):
        for tup in block.split():
            lon, lat, *alt = (float(v) for v in tup.split(","))
            points.append((lat, lon, alt[0] if alt else 0.0))
    return points


def rigid_fit(src, dst):
    """dst ~ R src + t (Kabsch)."""
    ms, md = src.mean(0), dst.mean(0)
    u, _, vt = np.linalg.svd((dst - md).T @ (src - ms))
    d = np.diag([1, 1, np.sign(np.linalg.det(u @ vt))])
    r = u @ d @ vt
    return r, md - r @ ms


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trajectory")
    p.add_argument("rtk")
    p.add_argument("times")
    p.add_argument("poses")
    p.add_argument("--lever-arm", default="0,0,0")
    p.add_argument("--json", action="store_true")
    a = p.parse_args()
    lever = np.array([float(v) for v in a.lever_arm.split(",")])
    times = np.loadtxt(a.times)
    poses = np.loadtxt(a.poses).reshape(-1, 3, 4)
    rtk = read_kml(a.rtk)
    n = min(len(rtk), len(poses), len(times))
    enu = Enu(*rtk[0])
    track = np.array([enu(*rtk[k]) for k in range(n)])
    # The truth's GPS-unit points onto the track: one rigid transform (gravity and heading), then the cameras.
    units = np.array([poses[k, :, :3] @ lever + poses[k, :, 3] for k in range(n)])
    r, t = rigid_fit(units, track)
    cameras = (r @ poses[:n, :, 3].T).T + t
    fit = np.linalg.norm((r @ units.T).T + t - track, axis=1)
    index = {round(float(v), 3): k for k, v in enumerate(times[:n])}
    errors, errors_h = [], []
    with open(a.trajectory) as f:
        header = f.readline()
        if not header.startswith("t,"):
            sys.exit(f"{a.trajectory}: expected a t,lat,lon,alt header")
        for line in f:
            ts, lat, lon, alt = (float(v) for v in line.split(",")[:4])
            k = index.get(round(ts, 3))
            if k is None:
                continue
            d = enu(lat, lon, alt) - cameras[k]
            errors.append(np.linalg.norm(d))
            errors_h.append(np.linalg.norm(d[:2]))
    e, eh = np.array(errors), np.array(errors_h)
    out = {"frames": int(len(e)), "track_frames": int(n), "rmse_m": float(np.sqrt((e ** 2).mean())),
           "horizontal_rmse_m": float(np.sqrt((eh ** 2).mean())), "median_m": float(np.median(e)),
           "max_m": float(e.max()), "truth_fit_rmse_m": float(np.sqrt((fit ** 2).mean()))}
    if a.json:
        print(json.dumps(out))
    else:
        print(f"{out['frames']} of {n} frames: RMSE {out['rmse_m']:.2f} m (horizontal {out['horizontal_rmse_m']:.2f} m), "
              f"median {out['median_m']:.2f} m, max {out['max_m']:.2f} m; the truth's fit to the track "
              f"{out['truth_fit_rmse_m']:.2f} m RMSE")


if __name__ == "__main__":
    main()
