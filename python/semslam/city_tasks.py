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
FINISHED = ("complete", "ok")  # run.json "status" of a finished run ("complete") and merge ("ok")


class CityTaskError(RuntimeError):
    """A drive's run or a merge failed: the message gives the command and the tail of its stderr."""


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
        raise CityTaskError(f"{what} failed ({how}): {' '.join(cmd)}\n{_stderr_tail(result.stderr)}")


def read_run_json(folder: str) -> Optional[dict]:
    try:
        with open(os.path.join(folder, RUN_JSON), encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) else None


def _mtime_ns(folder: str) -> int:
    return os.stat(os.path.join(folder, RUN_JSON)).st_mtime_ns


def is_complete(folder: str, inputs: Sequence[str] = ()) -> bool:
    """A finished output: its run.json is there, and newer than every input's (a drive run again since then makes
    the merges that hold it stale)."""
    if read_run_json(folder) is None:
        return False
    mine = _mtime_ns(folder)
    return all(read_run_json(i) is not None and _mtime_ns(i) <= mine for i in inputs)


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
    folder cannot be renamed over a non-empty one, then removed)."""
    aside = None
    if os.path.lexists(final):
        aside = partial + ".old"
        os.rename(final, aside)
    os.rename(partial, final)
    if aside:
        shutil.rmtree(aside, ignore_errors=True)


def _check_output(folder: str, what: str) -> dict:
    run = read_run_json(folder)
    if run is None:
        raise CityTaskError(f"{what}: the command succeeded but wrote no readable {RUN_JSON} in {folder}")
    status = run.get("status", "complete")
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


def run_drive(drive: Drive, drives_dir: str, semslam: str, run_args: Sequence[str]) -> dict:
    """`semslam run` of one drive into DRIVES_DIR/<name>, unless it is there already."""
    final = os.path.join(drives_dir, drive.name)
    what = f"drive {drive.name}"
    if is_complete(final):
        return _summary("drive", drive.name, final, read_run_json(final), True, None)
    worker = _announce("drive", drive.name)
    partial = new_partial(final)
    try:
        run_command([semslam, "run", *drive.run_args(), "--out", partial, *run_args, "-q"], what)
        run = _check_output(partial, what)
        move_into_place(partial, final)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    return _summary("drive", drive.name, final, run, False, worker)


def _path_of(item) -> str:
    return item["path"] if isinstance(item, dict) else item


def merge_runs(name: str, inputs: List, out: str, semslam: str, reuse: bool = True) -> dict:
    """`semslam merge --maps IN... --out OUT` (inputs: run folders, or the summaries of the tasks that made them).
    With `reuse`, an OUT newer than its inputs is kept: OUT must then be named for what it holds."""
    paths = [_path_of(i) for i in inputs]
    what = f"merge {name}"
    if reuse and is_complete(out, paths):
        return _summary("merge", name, out, read_run_json(out), True, None)
    worker = _announce("merge", name)
    partial = new_partial(out)
    try:
        if len(paths) == 1:  # one drive: its run folder is the city
            shutil.copytree(paths[0], partial, copy_function=_link_or_copy)
        else:
            run_command([semslam, "merge", "--maps", *paths, "--out", partial, "-q"], what)
        run = _check_output(partial, what)
        move_into_place(partial, out)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    return _summary("merge", name, out, run, False, worker)


def _link_or_copy(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)
