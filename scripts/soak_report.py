#!/usr/bin/env python3
"""Resident memory against frames from a run's tracking.csv (column rss_mib): a table per 1000 frames (--rows), the growth
per 1000 frames over the second half of the run, and an SVG plot (no plotting library needed). With --truth (the
drive's KITTI poses), each 1000 frames also give their share of new ground: a map that only grows where the drive
has not been before grows its keyframes, and its memory, with that share."""
import argparse
import csv
import json
import math
import os
import sys
import tempfile


def read_rows(path):
    rows = []
    with open(path, newline="") as f:
        for number, row in enumerate(csv.DictReader(f), 2):
            if not row.get("rss_mib"):
                continue
            try:
                rows.append({
                    "frame": int(row["frame"]),
                    "rss": float(row["rss_mib"]),
                    "keyframes": int(row["keyframes"]) if row.get("keyframes") else None,
                    "points": int(row["map_points"]) if row.get("map_points") else None,
                })
            except (KeyError, TypeError, ValueError) as e:
                raise SystemExit(f"{path}:{number}: not a tracking.csv row (frame, rss_mib, keyframes, map_points): "
                                 f"{type(e).__name__} {e}")
    return rows


def read_kitti_poses(path):
    """Camera centres and viewing directions (the third column of the rotation) of a KITTI poses file."""
    centres, directions = [], []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            v = line.split()
            if not v:
                continue
            if len(v) != 12:
                raise SystemExit(f"{path}:{number}: expected 12 numbers, found {len(v)}")
            try:
                m = [float(x) for x in v]
            except ValueError as e:
                raise SystemExit(f"{path}:{number}: {e}")
            centres.append((m[3], m[7], m[11]))
            directions.append((m[2], m[6], m[10]))
    return centres, directions


def new_ground(centres, directions, radius=8.0, min_gap=300, min_cos=0.7):
    """Per frame: True unless an earlier frame (at least min_gap frames before) stood within `radius` metres,
    looking the same way (the cosine of the angle between the views at least min_cos)."""
    def cell(c):
        return math.floor(c[0] / radius), math.floor(c[2] / radius)

    def same_view(i, j):
        return (math.dist(centres[i], centres[j]) < radius
                and sum(a * b for a, b in zip(directions[i], directions[j])) > min_cos)

    cells = {}
    result = []
    for i in range(len(centres)):
        if i >= min_gap:
            cells.setdefault(cell(centres[i - min_gap]), []).append(i - min_gap)
        cx, cz = cell(centres[i])
        near = (j for dx in (-1, 0, 1) for dz in (-1, 0, 1) for j in cells.get((cx + dx, cz + dz), []))
        result.append(not any(same_view(i, j) for j in near))
    return result


def slope_per_1000(rows):
    """Least-squares slope of RSS against frame, MiB per 1000 frames."""
    n = len(rows)
    if n < 2:
        return 0.0
    mx = sum(r["frame"] for r in rows) / n
    my = sum(r["rss"] for r in rows) / n
    sxx = sum((r["frame"] - mx) ** 2 for r in rows)
    sxy = sum((r["frame"] - mx) * (r["rss"] - my) for r in rows)
    return 1000.0 * sxy / sxx if sxx > 0 else 0.0


