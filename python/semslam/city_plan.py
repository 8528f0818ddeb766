"""The pure parts of `python3 -m semslam.city`: which drives, with which GPS log and landmark catalogue, and the
tree of merges. Nothing here runs a process or needs Dask or the compiled module."""

import dataclasses
import json
import math
import os
import re
from typing import List, Optional, Sequence


class CityInputError(ValueError):
    """Bad input to the city command (a drive, the manifest, the output folder): the message names what and where."""


@dataclasses.dataclass
class Drive:
    name: str                 # the drive's folder name under OUT/drives/
    sequence: str             # absolute: what `semslam run --sequence` takes
    gps: Optional[str] = None          # absolute, or None: no GPS
    landmarks: Optional[str] = None    # absolute, or None: no catalogue
    gps_lever_arm: Optional[List[float]] = None  # X,Y,Z metres in the camera frame
    camera_height_m: Optional[float] = None  # above the road; None: semslam run's default
    named_by_hand: bool = False  # the manifest gave the name: it is kept when names clash
    origin: str = ""  # where it was given, for messages: "--drives[1]", "FILE: drives[0]"

    def run_args(self) -> List[str]:
        """The arguments of `semslam run` that say what this drive is (no --out)."""
        args = ["--sequence", self.sequence]
        if self.gps:
            args += ["--gps", self.gps]
        if self.landmarks:
            args += ["--landmarks", self.landmarks]
        if self.gps_lever_arm is not None:
            args += ["--gps-lever-arm", ",".join(repr(float(v)) for v in self.gps_lever_arm)]
        if self.camera_height_m is not None:
            args += ["--camera-height", repr(float(self.camera_height_m))]
        return args


_LANDMARK_FILES = ("landmarks.csv", "landmarks.geojson")


def _drive_root(sequence: str) -> str:
    """The folder that holds a drive's GPS log and catalogue: the synthetic city's (and a KITTI odometry dataset
    root's) output folder for X/sequences/NN or X itself, else the sequence folder (a KITTI raw drive)."""
    if os.path.isdir(os.path.join(sequence, "sequences")):
        return sequence
    parent = os.path.dirname(sequence)
    if os.path.basename(parent) == "sequences":
        return os.path.dirname(parent)
    return sequence


def _sequences_in(root: str) -> List[str]:
    """The sequence folders of a dataset root (ROOT/sequences/XX with image_0/), as `semslam run` looks for them."""
    folder = os.path.join(root, "sequences")
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    return [os.path.join(folder, n) for n in names if os.path.isdir(os.path.join(folder, n, "image_0"))]


def drive_identity(sequence: str) -> str:
    """What a drive is, for comparing two: the real path of its sequence folder, a dataset root holding one
    sequence standing for that sequence (`semslam run` reads the same frames from both)."""
    sequence = os.path.realpath(sequence)
    if os.path.isdir(sequence):
        only = _sequences_in(sequence)
        if len(only) == 1 and not _holds_a_sequence(sequence):
            return os.path.realpath(only[0])
    return sequence


def drive_folder(sequence: str) -> str:
    """The folder that is the drive (its data): the synthetic city's X for X/sequences/NN (its only sequence), else
    the sequence folder, or the folder of a camera.yaml."""
    if not os.path.isdir(sequence):
        return os.path.dirname(sequence)
    root = _drive_root(sequence)
    if root != sequence and len(_sequences_in(root)) == 1:
        return root
    return sequence


def _holds_a_sequence(folder: str) -> bool:
    """A sequence folder as `semslam run` opens it directly (not through ROOT/sequences/XX)."""
    return (os.path.isdir(os.path.join(folder, "image_0")) or os.path.isfile(os.path.join(folder, "calib.txt")) or
            any(os.path.isdir(os.path.join(folder, f"image_0{i}")) for i in range(4)) or
            any(os.path.isfile(os.path.join(folder, f)) for f in ("camera.yaml", "camera.yml")))


