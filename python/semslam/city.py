"""Many drives, one city map, on Dask distributed: `python3 -m semslam.city --drives D1 D2 ... --out DIR`.

Each drive is one Dask task that runs `semslam run` into DIR/drives/<name>/; the run folders are then merged in a
tree of `semslam merge` tasks (groups of up to --merge-group maps, the outputs merged again) until one map remains,
DIR/city/ (a run folder as `semslam merge` writes it). Intermediate merges go to DIR/merges/ and are removed once the
city is done. Every output is written to a temporary folder and renamed into place when its command succeeded; an
output already there is not made again, so running the same command after a crash or Ctrl-C resumes. Dask runs a
task again when its worker dies. See README.md ("Many drives, one city map") and docs/formats.md (city manifest)."""

import argparse
import glob
import hashlib
import json
import os
import queue
import shutil
import sys
import time
import uuid
from typing import Dict, List, Optional, Sequence

from . import city_tasks
from .city_plan import CityInputError, Drive, discover_drive, merge_tree, read_manifest, unique_names

RETRIES = 2  # a task that raises (a command that failed) is tried this many more times


def _split_extra(argv: Sequence[str]):
    argv = list(argv)
    if "--" in argv:
        i = argv.index("--")
        return argv[:i], argv[i + 1:]
    return argv, []


def parse_args(argv: Sequence[str]) -> argparse.Namespace:
    own, extra = _split_extra(argv)
    p = argparse.ArgumentParser(
        prog="python3 -m semslam.city",
        description="Map many drives on a Dask cluster (one `semslam run` task per drive) and merge their maps "
                    "into one city map (a tree of `semslam merge` tasks). Arguments after `--` are passed to every "
                    "`semslam run`.")
    p.add_argument("--drives", nargs="+", default=[], metavar="SEQUENCE",
                   help="sequence folders, as `semslam run --sequence` takes them; GPS (ROOT/oxts) and landmarks "
                        "(ROOT/landmarks.csv|.geojson) are found beside the synthetic city's sequences/NN and in a "
                        "KITTI raw drive")
    p.add_argument("--manifest", help="JSON file listing drives with their GPS log and catalogue (docs/formats.md)")
    p.add_argument("--out", required=True, help="output folder: drives/<name>/, city/ (the merged run folder)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDR", help="a running Dask scheduler, e.g. tcp://HOST:8786")
    where.add_argument("--local-workers", type=int, metavar="N",
                       help="a local cluster of N worker processes (default: one per 3 cores, at most one per "
                            "drive)")
    p.add_argument("--mode", choices=["mono", "stereo"], help="sensor mode of every run (default: run's)")
    p.add_argument("--frames", metavar="A:B", help="frames A..B-1 of every drive")
    p.add_argument("--semslam", metavar="BIN", help="the semslam binary (default: $SEMSLAM_BIN, else on PATH)")
    p.add_argument("--merge-group", type=int, default=2, metavar="K", help="maps merged per merge task (default 2)")
    args = p.parse_args(own)
    args.run_args = extra
    if not args.drives and not args.manifest:
        p.error("give drives: --drives and/or --manifest")
    if args.local_workers is not None and args.local_workers < 1:
        p.error("--local-workers: at least 1")
    if args.merge_group < 2:
        p.error("--merge-group: at least 2")
    return args


def find_semslam(explicit: Optional[str]) -> str:
    candidate = explicit or os.environ.get("SEMSLAM_BIN") or "semslam"
    found = shutil.which(candidate)
    if found is None:
        source = "--semslam" if explicit else "$SEMSLAM_BIN" if os.environ.get("SEMSLAM_BIN") else "PATH"
        raise CityInputError(f"semslam binary '{candidate}' (from {source}) not found or not executable; pass "
                             "--semslam BIN or set SEMSLAM_BIN")
    return os.path.abspath(found)