def svg_plot(rows, path, title):
    width, height, left, right, top, bottom = 760, 360, 70, 70, 30, 50
    frames = [r["frame"] for r in rows]
    x0, x1 = min(frames), max(frames)
    rss_max = max(max(r["rss"] for r in rows), 1.0) * 1.1
    kf = [r["keyframes"] or 0 for r in rows]
    kf_max = max(max(kf), 1) * 1.1

    def sx(f):
        return left + (f - x0) / max(x1 - x0, 1) * (width - left - right)

    def sy(v, vmax):
        return height - bottom - v / vmax * (height - top - bottom)

    step = max(1, len(rows) // 1500)
    rss_line = " ".join(f"{sx(r['frame']):.1f},{sy(r['rss'], rss_max):.1f}" for r in rows[::step])
    kf_line = " ".join(f"{sx(r['frame']):.1f},{sy(k, kf_max):.1f}" for r, k in list(zip(rows, kf))[::step])
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" '
           f'font-size="12">', f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{width / 2}" y="18" text-anchor="middle" font-size="14">{title}</text>',
           f'<polyline fill="none" stroke="#1f77b4" stroke-width="1.5" points="{rss_line}"/>',
           f'<polyline fill="none" stroke="#ff7f0e" stroke-width="1" stroke-dasharray="4 2" points="{kf_line}"/>',
           f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>',
           f'<line x1="{left}" y1="{top}" x2="{left}" y2="{height - bottom}" stroke="black"/>',
           f'<line x1="{width - right}" y1="{top}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>']
    for i in range(6):
        f = x0 + (x1 - x0) * i / 5
        out.append(f'<text x="{sx(f):.1f}" y="{height - bottom + 16}" text-anchor="middle">{f:.0f}</text>')
        v = rss_max * i / 5
        out.append(f'<text x="{left - 6}" y="{sy(v, rss_max) + 4:.1f}" text-anchor="end" fill="#1f77b4">{v:.0f}</text>')
        k = kf_max * i / 5
        out.append(f'<text x="{width - right + 6}" y="{sy(k, kf_max) + 4:.1f}" fill="#ff7f0e">{k:.0f}</text>')
    out.append(f'<text x="{width / 2}" y="{height - 12}" text-anchor="middle">frame</text>')
    out.append(f'<text x="16" y="{height / 2}" transform="rotate(-90 16 {height / 2})" text-anchor="middle" '
               f'fill="#1f77b4">resident memory (MiB)</text>')
    out.append(f'<text x="{width - 14}" y="{height / 2}" transform="rotate(90 {width - 14} {height / 2})" '
               f'text-anchor="middle" fill="#ff7f0e">keyframes in the map</text>')
    out.append("</svg>")
    write_atomically(path, "\n".join(out) + "\n")


def write_atomically(path, text):
    """Written beside `path` and renamed over it: a reader (a browser reloading the plot) never sees half a file,
    and an interrupted write leaves the previous plot."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=folder)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("tracking_csv")
    parser.add_argument("--run-json")
    parser.add_argument("--svg")
    parser.add_argument("--truth", help="the drive's poses (KITTI format) for the share of new ground")
    parser.add_argument("--rows", type=int, default=1000, help="frames per table row (default 1000)")
    args = parser.parse_args()
    if args.rows < 1:
        parser.error("--rows must be at least 1")
    rows = read_rows(args.tracking_csv)
    if not rows:
        raise SystemExit(f"{args.tracking_csv}: no rss_mib column or no rows")
    fresh = new_ground(*read_kitti_poses(args.truth)) if args.truth else None
    print("frames          peak RSS MiB   keyframes   map points   new keyframes   new ground   "
          f"(at the end of each {args.rows} frames)")
    previous_keyframes = 0
    for start in range(0, rows[-1]["frame"] + 1, args.rows):
        bucket = [r for r in rows if start <= r["frame"] < start + args.rows]
        if not bucket:
            continue
        last = bucket[-1]
        keyframes = last["keyframes"] or 0
        share = ""
        if fresh is not None:
            window = fresh[start:start + args.rows]
            share = f"{100.0 * sum(window) / max(len(window), 1):9.0f} %"
        print(f"{start:5d}-{start + args.rows - 1:5d}   {max(r['rss'] for r in bucket):12.1f}   {keyframes:9d}   "
              f"{last['points'] or 0:10d}   {keyframes - previous_keyframes:13d}   {share}")
        previous_keyframes = keyframes
    half = rows[len(rows) // 2:]
    print(f"growth over the second half: {slope_per_1000(half):.1f} MiB per 1000 frames; "
          f"over the whole run: {slope_per_1000(rows):.1f}")
    if args.run_json:
        with open(args.run_json) as f:
            run = json.load(f)
        print(f"run.json: peak_rss_mib {run.get('peak_rss_mib')}, keyframes {run.get('keyframes')}, "
              f"points {run.get('points')}, loops {run.get('loops')}, tracked {run.get('tracked')}/{run.get('frames')}")
    if args.svg:
        svg_plot(rows, args.svg, f"semslam run over {rows[-1]['frame'] + 1} frames: memory and keyframes")
        print(f"plot: {args.svg}")


if __name__ == "__main__":
    try:
        main()
    except OSError as e:  # a file missing or unreadable: its name and why, not a traceback
        raise SystemExit(f"soak_report: {e}")
    except json.JSONDecodeError as e:
        raise SystemExit(f"soak_report: --run-json is not JSON: {e}")
    except KeyboardInterrupt:
        print("soak_report: interrupted", file=sys.stderr)
        sys.exit(130)
