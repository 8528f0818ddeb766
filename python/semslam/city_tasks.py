"""What the Dask workers of `python3 -m semslam.city` run: one `semslam run` per drive, `semslam merge` of a group of
run folders, each as a subprocess. A task writes into a temporary folder beside its output and renames it into place
only once the command succeeded, so an output folder that exists is complete; one that is already there (and newer
than its inputs) is not made again."""

import ctypes
import glob
import json
import os
import shutil
import signal
import subprocess
import uuid
from typing import List, Optional, Sequence

from .city_plan import Drive

EVENT_TOPIC = "semslam.city"  # tasks report that they started on this Dask event topic
RUN_JSON = "run.json"
# Every semslam command leaves it in its output folder (src/semslam/system/run_output_dir.h).
LOCK_FILE = ".semslam.lock"
FINISHED = ("complete", "ok")  # run.json "status" of a finished run ("complete") and merge ("ok")
RETRIES = 2  # a command that failed in a way that may not repeat is tried this many more times
REPEATING_EXIT_CODES = (1, 2)  # semslam's "failed" and "bad input": the same command fails again


class CityTaskError(RuntimeError):
    """A drive's run or a merge failed: the message gives the command and the tail of its stderr. `repeats`: the
    same command would fail again (bad input, a failed run), so it is not tried again."""

    def __init__(self, message: str, repeats: bool = True):
        super().__init__(message)
        self.repeats = repeats

    def __reduce__(self):  # sent from the worker to the client: keep `repeats`
        return (type(self), (str(self), self.repeats))


def _announce(kind: str, name: str) -> Optional[str]:
    """Tells the client (its progress lines) that a task started, and on which worker. None outside Dask."""
    try:
        from distributed import get_worker
        worker = get_worker()
    except (ImportError, ValueError):
        return None
    worker.log_event(EVENT_TOPIC, {"kind": kind, "name": name, "worker": worker.address, "pid": os.getpid()})
    return worker.address


def _libc_prctl():
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None


_PRCTL = _libc_prctl()
_PR_SET_PDEATHSIG = 1


def _die_with_parent():
    # A worker that dies (killed, out of memory) must not leave its semslam process writing on: the task is run
    # again elsewhere, and the orphan would keep its temporary folder alive and busy the machine.
    if _PRCTL is not None:
        _PRCTL(_PR_SET_PDEATHSIG, signal.SIGKILL)


def _stderr_tail(text: str, lines: int = 20) -> str:
    tail = [line for line in text.strip().splitlines() if line.strip()][-lines:]
    return "\n".join("    " + line for line in tail) or "    (nothing on stderr)"


def run_command(cmd: Sequence[str], what: str) -> None:
    try:
        result = subprocess.run(list(cmd), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, errors="replace", preexec_fn=_die_with_parent)
    except OSError as e:
        raise CityTaskError(f"{what}: cannot start {cmd[0]}: {e.strerror}") from None
    if result.returncode != 0:
        how = f"killed by signal {-result.returncode}" if result.returncode < 0 else f"exit code {result.returncode}"
        # Killed (out of memory) or an unexpected code may not happen again; bad input or a failed run will.
        raise CityTaskError(f"{what} failed ({how}): {' '.join(cmd)}\n{_stderr_tail(result.stderr)}",
                            repeats=result.returncode in REPEATING_EXIT_CODES)


def read_run_json(folder: str) -> Optional[dict]:
    try:
        with open(os.path.join(folder, RUN_JSON), encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) else None


def _mtime_ns(folder: str) -> int:
    return os.stat(os.path.join(folder, RUN_JSON)).st_mtime_ns


def _finished(run: Optional[dict]) -> bool:
    return run is not None and run.get("status") in FINISHED


def is_complete(folder: str, inputs: Sequence[str] = ()) -> bool:
    """A finished output: its run.json is there with a finished status (not "interrupted"), and newer than every
    input's (a drive run again since then makes the merges that hold it stale)."""
    if not _finished(read_run_json(folder)):
        return False
    mine = _mtime_ns(folder)
    return all(_finished(read_run_json(i)) and _mtime_ns(i) <= mine for i in inputs)