def prepare_out(out: str) -> str:
    out = os.path.abspath(out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise CityInputError(f"{out}: --out exists and is not a folder")
    try:
        os.makedirs(os.path.join(out, "drives"), exist_ok=True)
        probe = os.path.join(out, f".write-test-{uuid.uuid4().hex[:8]}")
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as e:
        raise CityInputError(f"{out}: cannot write the output folder: {e.strerror}") from None
    return out


def collect_drives(args) -> List[Drive]:
    drives = [discover_drive(d) for d in args.drives]
    if args.manifest:
        drives += read_manifest(args.manifest)
    unique_names(drives)
    return drives


def run_args_of(args) -> List[str]:
    extra = list(args.run_args)
    run_args = []
    if args.mode:
        run_args += ["--mode", args.mode]
    if args.frames:
        run_args += ["--frames", args.frames]
    if "--pacing" not in extra:  # a batch of drives: every frame as soon as mapping allows, reproducibly
        run_args += ["--pacing", "synchronous"]
    return run_args + extra


def _describe(result: dict) -> str:
    parts = []
    if result.get("frames") is not None:
        parts.append(f"{result['frames']} frames")
    if isinstance(result.get("ate_rmse"), (int, float)) and result["ate_rmse"] >= 0:
        parts.append(f"ATE {result['ate_rmse']:.3f} m")
    if result.get("kind") == "merge" and result.get("sessions") is not None:
        n, maps = result["sessions"], result.get("maps")
        # Sessions no place or GPS tied together stay separate maps of the city's atlas.
        parts.append(f"{n} session{'' if n == 1 else 's'}" + (f" in {maps} map{'' if maps == 1 else 's'}"
                                                               if isinstance(maps, int) else ""))
    if isinstance(result.get("seconds"), (int, float)):
        parts.append(f"{result['seconds']:.1f} s")
    return ", ".join(parts)


class Progress:
    """Progress lines: one per drive and merge as it is queued, starts (on which worker) and ends."""

    def __init__(self, stream=sys.stdout):
        self.stream = stream
        self.events: "queue.Queue[dict]" = queue.Queue()
        self.ended = set()  # labels reported done or failed: a late start event of theirs is not news
        self.starts = {}  # label -> how many times it started (a task is run again when its worker died or it failed)

    def line(self, text: str) -> None:
        print(text, file=self.stream, flush=True)

    def on_event(self, event) -> None:  # called by the Dask client's thread
        _, msg = event
        self.events.put(msg)

    def drain(self, labels: Dict[str, str]) -> None:
        while True:
            try:
                msg = self.events.get_nowait()
            except queue.Empty:
                return
            label = f"{msg.get('kind')} {msg.get('name')}"
            if label in labels.values() and label not in self.ended:
                n = self.starts[label] = self.starts.get(label, 0) + 1
                again = f", attempt {n}" if n > 1 else ""
                self.line(f"  {label}: running on {msg.get('worker')} (pid {msg.get('pid')}{again})")


def build_graph(client, drives: List[Drive], out: str, semslam: str, run_args: List[str], group: int, token: str):
    """Submits the drive tasks and the merge tree; returns (labels by key, all futures, the city's future)."""
    labels, futures = {}, []
    level = []
    for d in drives:
        f = client.submit(city_tasks.run_drive, d, os.path.join(out, "drives"), semslam, run_args,
                          key=f"semslam-city-drive-{d.name}-{token}", retries=RETRIES, pure=False)
        labels[f.key] = f"drive {d.name}"
        futures.append(f)
        level.append((f, [d.name]))
    city_dir = os.path.join(out, "city")
    if city_is_current(out, drives):
        # Made from these drives' runs as they are (the merges are removed once the city is done).
        f = client.submit(city_tasks.keep_city, city_dir, [f for f, _ in level],
                          key=f"semslam-city-merge-city-{token}", pure=False)
        labels[f.key] = "merge city"
        futures.append(f)
        return labels, futures, f
    tree = merge_tree(len(drives), group)
    if not tree:  # one drive: its run folder, copied, is the city
        tree = [[[0]]]
    for depth, groups in enumerate(tree, 1):
        next_level = []
        for index, members in enumerate(groups):
            names = [n for m in members for n in level[m][1]]
            last = depth == len(tree)
            if len(members) == 1 and not last:
                next_level.append(level[members[0]])
                continue
            name = "city" if last else f"{depth}-{index}"
            # Named for the drives it holds (a hash: a city's worth of names would be too long a file name), so
            # that a later run of the same command finds it.
            digest = hashlib.sha1("\n".join(names).encode()).hexdigest()[:12]
            target = os.path.join(out, "city") if last else os.path.join(out, "merges", f"{name}-{digest}")
            # OUT/city holds whatever drives it was made of (city_is_current checked that above): made anew.
            f = client.submit(city_tasks.merge_runs, name, [level[m][0] for m in members], target, semslam,
                              reuse=not last, key=f"semslam-city-merge-{name}-{token}", retries=RETRIES, pure=False)
            labels[f.key] = f"merge {name}"
            futures.append(f)
            next_level.append((f, names))
        level = next_level
    return labels, futures, level[0][0]


CITY_JSON = "city.json"


def city_is_current(out: str, drives: List[Drive]) -> bool:
    """OUT/city is complete, made of these drives (OUT/city.json) and newer than each drive's run."""
    try:
        with open(os.path.join(out, CITY_JSON), encoding="utf-8") as f:
            made_of = sorted((d["name"], d["sequence"]) for d in json.load(f)["drives"])
    except (OSError, ValueError, KeyError, TypeError):
        return False
    if made_of != sorted((d.name, d.sequence) for d in drives):
        return False
    return city_tasks.is_complete(os.path.join(out, "city"), [os.path.join(out, "drives", d.name) for d in drives])


def write_city_json(out: str, drives: List[Drive], results: Dict[str, dict], city: dict) -> None:
    """OUT/city.json: what the city was made of, with each drive's figures (temporary file, then renamed)."""
    doc = {"city": "city", "sessions": city.get("sessions"), "drives": []}
    for d in drives:
        r = results.get(f"drive {d.name}", {})
        doc["drives"].append({"name": d.name, "sequence": d.sequence, "gps": d.gps, "landmarks": d.landmarks,
                              "gps_lever_arm": d.gps_lever_arm, "run": f"drives/{d.name}", "frames": r.get("frames"),
                              "ate_rmse": r.get("ate_rmse"), "seconds": r.get("seconds")})
    path = os.path.join(out, CITY_JSON)
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


def run_city(client, drives: List[Drive], out: str, semslam: str, run_args: List[str], group: int,
             progress: Progress) -> int:
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]
    client.subscribe_topic(city_tasks.EVENT_TOPIC, progress.on_event)
    workers = len(client.scheduler_info().get("workers", {}))
    on = f"{workers} worker(s)" if workers else "no worker yet (the tasks wait for one)"
    progress.line(f"semslam.city: {len(drives)} drive(s), {on} at {client.scheduler.address}; city map: "
                  f"{os.path.join(out, 'city')}")
    labels, futures, city = build_graph(client, drives, out, semslam, run_args, group, token)
    for d in drives:
        progress.line(f"  drive {d.name}: queued ({d.sequence})")
    drive_errors, merge_errors, results = [], [], {}
    order = {f.key: i for i, f in enumerate(futures)}
    pending = as_completed(futures, with_results=False)
    while not pending.is_empty():
        # Completions first: a task's start event can arrive before its inputs' completions were handled.
        batch = pending.next_batch(block=False) if pending.has_ready() else []
        for f in batch:
            label = labels[f.key]
            progress.ended.add(label)
            if f.status == "finished":
                result = results[label] = f.result()
                state = "already complete" if result["reused"] else "done"
                progress.line(f"  {label}: {state}: {_describe(result)}")
            elif label.startswith("drive"):
                drive_errors.append(str(f.exception()))
                progress.line(f"  {label}: FAILED: {f.exception()}")
            else:
                merge_errors.append((order[f.key], label, str(f.exception())))
        progress.drain(labels)
        if not batch:
            time.sleep(0.2)
    progress.drain(labels)
    # A merge whose input failed fails with that input's error: the first task with an error (in the tree's order)
    # is its cause.
    reported = set(drive_errors)
    for _, label, err in sorted(merge_errors):
        progress.line(f"  {label}: not done (an input failed)" if err in reported else f"  {label}: FAILED: {err}")
        reported.add(err)
    if drive_errors or merge_errors:
        progress.line(f"semslam.city: failed ({len(drive_errors)} drive(s), {len(merge_errors)} merge(s) not done); "
                      "outputs already made are kept: the same command resumes from there")
        return 1
    write_city_json(out, drives, results, city.result())
    shutil.rmtree(os.path.join(out, "merges"), ignore_errors=True)
    progress.line(f"semslam.city: city map in {city.result()['path']} ({CITY_JSON}: its drives)")
    return 0


