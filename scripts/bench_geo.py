"""Geographic figures of the benchmark, from the files a run writes and the drives' own GPS: whether a landmark's
nearest keyframe is the right one, WGS84 rows of a localization, path lengths. Pure functions of their inputs
(tests: tests/scripts/benchmark_test.py).

"The right nearest keyframe": a landmark's nearest keyframe (landmarks.geojson `nearest_keyframe.frame_index`)
is right when its frame is within RIGHT_KEYFRAME_FRAMES frames of a frame where the true track passes nearest to
the landmark. A drive may pass a place more than once (a revisit): every local minimum of the track's horizontal
distance to the landmark that comes within REVISIT_SLACK_M of the closest one counts as a nearest approach.
"""

import csv
import datetime
import json
import math
import os
import re

RIGHT_KEYFRAME_FRAMES = 10  # 1 s at KITTI's 10 Hz: keyframes come at least every 10 frames
REVISIT_SLACK_M = 5.0
EARTH_RADIUS_M = 6378137.0


def local_en(lat, lon, origin):
    """East, north in metres of (lat, lon) around origin (lat, lon): equirectangular, good over a few km."""
    lat0, lon0 = origin
    return (math.radians(lon - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0)),
            math.radians(lat - lat0) * EARTH_RADIUS_M)


def read_kml_track(path):
    """(lat, lon, alt) of every `lon,lat[,alt]` tuple of the KML's <coordinates> (frame k = point k)."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    points = []
    for block in re.findall(r"<coordinates>(.*?)</coordinates>", text, re.S):
        for item in block.split():
            values = [float(v) for v in item.split(",")]
            points.append((values[1], values[0], values[2] if len(values) > 2 else 0.0))
    return points


def read_oxts_track(drive):
    """(lat, lon, alt) of each OXTS record of a KITTI raw drive (record k = frame k of the synced drive)."""
    folder = os.path.join(drive, "oxts", "data")
    track = []
    for name in sorted(os.listdir(folder)):
        if name.endswith(".txt"):
            with open(os.path.join(folder, name)) as f:
                values = f.read().split()
            track.append((float(values[0]), float(values[1]), float(values[2])))
    return track


def nearest_approach_frames(track, point, slack_m=REVISIT_SLACK_M):
    """Frames where the track (list of (lat, lon, ...)) passes nearest to point (lat, lon): the local minima of
    the horizontal distance within slack_m of the smallest one."""
    if not track:
        return [], math.inf
    origin = (point[0], point[1])
    d = [math.hypot(*local_en(p[0], p[1], origin)) for p in track]
    best = min(d)
    frames = []
    for k, dk in enumerate(d):
        left = d[k - 1] if k > 0 else math.inf
        right = d[k + 1] if k + 1 < len(d) else math.inf
        if dk <= left and dk <= right and dk <= best + slack_m:
            frames.append(k)
    return frames, best


def landmarks_with_right_keyframe(features, track, category=None, frames=RIGHT_KEYFRAME_FRAMES,
                                  slack_m=REVISIT_SLACK_M):
    """(landmarks considered, with the right nearest keyframe, details) for landmarks.geojson features.

    category: only features of that category (e.g. 'corner'); None: all. A feature without a nearest keyframe
    counts as not right.
    """
    considered, right, details = 0, 0, []
    for feature in features:
        props = feature.get("properties", {})
        if category is not None and props.get("category") != category:
            continue
        lon, lat = feature["geometry"]["coordinates"][:2]
        approach, distance = nearest_approach_frames(track, (lat, lon), slack_m)
        keyframe = (props.get("nearest_keyframe") or {}).get("frame_index")
        ok = keyframe is not None and any(abs(int(keyframe) - k) <= frames for k in approach)
        considered += 1
        right += 1 if ok else 0
        details.append({"name": props.get("name"), "keyframe_frame": keyframe, "nearest_approach": approach,
                        "track_distance_m": distance, "right": ok})
    return considered, right, details


def read_geojson_features(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f).get("features", [])


def localization_wgs84(localization_csv, unreferenced_maps):
    """Rows (t, lat, lon, alt) of a localization.csv with a WGS84 position, and how many such rows are of a map
    in `unreferenced_maps` (a map without a georeference must never give one)."""
    rows, wrong = [], 0
    with open(localization_csv, newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            if not row.get("lat"):
                continue
            rows.append((row["t"], row["lat"], row["lon"], row.get("alt") or "0"))
            if row.get("map") not in (None, "") and int(row["map"]) in unreferenced_maps:
                wrong += 1
    return rows, wrong


def write_wgs84_csv(path, rows):
    """A trajectory_wgs84.csv-style file (t,lat,lon,alt), as tools/wgs84_against_rtk.py reads it."""
    with open(path, "w", encoding="utf-8") as f:
        f.write("t,lat,lon,alt\n")
        for row in rows:
            f.write(",".join(str(v) for v in row) + "\n")


def count_csv_rows(path):
    with open(path, encoding="utf-8") as f:
        return max(0, sum(1 for line in f if line.strip()) - 1)


def tum_path_length(path):
    """Length in trajectory units of a TUM trajectory (sum of the steps between consecutive camera centres)."""
    centres = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                v = line.split()
                centres.append((float(v[1]), float(v[2]), float(v[3])))
    return sum(math.dist(a, b) for a, b in zip(centres, centres[1:]))


def read_kitti_raw_stamps(path):
    """Seconds since the epoch of each line of a KITTI raw timestamps.txt."""
    stamps = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            day, clock = line.replace("T", " ").split(" ")
            whole, _, fraction = clock.partition(".")
            t = datetime.datetime.strptime(day + " " + whole, "%Y-%m-%d %H:%M:%S").replace(
                tzinfo=datetime.timezone.utc).timestamp()
            stamps.append(t + (float("0." + fraction) if fraction else 0.0))
    return stamps


def oxts_forward_distance(drive, first, end):
    """Distance driven from frame `first` to frame `end - 1` by the OXTS forward speed `vf` (trapezoid rule over
    the records' times): KITTI's devkit positions are good to decimetres only, the speed to centimetres."""
    folder = os.path.join(drive, "oxts", "data")
    names = sorted(n for n in os.listdir(folder) if n.endswith(".txt"))[first:end]
    speeds = []
    for name in names:
        with open(os.path.join(folder, name)) as f:
            speeds.append(float(f.read().split()[8]))
    stamps = read_kitti_raw_stamps(os.path.join(drive, "oxts", "timestamps.txt"))[first:end]
    return sum(0.5 * (speeds[i] + speeds[i + 1]) * (stamps[i + 1] - stamps[i]) for i in range(len(speeds) - 1))


def class_shares(classes):
    """Shares (0..1) of the map points of run.json `classes`: street classes, person, sky (labelled points)."""
    street = ("road", "sidewalk", "building", "vegetation", "terrain", "car")
    labelled = sum(n for k, n in classes.items() if k != "unlabeled")
    if labelled == 0:
        return None
    return {"street": sum(classes.get(k, 0) for k in street) / labelled,
            "person": classes.get("person", 0) / labelled,
            "sky": classes.get("sky", 0) / labelled}
