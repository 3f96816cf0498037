"""Atomic file output: a file, or a set of files, is either the old good one or the new complete one.

Temporary files and folders are written beside their target under a name that carries the
writer's host and process id (:func:`part_name`): ``.<name>.<host>.<pid>.<token>.part``. A
writer killed before its rename leaves such a part behind; the next write into the same folder
removes every part of this host whose process is no longer alive (:func:`clean_stale_parts`)
and never touches a live writer's part or another host's (whose processes it cannot see).

A run that writes several files (``vobscure render``, ``vobscure compare``) writes them through
:func:`file_set`: into a fresh staging folder beside the targets, then, under a lock on the
folder, moved into place one rename each, after a ``COMMIT`` marker that makes the moves
replayable. A run killed before the marker leaves the previous set untouched (its staging
folder is removed as a stale part); killed after it, during the moves, the folder is mixed
until the next writer into it (or :func:`check_writable_dir` of it) finishes the moves. Files of the previous set (recorded in a manifest) that the new set lacks are removed,
so the set is always one run's as a whole; files of the folder that no set wrote are kept.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import secrets
import shutil
import socket
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["atomic_write", "save_npz", "part_name", "clean_stale_parts", "file_set", "check_writable_dir",
           "OutputError"]

#: How long a second writer waits for the lock of a folder whose file set is being moved into
#: place (the moves are renames: milliseconds), in seconds.
LOCK_WAIT = 60.0
#: The marker a staging folder holds once its files are complete and may be moved into place.
COMMIT = "COMMIT"

_PART = re.compile(r"^\.(?P<name>.+)\.(?P<host>[A-Za-z0-9_-]+)\.(?P<pid>\d+)\.(?P<token>[0-9a-f]+)\.part$")


class OutputError(OSError):
    """An output path cannot be written; the message names it and says why."""


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "-", socket.gethostname())[:40] or "host"


def part_name(name: str) -> str:
    """The name of a temporary file (or folder) for ``name``: it carries this host and process id.

    Examples
    --------
    >>> part_name("results.csv").startswith(".results.csv.") and part_name("x").endswith(".part")
    True
    """
    return f".{name}.{_host()}.{os.getpid()}.{secrets.token_hex(4)}.part"


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:   # a process of another user: alive
        return True
    except OSError:
        return True           # cannot tell: keep its part
    return True


def clean_stale_parts(directory) -> list[Path]:
    """Remove the parts in ``directory`` that dead processes of this host left; return them.

    A staging folder holding the :data:`COMMIT` marker is finished (its files moved into
    place) rather than removed. Parts of live processes and of other hosts are kept.
    """
    directory = Path(directory)
    removed = []
    host = _host()
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        m = _PART.match(entry.name)
        if m is None or m["host"] != host or _alive(int(m["pid"])):
            continue
        path = Path(entry.path)
        try:
            if entry.is_dir(follow_symlinks=False):
                if (path / COMMIT).is_file():
                    with _locked(directory):
                        _move_set(path, directory, m["name"])
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink()
        except OSError:
            continue      # another cleaner got there first, or it is not ours to remove
        removed.append(path)
    return removed


def atomic_write(path, write) -> Path:
    """Call ``write(fileobj)`` on a temporary file beside ``path``, then rename it into place.

    The rename is atomic on POSIX, so an interrupted run never leaves a truncated file where
    a good one was; the temporary file is removed on any error, and a killed writer's is
    removed by the next write into the folder (:func:`clean_stale_parts`).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_parts(path.parent)
    tmp = path.parent / part_name(path.name)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)   # the umask applies
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def save_npz(path, provenance: dict, **arrays) -> Path:
    """Compressed ``.npz`` of ``arrays`` plus a JSON ``provenance`` record, written atomically."""
    record = json.dumps(provenance, sort_keys=True, default=_jsonable)
    return atomic_write(path, lambda fh: np.savez_compressed(fh, provenance=np.array(record), **arrays))


def check_writable_dir(path, what: str) -> Path:
    """Make the folder ``path`` (and its parents) and check that a file can be created in it.

    Called before a job's work, so that an output that cannot be written fails in a second,
    not after the work; it also cleans the folder's stale parts (:func:`clean_stale_parts`). Raises :class:`OutputError` naming ``what`` (the option, e.g.
    ``"--out"``) and the path.
    """
    path = Path(path)
    for parent in [path, *path.parents]:
        if parent.exists():
            if not parent.is_dir():
                where = "is a file" if parent == path else f"is under {parent}, which is a file"
                raise OutputError(errno.ENOTDIR, f"{what} {path}: {where}, not a folder")
            break
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path, prefix=".probe-"):
            pass
    except OSError as exc:
        raise OutputError(exc.errno or errno.EACCES,
                          f"{what} {path}: cannot write there ({exc.strerror or exc})") from None
    clean_stale_parts(path)   # a set a killed run was moving into place is finished now, not after the work
    return path


# --------------------------------------------------------------------------- sets of files
def _manifest(directory: Path, name: str) -> Path:
    return directory / f".{name}.files.json"


def _move_set(staging: Path, directory: Path, name: str) -> None:
    """Move a committed staging folder's files into ``directory`` and drop the previous set's
    files it lacks (both steps can be repeated: a killed mover is finished by the next)."""
    new = sorted(p.name for p in staging.iterdir() if p.is_file() and p.name != COMMIT)
    manifest = _manifest(directory, name)
    try:
        old = json.loads(manifest.read_text("utf-8"))["files"]
    except (OSError, ValueError, KeyError, TypeError):
        old = []
    recorded = json.loads((staging / COMMIT).read_text("utf-8"))["files"]   # moved ones included
    for f in new:
        os.replace(staging / f, directory / f)
    for f in old:
        if f not in recorded and "/" not in f and not f.startswith("."):
            with contextlib.suppress(FileNotFoundError):
                (directory / f).unlink()
    tmp = directory / part_name(manifest.name)
    tmp.write_text(json.dumps({"files": recorded}), "utf-8")
    os.replace(tmp, manifest)


@contextlib.contextmanager
def _locked(directory: Path):
    """An exclusive lock on ``directory`` (``fcntl.flock`` on a lock file; no lock where
    ``fcntl`` is missing), waited for up to :data:`LOCK_WAIT` seconds."""
    try:
        import fcntl
    except ImportError:   # pragma: no cover - Windows: renames only
        yield
        return
    import time

    with open(directory / ".vobscure.lock", "a+b") as fh:
        deadline = time.monotonic() + LOCK_WAIT
        while True:
            try:
                fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise OutputError(errno.EBUSY, f"{directory}: another vobscure run has been moving its files "
                                                   f"into this folder for {LOCK_WAIT:g} s; try again") from None
                time.sleep(0.05)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


@contextlib.contextmanager
def file_set(directory, name: str):
    """Write a run's files as one set: yields a staging folder to write them into.

    On a normal exit the files are moved into ``directory`` as described in the module's
    docstring; ``name`` names the set (the same for every run whose files replace each
    other's, e.g. ``"compare"``). On an error the staging folder is removed and ``directory``
    is left as it was.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    clean_stale_parts(directory)
    staging = directory / part_name(name)
    staging.mkdir()
    try:
        yield staging
        files = sorted(p.name for p in staging.iterdir() if p.is_file())
        marker = staging / f".{COMMIT}.tmp"
        marker.write_text(json.dumps({"files": files}), "utf-8")
        os.replace(marker, staging / COMMIT)
        with _locked(directory):
            _move_set(staging, directory, name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serializable: {type(value).__name__}")
