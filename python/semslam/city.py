"""Many drives, one city map, on Dask distributed: `python3 -m semslam.city --drives D1 D2 ... --out DIR`.

Each drive is one Dask task that runs `semslam run` into DIR/drives/<name>/; the run folders are then merged in a
tree of `semslam merge` tasks (groups of up to --merge-group maps, the outputs merged again) until one map remains,
DIR/city/ (a run folder as `semslam merge` writes it). Intermediate merges go to DIR/merges/ and are removed once the
city is done. Every output is written to a temporary folder and renamed into place when its command succeeded; an
output already there, made by the same command, is not made again, so running the same command after a crash or
Ctrl-C resumes. Dask runs a task again when its worker dies. OUT/.city.lock keeps a second command off OUT. See
README.md ("Many drives, one city map") and docs/formats.md (city manifest)."""

import argparse
import contextlib
import errno
import fcntl
import glob
import hashlib
import json
import os
import queue
import re
import shutil
import signal
import socket
import sys
import threading
import time
import uuid
from typing import Dict, List, Optional, Sequence

from . import city_tasks
from .city_plan import (CityInputError, Drive, check_layout, discover_drive, drive_folder, merge_tree, read_manifest,
                        unique_names)

LOCK_FILE = ".city.lock"  # OUT/.city.lock: one city command per output folder
OUTPUTS = ("drives", "city", "merges")  # what the command writes under OUT (and replaces)
# Arguments of `semslam run` that the city command sets per drive: given after `--` they would clash with its own.
OWN_RUN_OPTIONS = ("--out", "--sequence", "--map-in")
SCHEDULER_SCHEMES = ("tcp", "tls")
CONNECT_TIMEOUT_S = 5  # the first TCP connection to the scheduler: an address that does not answer is reported soon
CLIENT_TIMEOUT_S = 20  # Dask's handshake once the scheduler's port answered


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
    # An empty path would silently be the current folder.
    if args.out == "":
        p.error("--out: an empty path; give the output folder")
    if "" in args.drives:
        p.error("--drives: an empty path is not a drive")
    if args.manifest == "":
        p.error("--manifest: an empty path; give the manifest file")
    if args.frames is not None:
        m = re.fullmatch(r"(\d*):(\d*)", args.frames)  # as `semslam run` reads it: A:B, either side may be empty
        if not m:
            p.error(f"--frames: '{args.frames}' must look like A:B (frames A..B-1, either side may be empty)")
        if m.group(1) and m.group(2) and int(m.group(1)) >= int(m.group(2)):
            p.error(f"--frames: '{args.frames}' holds no frame (A must be less than B)")
    for arg in extra:
        option = arg.split("=", 1)[0]
        if option in OWN_RUN_OPTIONS:
            p.error(f"after `--`: {option} is set by the city command for each drive (OUT/drives/<name>, the "
                    "drive's sequence, a new map): leave it out")
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