def drive_command(drive: Drive, run_args: Sequence[str]) -> List[str]:
    """The arguments of the drive's `semslam run`, without --out (which run_drive inserts)."""
    return ["run", *drive.run_args(), *run_args, "-q"]


def merge_command(paths: Sequence[str]) -> List[str]:
    return ["merge", "--maps", *paths, "-q"]


def _options(args: Sequence[str]) -> List[tuple]:
    """A command's arguments as options with their values (("--frames", "0:20"), ...), --out left out and paths
    compared as real paths: the same command given through a symlink is the same."""
    groups: List[list] = []
    for arg in args:
        if arg.startswith("-") or not groups:
            groups.append([arg])
        else:
            groups[-1].append(os.path.realpath(arg) if os.path.isabs(arg) else arg)
    return [tuple(g) for g in groups if g[0] != "--out"]


def made_otherwise(folder: str, command: Sequence[str]) -> Optional[str]:
    """Why the output in `folder` is not what `semslam COMMAND` (without --out) makes: its run.json records
    another command (provenance.command) or, without that record, another sequence. None when it is the same,
    or when there is no finished output to compare."""
    run = read_run_json(folder)
    if not _finished(run):
        return None
    provenance = run.get("provenance") if isinstance(run.get("provenance"), dict) else {}
    made_by = provenance.get("command")
    if isinstance(made_by, list) and made_by and all(isinstance(a, str) for a in made_by):
        had, now = _options(made_by[1:]), _options(command)
        if had == now:
            return None
        gone = [" ".join(o) for o in had if o not in now]
        new = [" ".join(o) for o in now if o not in had]
        if not gone and not new:
            return "made with its arguments in another order"
        return ("made with other arguments (" + "; ".join(
            ([f"had {', '.join(gone)}"] if gone else []) + ([f"now {', '.join(new)}"] if new else [])) + ")")
    config = run.get("config") if isinstance(run.get("config"), dict) else {}
    sequence = config.get("sequence")
    if command[:1] == ["run"] and isinstance(sequence, str) and "--sequence" in command:
        wanted = command[command.index("--sequence") + 1]
        if os.path.realpath(sequence) != os.path.realpath(wanted):
            return f"made from another sequence ({sequence})"
    return None


def semslam_wrote(folder: str) -> bool:
    """Whether `folder` is an output of a semslam command (its lock file and a run.json), which the city command
    may replace: anything else there is the user's, and is never removed."""
    return (os.path.isdir(folder) and not os.path.islink(folder) and
            os.path.isfile(os.path.join(folder, LOCK_FILE)) and read_run_json(folder) is not None)


def partial_prefix(final: str) -> str:
    return os.path.join(os.path.dirname(final), "." + os.path.basename(final) + ".partial-")


def new_partial(final: str) -> str:
    """A fresh temporary folder name beside `final` (not created), after removing those of earlier attempts: a
    task is only run again once its earlier attempt's worker is gone (and its semslam process with it)."""
    prefix = partial_prefix(final)
    for stale in glob.glob(glob.escape(prefix) + "*"):
        shutil.rmtree(stale, ignore_errors=True)
    os.makedirs(os.path.dirname(final), exist_ok=True)
    return prefix + uuid.uuid4().hex[:12]


def move_into_place(partial: str, final: str) -> None:
    """Renames the finished folder `partial` to `final`, replacing an older `final` (renamed aside first, since a
    folder cannot be renamed over a non-empty one, then removed) only when semslam wrote it."""
    aside = None
    if os.path.lexists(final):
        if not semslam_wrote(final):
            raise CityTaskError(f"{final} exists and is not a semslam output (no {LOCK_FILE} and {RUN_JSON}): it is "
                                "left as it is; move it away or choose another --out")
        aside = partial + ".old"
        os.rename(final, aside)
    os.rename(partial, final)
    if aside:
        shutil.rmtree(aside, ignore_errors=True)