def check_layout(sequence: str) -> None:
    """Refuses what `semslam run --sequence` would refuse by its layout alone (src/semslam/io/sequence.cc,
    OpenSequence), so that a wrong folder is reported before a cluster starts instead of failing on a worker."""
    expected = ("expected a KITTI odometry sequence folder (image_0/, calib.txt), a dataset root holding "
                "sequences/XX/image_0/, a KITTI raw drive folder (image_00/data/) or an image folder with "
                "camera.yaml (or the .yaml itself)")
    if os.path.isfile(sequence):
        if not sequence.endswith((".yaml", ".yml")):
            raise CityInputError(f"{sequence}: is a file, not a sequence; {expected}")
        return
    if _holds_a_sequence(sequence):
        return
    if os.path.isdir(os.path.join(sequence, "sequences")):
        found = _sequences_in(sequence)
        if not found:
            raise CityInputError(f"{sequence}/sequences: holds no sequence folder with image_0/ (expected "
                                 "sequences/XX/image_0/)")
        if len(found) > 1:
            raise CityInputError(f"{sequence}/sequences: holds {len(found)} sequences; give each as a drive: "
                                 f"{', '.join(found)}")
        return
    raise CityInputError(f"{sequence}: not a sequence folder; {expected}")


def _default_name(sequence: str) -> str:
    """The drive's output folder name: X for X/sequences/NN when NN is X's only sequence (the synthetic city),
    X_NN when there are more (a KITTI odometry dataset), else the sequence folder's name."""
    root = _drive_root(sequence)
    name = os.path.basename(root) or "drive"
    if root != sequence and os.path.basename(os.path.dirname(sequence)) == "sequences":
        others = [d for d in os.listdir(os.path.dirname(sequence)) if not d.startswith(".")]
        if len(others) > 1:
            name += "_" + os.path.basename(sequence)
    return re.sub(r"[^A-Za-z0-9._-]", "_", name)


def discover_drive(sequence: str, origin: str = "") -> Drive:
    """A drive from its sequence folder alone: GPS from ROOT/oxts (the synthetic city, a KITTI raw drive), the
    catalogue from ROOT/landmarks.csv or ROOT/landmarks.geojson, where ROOT is _drive_root(sequence)."""
    if not sequence:  # os.path.abspath("") would be the current folder
        raise CityInputError(f"{origin or 'a drive'}: an empty path is not a drive")
    sequence = os.path.abspath(sequence)
    if not os.path.exists(sequence):
        raise CityInputError(f"{sequence}: drive not found (a sequence folder, as `semslam run --sequence` takes)")
    if not (os.path.isdir(sequence) or sequence.endswith((".yaml", ".yml"))):
        raise CityInputError(f"{sequence}: a drive is a sequence folder (or an image folder's camera.yaml)")
    root = _drive_root(sequence) if os.path.isdir(sequence) else os.path.dirname(sequence)
    gps = os.path.join(root, "oxts")
    landmarks = next((os.path.join(root, f) for f in _LANDMARK_FILES if os.path.isfile(os.path.join(root, f))),
                     None)
    return Drive(name=_default_name(sequence), sequence=sequence, gps=gps if os.path.isdir(gps) else None,
                 landmarks=landmarks, origin=origin or sequence)


def _manifest_path(value, key: str, index: int, manifest: str, base: str) -> Optional[str]:
    where = f"{manifest}: drives[{index}].{key}"
    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise CityInputError(f"{where}: expected a path (a non-empty string) or null")
    path = os.path.abspath(os.path.join(base, value))
    if not os.path.exists(path):
        raise CityInputError(f"{where}: {path} not found")
    return path