def _inside(path: str, folder: str) -> bool:
    """Whether `path` is `folder` or lies in it (both real paths)."""
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def check_out(out: str, drives: List[Drive]) -> None:
    """Refuses an OUT whose outputs would replace a drive's data: OUT/drives/<name>, OUT/city and OUT/merges/...
    are replaced when made again, so no sequence, GPS log or catalogue may lie there, nor OUT inside a drive. A
    folder already at OUT/drives/<name> or OUT/city that semslam did not write is refused too."""
    real_out = os.path.realpath(out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise CityInputError(f"{out}: --out exists and is not a folder")
    written = [os.path.join(real_out, name) for name in OUTPUTS]
    for d in drives:
        for what, path in (("sequence", d.sequence), ("GPS log", d.gps), ("landmark catalogue", d.landmarks)):
            if path is None:
                continue
            real = os.path.realpath(path)
            clash = next((w for w in written if _inside(real, w)), None)
            if clash is not None:
                raise CityInputError(f"drive {d.name}: its {what} {path} lies in {clash}, which the city command "
                                     "writes and replaces; choose another --out")
        folder = os.path.realpath(drive_folder(d.sequence))
        if _inside(real_out, folder):
            raise CityInputError(f"{out}: --out lies in drive {d.name}'s folder {folder}; choose a folder outside "
                                 "the drives")
    for target in [os.path.join(out, "drives", d.name) for d in drives] + [os.path.join(out, "city")]:
        if os.path.lexists(target) and not city_tasks.semslam_wrote(target):
            raise CityInputError(f"{target}: exists and is not a semslam output (no {city_tasks.LOCK_FILE} and "
                                 f"{city_tasks.RUN_JSON}); the city command would replace it: move it away or "
                                 "choose another --out")


def prepare_out(out: str) -> str:
    out = os.path.abspath(out)  # check_out has refused an OUT that is a file
    try:
        os.makedirs(os.path.join(out, "drives"), exist_ok=True)
        probe = os.path.join(out, f".write-test-{uuid.uuid4().hex[:8]}")
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as e:
        raise CityInputError(f"{out}: cannot write the output folder: {e.strerror}") from None
    return out


def lock_out(out: str) -> int:
    """Takes OUT/.city.lock (held until the process ends: its descriptor is returned); a second city command on
    the same OUT would replace the first one's outputs under it. The file stays, holding the last holder's pid."""
    path = os.path.join(out, LOCK_FILE)
    try:
        os.makedirs(out, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as e:
        raise CityInputError(f"{out}: cannot write the output folder: {e.strerror}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        holder = os.pread(fd, 256, 0).decode(errors="replace").strip()
        os.close(fd)
        if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
            raise CityInputError(f"{out}: another semslam.city command is writing into this folder"
                                 f"{f' ({holder})' if holder else ''}; wait for it to end or choose another "
                                 "--out") from None
        raise CityInputError(f"{path}: cannot lock: {e.strerror}") from None
    holder = f"pid {os.getpid()}, semslam.city\n".encode()
    os.ftruncate(fd, 0)
    os.pwrite(fd, holder, 0)
    return fd


def remove_unused_out(out: str) -> None:
    """Removes OUT when this command made it and it still holds nothing but what prepare_out and lock_out put
    there (a failure before the first output leaves no empty folder behind)."""
    try:
        if sorted(os.listdir(out)) in ([LOCK_FILE, "drives"], ["drives"]) and not os.listdir(os.path.join(out,
                                                                                                          "drives")):
            os.rmdir(os.path.join(out, "drives"))
            if os.path.exists(os.path.join(out, LOCK_FILE)):
                os.remove(os.path.join(out, LOCK_FILE))
            os.rmdir(out)
    except OSError:
        pass


def collect_drives(args) -> List[Drive]:
    drives = [discover_drive(d, origin=f"--drives {d}") for d in args.drives]
    if args.manifest:
        drives += read_manifest(args.manifest)
    unique_names(drives)
    for d in drives:
        check_layout(d.sequence)
    return drives


def check_scheduler(address: str) -> str:
    """Checks a --scheduler address before Dask tries it (which waits its whole timeout on any failure): the scheme
    (tcp:// when none), the port, the host's name, and one TCP connection. Returns the address with its scheme."""
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme not in SCHEDULER_SCHEMES:
        raise CityInputError(f"--scheduler {address}: expected tcp://HOST:PORT (a Dask scheduler's address; "
                             f"schemes: {', '.join(SCHEDULER_SCHEMES)})")
    m = re.fullmatch(r"(\[[^\]]+\]|[^:/\[\]]+):(\d+)/?", rest)
    if not m:
        raise CityInputError(f"--scheduler {address}: expected {scheme}://HOST:PORT")
    host, port = m.group(1).strip("[]"), int(m.group(2))
    if not 1 <= port <= 65535:
        raise CityInputError(f"--scheduler {address}: port {port} is not in 1..65535")
    try:
        socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as e:
        raise CityInputError(f"--scheduler {address}: unknown host '{host}' ({e.strerror})") from None
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S):
            pass
    except socket.timeout:
        raise CityInputError(f"--scheduler {address}: no answer within {CONNECT_TIMEOUT_S} s (is the scheduler "
                             "running, and its port open?)") from None
    except OSError as e:
        raise CityInputError(f"--scheduler {address}: cannot connect: {e.strerror or e} (is the scheduler "
                             "running?)") from None
    return f"{scheme}://{rest}"


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
        self.starts = {}  # label -> how many times it started (a task is run again when its worker died)

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


def build_graph(client, drives: List[Drive], out: str, semslam: str, run_args: List[str], group: int, token: str,
                futures: Optional[list] = None):
    """Submits the drive tasks and the merge tree; returns (labels by key, all futures, the city's future, the
    intermediate merges' folders). `futures` (a list) receives each future as it is submitted, so that an
    interruption can cancel them. Dask does not retry a task (a command that may succeed when run again is retried
    by the task itself; a worker that died has its task run again by Dask)."""
    labels, futures = {}, futures if futures is not None else []
    level, merge_dirs = [], []
    for d in drives:
        f = client.submit(city_tasks.run_drive, d, os.path.join(out, "drives"), semslam, run_args,
                          key=f"semslam-city-drive-{d.name}-{token}", pure=False)
        labels[f.key] = f"drive {d.name}"
        futures.append(f)
        level.append((f, [d.name]))
    city_dir = os.path.join(out, "city")
    if city_is_current(out, drives, run_args):
        # Made from these drives' runs as they are (the merges are removed once the city is done).
        f = client.submit(city_tasks.keep_city, city_dir, [f for f, _ in level],
                          key=f"semslam-city-merge-city-{token}", pure=False)
        labels[f.key] = "merge city"
        futures.append(f)
        return labels, futures, f, merge_dirs
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
                              reuse=not last, key=f"semslam-city-merge-{name}-{token}", pure=False)
            labels[f.key] = f"merge {name}"
            futures.append(f)
            next_level.append((f, names))
            if not last:
                merge_dirs.append(target)
        level = next_level
    return labels, futures, level[0][0], merge_dirs


CITY_JSON = "city.json"


def drive_redone_because(out: str, drive: Drive, run_args: List[str]) -> Optional[str]:
    """Why OUT/drives/<name>, finished, is not what this command would make of the drive (None: it is, or there
    is no finished run to keep): it is then run again, and the merges holding it with it."""
    return city_tasks.made_otherwise(os.path.join(out, "drives", drive.name),
                                     city_tasks.drive_command(drive, run_args))


def city_is_current(out: str, drives: List[Drive], run_args: Optional[List[str]] = None) -> bool:
    """OUT/city is complete, made of these drives (OUT/city.json) and newer than each drive's run, and (with
    `run_args`) each drive's run is what this command makes of it."""
    if run_args is not None and any(drive_redone_because(out, d, run_args) for d in drives):
        return False
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
                              "gps_lever_arm": d.gps_lever_arm, "camera_height_m": d.camera_height_m,
                              "run": f"drives/{d.name}", "frames": r.get("frames"),
                              "ate_rmse": r.get("ate_rmse"), "seconds": r.get("seconds")})
    path = os.path.join(out, CITY_JSON)
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