def connect(args, n_drives: int):
    from distributed import Client, LocalCluster
    if args.scheduler:
        return Client(args.scheduler), None
    n = args.local_workers or max(1, min(n_drives, (os.cpu_count() or 1) // 3))
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
    return Client(cluster), cluster


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        semslam = find_semslam(args.semslam)
        drives = collect_drives(args)
        out = prepare_out(args.out)
    except CityInputError as e:
        print(f"semslam.city: error: {e}", file=sys.stderr)
        return 2
    try:
        client, cluster = connect(args, len(drives))
    except ImportError as e:
        print(f"semslam.city: error: Dask distributed is missing ({e}): install python3-distributed "
              "(scripts/install-deps.sh)", file=sys.stderr)
        return 2
    except (OSError, TimeoutError) as e:
        print(f"semslam.city: error: cannot reach the Dask scheduler {args.scheduler or '(local)'}: {e}",
              file=sys.stderr)
        return 2
    interrupted = False
    try:
        return run_city(client, drives, out, semslam, run_args_of(args), args.merge_group, Progress())
    except KeyboardInterrupt:
        interrupted = True
        print("semslam.city: interrupted; finished drives and merges are kept: run the same command to resume",
              file=sys.stderr)
        return 130
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
            if interrupted:  # the local workers, and their semslam processes, are gone: so are their outputs
                for partial in glob.glob(os.path.join(glob.escape(out), "**", ".*.partial-*"), recursive=True):
                    shutil.rmtree(partial, ignore_errors=True)


if __name__ == "__main__":
    # Run as `python3 -m semslam.city`: call the importable module's main, so that the tasks Dask sends to the
    # workers name functions of semslam.city_tasks (which the workers import), not of __main__.
    from semslam.city import main as _main
    sys.exit(_main())