def _check_output(folder: str, what: str) -> dict:
    run = read_run_json(folder)
    if run is None:
        raise CityTaskError(f"{what}: the command succeeded but wrote no readable {RUN_JSON} in {folder}")
    status = run.get("status")
    if status not in FINISHED:
        raise CityTaskError(f"{what}: {folder}/{RUN_JSON} has status '{status}', not {' or '.join(FINISHED)}")
    return run


def _summary(kind: str, name: str, folder: str, run: dict, reused: bool, worker: Optional[str]) -> dict:
    maps = run.get("maps") if isinstance(run.get("maps"), dict) else {}
    sessions = maps.get("sessions")
    return {"kind": kind, "name": name, "path": folder, "reused": reused, "worker": worker,
            "frames": run.get("frames"), "ate_rmse": run.get("ate_rmse"), "seconds": run.get("seconds"),
            "sessions": len(sessions) if isinstance(sessions, list) else None, "maps": maps.get("count")}


def keep_city(city_dir: str, drive_results: List[dict]) -> dict:
    """The city as it is, when it is newer than every drive's run (checked before the drives' tasks were sent)."""
    if any(not r["reused"] for r in drive_results):
        raise CityTaskError(f"{city_dir}: a drive was run again after the city was found complete; run the "
                            "command again to merge anew")
    return _summary("merge", "city", city_dir, read_run_json(city_dir), True, None)


def _make(final: str, what: str, write) -> dict:
    """Runs write(partial) into a fresh temporary folder, checks its run.json and renames it to `final`; a command
    that failed in a way that may not repeat (killed, an unexpected exit code) is tried again, up to RETRIES
    times. (A worker that dies has its task run again by Dask itself.)"""
    for attempt in range(RETRIES + 1):
        partial = new_partial(final)
        try:
            write(partial)
            run = _check_output(partial, what)
            move_into_place(partial, final)
            return run
        except CityTaskError as e:
            shutil.rmtree(partial, ignore_errors=True)
            if e.repeats or attempt == RETRIES:
                raise
        except BaseException:
            shutil.rmtree(partial, ignore_errors=True)
            raise
    raise AssertionError("unreachable")


def run_drive(drive: Drive, drives_dir: str, semslam: str, run_args: Sequence[str]) -> dict:
    """`semslam run` of one drive into DRIVES_DIR/<name>, unless it is there already, made by the same command."""
    final = os.path.join(drives_dir, drive.name)
    what = f"drive {drive.name}"
    command = drive_command(drive, run_args)
    if is_complete(final) and made_otherwise(final, command) is None:
        return _summary("drive", drive.name, final, read_run_json(final), True, None)
    worker = _announce("drive", drive.name)
    # --out right after what the drive is, as the command line was always written.
    cmd = [semslam, command[0], *drive.run_args(), "--out", None, *run_args, "-q"]
    run = _make(final, what, lambda partial: run_command([partial if a is None else a for a in cmd], what))
    return _summary("drive", drive.name, final, run, False, worker)


def _path_of(item) -> str:
    return item["path"] if isinstance(item, dict) else item


def merge_runs(name: str, inputs: List, out: str, semslam: str, reuse: bool = True) -> dict:
    """`semslam merge --maps IN... --out OUT` (inputs: run folders, or the summaries of the tasks that made them).
    With `reuse`, an OUT newer than its inputs is kept: OUT must then be named for what it holds."""
    paths = [_path_of(i) for i in inputs]
    what = f"merge {name}"
    if reuse and is_complete(out, paths) and made_otherwise(out, merge_command(paths)) is None:
        return _summary("merge", name, out, read_run_json(out), True, None)
    worker = _announce("merge", name)

    def write(partial):
        if len(paths) == 1:  # one drive: its run folder is the city
            shutil.copytree(paths[0], partial, copy_function=_link_or_copy)
        else:
            run_command([semslam, "merge", "--maps", *paths, "--out", partial, "-q"], what)

    run = _make(out, what, write)
    return _summary("merge", name, out, run, False, worker)


def _link_or_copy(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)