def run_city(client, drives: List[Drive], out: str, semslam: str, run_args: List[str], group: int,
             progress: Progress, futures: Optional[list] = None) -> int:
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]
    client.subscribe_topic(city_tasks.EVENT_TOPIC, progress.on_event)
    workers = len(client.scheduler_info().get("workers", {}))
    on = f"{workers} worker(s)" if workers else "no worker yet (the tasks wait for one)"
    progress.line(f"semslam.city: {len(drives)} drive(s), {on} at {client.scheduler.address}; city map: "
                  f"{os.path.join(out, 'city')}")
    labels, futures, city, merge_dirs = build_graph(client, drives, out, semslam, run_args, group, token, futures)
    for d in drives:
        redone = drive_redone_because(out, d, run_args)
        progress.line(f"  drive {d.name}: queued ({d.sequence})" +
                      (f"; its earlier run is redone: {redone}" if redone else ""))
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
    for folder in merge_dirs:  # only what this command made: anything else under OUT/merges is not ours
        shutil.rmtree(folder, ignore_errors=True)
    try:
        os.rmdir(os.path.join(out, "merges"))
    except OSError:
        pass
    progress.line(f"semslam.city: city map in {city.result()['path']} ({CITY_JSON}: its drives)")
    return 0


class Terminated(KeyboardInterrupt):
    """SIGTERM (`kill`, a Slurm job's time limit): stops the command as Ctrl-C does, with exit code 143."""


def _raise_terminated(signum, frame):
    raise Terminated()


