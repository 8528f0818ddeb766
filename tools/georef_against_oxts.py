#!/usr/bin/env python3
"""How far a run's georeferenced trajectory (trajectory_wgs84.csv) lies from the OXTS truth of a KITTI raw drive.

Each tracked frame's camera centre in WGS84 is compared with the camera centre the OXTS reading of that frame
gives: the IMU position (lat, lon, alt) plus the IMU-to-camera lever arm (calib_imu_to_velo, calib_velo_to_cam,
R_rect_00 and the camera's P_rect offset) turned by the reading's roll, pitch and yaw, as KITTI's raw devkit
does. Both go to a local east-north-up frame at the first reading (equirectangular: the drives are a few hundred
metres). Frames are matched by time (the nearest OXTS reading).

  /usr/bin/python3 tools/georef_against_oxts.py RUN_DIR DRIVE_DIR [--camera image_02] [--gps-every 30]
                                                [--no-lever-arm]

Prints the horizontal and 3D RMSE and maximum over the matched frames, and the same over the frames whose fix
was not given to the run (every frame but each --gps-every-th).
"""
import argparse
import datetime
import math
import os
import sys

import numpy as np

EARTH_RADIUS = 6378137.0


def read_stamps(path):
    stamps = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            day, clock = line.split(' ')
            whole, _, fraction = clock.partition('.')
            t = datetime.datetime.strptime(day + ' ' + whole, '%Y-%m-%d %H:%M:%S').replace(tzinfo=datetime.timezone.utc)
            stamps.append(t.timestamp() + float('0.' + fraction) if fraction else t.timestamp())
    return np.array(stamps)


def read_calib(path):
    values = {}
    with open(path) as f:
        for line in f:
            key, _, rest = line.partition(':')
            try:
                values[key.strip()] = np.array([float(v) for v in rest.split()])
            except ValueError:
                pass
    return values


def rigid(r, t):
    m = np.eye(4)
    m[:3, :3] = np.asarray(r).reshape(3, 3)
    m[:3, 3] = t
    return m


def camera_in_imu(calib_dir, camera):
    imu_to_velo = read_calib(os.path.join(calib_dir, 'calib_imu_to_velo.txt'))
    velo_to_cam = read_calib(os.path.join(calib_dir, 'calib_velo_to_cam.txt'))
    cam_to_cam = read_calib(os.path.join(calib_dir, 'calib_cam_to_cam.txt'))
    velo_from_imu = rigid(imu_to_velo['R'], imu_to_velo['T'])
    cam0_from_velo = rigid(velo_to_cam['R'], velo_to_cam['T'])
    rect = cam_to_cam['R_rect_00'].reshape(3, 3)
    p = cam_to_cam['P_rect_0' + camera[-1]].reshape(3, 4)
    centre_rect = np.array([-p[0, 3] / p[0, 0], -p[1, 3] / p[1, 1], -p[2, 3]])
    centre_cam0 = rect.T @ centre_rect
    centre = np.linalg.inv(velo_from_imu) @ np.linalg.inv(cam0_from_velo) @ np.append(centre_cam0, 1.0)
    return centre[:3]


def enu(lat, lon, alt, origin):
    lat0, lon0, alt0 = origin
    east = np.radians(lon - lon0) * EARTH_RADIUS * math.cos(math.radians(lat0))
    north = np.radians(lat - lat0) * EARTH_RADIUS
    return np.stack([east, north, alt - alt0], axis=-1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('run')
    parser.add_argument('drive')
    parser.add_argument('--camera', default='image_02')
    parser.add_argument('--gps-every', type=int, default=30)
    parser.add_argument('--no-lever-arm', action='store_true',
                        help='compare with the IMU positions themselves (what a GPS fix says)')
    args = parser.parse_args()

    oxts_dir = os.path.join(args.drive, 'oxts', 'data')
    readings = np.array([np.loadtxt(os.path.join(oxts_dir, name))[:6] for name in sorted(os.listdir(oxts_dir))])
    oxts_t = read_stamps(os.path.join(args.drive, 'oxts', 'timestamps.txt'))
    camera_t = read_stamps(os.path.join(args.drive, args.camera, 'timestamps.txt'))
    lever = camera_in_imu(os.path.dirname(os.path.normpath(args.drive)), args.camera)
    if args.no_lever_arm:
        lever = np.zeros(3)
    origin = readings[0, :3]
    truth = []
    for lat, lon, alt, roll, pitch, yaw in readings:
        cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
        rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
        ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
        rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
        truth.append(enu(np.array(lat), np.array(lon), np.array(alt), origin) + rz @ ry @ rx @ lever)
    truth = np.array(truth)

    rows = np.loadtxt(os.path.join(args.run, 'trajectory_wgs84.csv'), delimiter=',', skiprows=1, ndmin=2)
    estimate = enu(rows[:, 1], rows[:, 2], rows[:, 3], origin)
    # Unix seconds, or (for other readers) seconds from the camera's first frame.
    stamps = rows[:, 0] if rows[0, 0] > 1e8 else camera_t[0] + rows[:, 0]
    frames = np.array([int(np.argmin(np.abs(oxts_t - t))) for t in stamps])
    error = estimate - truth[frames]
    horizontal = np.linalg.norm(error[:, :2], axis=1)
    full = np.linalg.norm(error, axis=1)
    unseen = (frames % args.gps_every) != 0

    def line(name, mask):
        if not mask.any():
            return '%s: no frames' % name
        return '%s: %d frames, horizontal RMSE %.2f m (max %.2f), 3D RMSE %.2f m (max %.2f)' % (
            name, mask.sum(), math.sqrt(np.mean(horizontal[mask] ** 2)), horizontal[mask].max(),
            math.sqrt(np.mean(full[mask] ** 2)), full[mask].max())

    print('lever arm IMU -> %s centre (IMU frame, m): %s' % (args.camera, np.round(lever, 3)))
    print(line('tracked frames', np.ones(len(frames), bool)))
    print(line('frames whose fix the run did not use', unseen))
    return 0


if __name__ == '__main__':
    sys.exit(main())