def read_manifest(path: str) -> List[Drive]:
    """Drives from a manifest (docs/formats.md, "City manifest"): {"drives": [{"sequence", "name"?, "gps"?,
    "landmarks"?, "gps_lever_arm"?, "camera_height_m"?}, ...]}. Relative paths are relative to the manifest's
    folder; a key left out is found as for --drives (discover_drive), a key set to null means none."""
    path = os.path.abspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise CityInputError(f"{path}: cannot read the manifest: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise CityInputError(f"{path}: not UTF-8 text (byte {e.start}): a manifest is JSON") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise CityInputError(f"{path}:{e.lineno}: not JSON: {e.msg}") from None
    except RecursionError:  # the parser recurses per nesting level
        raise CityInputError(f"{path}: nested too deeply to be a manifest") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("drives"), list) or not doc["drives"]:
        raise CityInputError(f"{path}: expected an object with a non-empty list \"drives\"")
    base = os.path.dirname(path)
    known = {"name", "sequence", "gps", "landmarks", "gps_lever_arm", "camera_height_m"}
    drives = []
    for i, entry in enumerate(doc["drives"]):
        if not isinstance(entry, dict):
            raise CityInputError(f"{path}: drives[{i}]: expected an object")
        unknown = sorted(set(entry) - known)
        if unknown:
            raise CityInputError(f"{path}: drives[{i}]: unknown field '{unknown[0]}' "
                                 f"(known: {', '.join(sorted(known))})")
        if "sequence" not in entry:
            raise CityInputError(f"{path}: drives[{i}]: field 'sequence' is missing")
        sequence = _manifest_path(entry["sequence"], "sequence", i, path, base)
        if sequence is None:
            raise CityInputError(f"{path}: drives[{i}].sequence: expected a path, not null")
        drive = discover_drive(sequence, origin=f"{path}: drives[{i}]")
        if "name" in entry:
            name = entry["name"]
            if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", name):
                raise CityInputError(f"{path}: drives[{i}].name: expected letters, digits, '.', '_' or '-' "
                                     f"(a folder name), got {json.dumps(name)}")
            drive.name = name
            drive.named_by_hand = True
        for key in ("gps", "landmarks"):
            if key in entry:
                setattr(drive, key, _manifest_path(entry[key], key, i, path, base))
        if entry.get("gps_lever_arm") is not None:
            arm = entry["gps_lever_arm"]
            if (not isinstance(arm, list) or len(arm) != 3 or
                    not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                            for v in arm)):
                raise CityInputError(f"{path}: drives[{i}].gps_lever_arm: expected [x, y, z], three finite "
                                     f"numbers (metres, camera frame), got {json.dumps(arm)}")
            drive.gps_lever_arm = [float(v) for v in arm]
        if entry.get("camera_height_m") is not None:
            height = entry["camera_height_m"]
            if (not isinstance(height, (int, float)) or isinstance(height, bool) or not math.isfinite(height) or
                    height <= 0):
                raise CityInputError(f"{path}: drives[{i}].camera_height_m: expected a positive number (metres "
                                     f"above the road), got {json.dumps(height)}")
            drive.camera_height_m = float(height)
        drives.append(drive)
    return drives


def _where(drive: Drive) -> str:
    return drive.origin or drive.sequence


def unique_names(drives: Sequence[Drive]) -> None:
    """Gives drives whose names clash (two synthetic cities both named `city`) suffixes -2, -3, ...; two names set
    by hand that clash, or one sequence given twice, are errors."""
    sequences = [drive_identity(d.sequence) for d in drives]
    for i, sequence in enumerate(sequences):
        if sequence in sequences[:i]:
            first = drives[sequences.index(sequence)]
            raise CityInputError(f"{drives[i].sequence}: the same drive is given twice ({_where(first)} and "
                                 f"{_where(drives[i])})")
    by_hand = [d for d in drives if d.named_by_hand]
    for i, drive in enumerate(by_hand):
        twin = next((d for d in by_hand[:i] if d.name == drive.name), None)
        if twin is not None:
            raise CityInputError(f"two drives are named '{drive.name}' ({_where(twin)} and {_where(drive)}): drive "
                                 "names must differ")
    taken = set()
    for drive in sorted(drives, key=lambda d: not d.named_by_hand):  # hand-set names keep theirs
        name, k = drive.name, 2
        while name in taken:
            name, k = f"{drive.name}-{k}", k + 1
        drive.name = name
        taken.add(name)


def merge_tree(count: int, group: int = 2) -> List[List[List[int]]]:
    """The merges that make one map of `count` maps, level by level: each level lists groups of indices into the
    previous level's outputs (level 0: the drives), in order. A group of one is passed on unmerged. Groups of one
    level are as even as `group` allows, so the tree stays shallow: ceil(log_group(count)) levels."""
    if count < 1:
        raise ValueError("merge_tree: at least one map")
    if group < 2:
        raise ValueError("merge_tree: groups of at least 2 maps")
    levels = []
    while count > 1:
        n_groups = -(-count // group)
        base, extra = divmod(count, n_groups)
        groups, start = [], 0
        for g in range(n_groups):
            size = base + (1 if g < extra else 0)
            groups.append(list(range(start, start + size)))
            start += size
        levels.append(groups)
        count = n_groups
    return levels