def _set_signals(handler_int, handler_term):
    """Sets the handlers of SIGINT and SIGTERM (only the main thread may); returns the earlier ones."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGINT, handler_int), signal.signal(signal.SIGTERM, handler_term)


@contextlib.contextmanager
def _signals_deferred():
    """Ctrl-C and SIGTERM held back (the list yielded receives them) while a local cluster starts: interrupted
    half-way, it cannot be closed cleanly (Dask's exit hook then fails with a traceback); it starts in seconds."""
    received: List[int] = []

    def hold(signum, frame):
        received.append(signum)

    ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # a background job's: stays ignored
    earlier = _set_signals(signal.SIG_IGN if ignored else hold, hold)
    try:
        yield received
    finally:
        if earlier is not None:
            _set_signals(*earlier)


def connect(args, n_drives: int, address: Optional[str]):
    from distributed import Client, LocalCluster
    if address:
        return Client(address, timeout=CLIENT_TIMEOUT_S), None
    # More workers than drives would only wait (the merges are fewer still).
    n = min(args.local_workers or max(1, (os.cpu_count() or 1) // 3), n_drives)
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        return Client(cluster), cluster
    except BaseException:
        cluster.close()
        raise


def _run(args, drives: List[Drive], out: str, semslam: str, address: Optional[str]) -> int:
    """Connects to (or starts) the cluster and makes the city; Ctrl-C or SIGTERM at any point (the cluster's
    start-up too) ends it cleanly."""
    client = cluster = None
    futures: list = []
    interrupted = False
    try:
        try:
            if address:
                client, cluster = connect(args, len(drives), address)
            else:
                with _signals_deferred() as received:
                    client, cluster = connect(args, len(drives), address)
                if received:
                    raise Terminated() if received[0] == signal.SIGTERM else KeyboardInterrupt()
        except ImportError as e:
            print(f"semslam.city: error: Dask distributed is missing ({e}): install python3-distributed "
                  "(scripts/install-deps.sh)", file=sys.stderr)
            return 2
        except (OSError, TimeoutError) as e:
            print(f"semslam.city: error: cannot reach the Dask scheduler {address or '(local)'}: {e}",
                  file=sys.stderr)
            return 2
        return run_city(client, drives, out, semslam, run_args_of(args), args.merge_group, Progress(), futures)
    except KeyboardInterrupt as e:
        interrupted = True
        _set_signals(signal.SIG_IGN, signal.SIG_IGN)  # a second Ctrl-C must not cut the cleanup short
        what = "terminated" if isinstance(e, Terminated) else "interrupted"
        if address and client is not None and futures:
            try:
                client.cancel(futures, force=True)
            except Exception:  # noqa: BLE001 - the scheduler may be gone too; nothing more to cancel then
                pass
            print(f"semslam.city: {what}; the city's tasks are cancelled, but a drive or merge already running on "
                  "a worker goes on until its semslam command ends (its output is kept when it finishes); "
                  "finished drives and merges are kept: run the same command to resume", file=sys.stderr)
        else:
            print(f"semslam.city: {what}; finished drives and merges are kept: run the same command to resume",
                  file=sys.stderr)
        return 143 if isinstance(e, Terminated) else 130
    finally:
        _set_signals(signal.SIG_IGN, signal.SIG_IGN)
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
            if interrupted:  # the local workers, and their semslam processes, are gone: so are their outputs
                for partial in glob.glob(os.path.join(glob.escape(out), "**", ".*.partial-*"), recursive=True):
                    shutil.rmtree(partial, ignore_errors=True)


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    # SIGINT as Python set it (ignored in a background job of a script, as the shell meant); SIGTERM like it.
    earlier = _set_signals(signal.getsignal(signal.SIGINT), _raise_terminated)
    try:
        try:
            semslam = find_semslam(args.semslam)
            drives = collect_drives(args)
            out = os.path.abspath(args.out)
            check_out(out, drives)
            address = check_scheduler(args.scheduler) if args.scheduler else None
        except CityInputError as e:
            print(f"semslam.city: error: {e}", file=sys.stderr)
            return 2
        created = not os.path.lexists(out)
        lock = None
        try:
            lock = lock_out(out)
            prepare_out(out)
            return _run(args, drives, out, semslam, address)
        except CityInputError as e:
            print(f"semslam.city: error: {e}", file=sys.stderr)
            return 2
        finally:
            if created:  # made by this command and still empty (a failure before the first output): removed
                remove_unused_out(out)
            if lock is not None:
                os.close(lock)
    except KeyboardInterrupt as e:  # before the cluster (its own interruptions are handled in _run)
        print(f"semslam.city: {'terminated' if isinstance(e, Terminated) else 'interrupted'}", file=sys.stderr)
        return 143 if isinstance(e, Terminated) else 130
    finally:
        if earlier is not None:
            _set_signals(*earlier)


if __name__ == "__main__":
    # Run as `python3 -m semslam.city`: call the importable module's main, so that the tasks Dask sends to the
    # workers name functions of semslam.city_tasks (which the workers import), not of __main__.
    from semslam.city import main as _main
    sys.exit(_main())
