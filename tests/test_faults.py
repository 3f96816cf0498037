"""Kills, concurrent runs, file-system faults and damaged input files.

Each fault is provoked for real: a writer process killed with SIGKILL, a pid that no longer
exists, a path under a regular file, a folder in the place of a cache entry, files cut short
or with flipped bytes, an EXR header patched to claim a huge data window.
"""

from __future__ import annotations

import csv
import gc
import io
import json
import os
import signal
import struct
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from vobscure import _io
from vobscure import io as vio
from vobscure.cli import main
from vobscure.experiments import compare as C
from vobscure.experiments.cache import CacheWarning, ReferenceCache

ROOT = Path(__file__).resolve().parents[1]
#: A small, fast comparison: its outputs are what the interruption tests protect.
COMPARE = dict(size=(16, 16), methods="point:4", references=("screen",), quick=True, cache=False,
               progress=False, repeats=1, screen_samples=16)
COMPARE_ARGS = ["compare", "--scene", "slab", "--size", "16", "16", "--methods", "point:4", "--reference",
                "screen", "--quick", "--repeats", "1", "--screen-samples", "16", "--quiet"]
#: Delay added to each rename of the slow run's move in the concurrency test: long enough for
#: the other run to commit in between, short enough for a quick test.
RENAME_DELAY = 0.02


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _part(directory: Path, name: str, pid: int, host: str | None = None) -> Path:
    return directory / f".{name}.{host or _io._host()}.{pid}.0badc0de.part"


def _one_line_error(err: str, path) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and str(path) in lines[0] and "error:" in lines[0], err


def _snapshot(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file() and not p.name.startswith(".")}


# --------------------------------------------------------------------------- stale parts
def test_a_dead_writers_part_is_removed_and_a_live_ones_kept(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        dead = _part(tmp_path, "out.npz", _dead_pid())
        live = _part(tmp_path, "out.npz", sleeper.pid)
        mine = _part(tmp_path, "out.png", os.getpid())
        foreign = _part(tmp_path, "out.npz", _dead_pid(), host="otherhost")
        dead_dir = _part(tmp_path, "compare", _dead_pid())
        dead_dir.mkdir()
        (dead_dir / "results.csv").write_text("half a run")
        for p in (dead, live, mine, foreign):
            p.write_bytes(b"partial")
        _io.atomic_write(tmp_path / "new.txt", lambda fh: fh.write(b"x"))
        assert not dead.exists() and not dead_dir.exists()
        assert live.exists() and mine.exists() and foreign.exists()
        assert not (tmp_path / "results.csv").exists()     # an uncommitted set is dropped
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_committed_set_of_a_dead_writer_is_finished(tmp_path):
    (tmp_path / "a.txt").write_text("old a")
    (tmp_path / "gone.txt").write_text("old, not in the new set")
    (tmp_path / ".run.files.json").write_text(json.dumps({"files": ["a.txt", "gone.txt"]}))
    staging = _part(tmp_path, "run", _dead_pid())
    staging.mkdir()
    (staging / "b.txt").write_text("new b")      # a.txt was moved before the kill
    (tmp_path / "a.txt").write_text("new a")
    (staging / _io.COMMIT).write_text(json.dumps({"files": ["a.txt", "b.txt"]}))
    _io.clean_stale_parts(tmp_path)
    assert _snapshot(tmp_path) == {"a.txt": b"new a", "b.txt": b"new b"}
    assert not staging.exists()


def test_the_next_commands_start_finishes_a_set_killed_while_moving(tmp_path, capsys):
    (tmp_path / "crease_ao.npz").write_text("new")          # moved before the kill
    (tmp_path / "crease_ao_depth.png").write_text("old")
    staging = _part(tmp_path, "crease_ao", _dead_pid())
    staging.mkdir()
    (staging / "crease_ao_depth.png").write_text("new")
    (staging / _io.COMMIT).write_text(json.dumps({"files": ["crease_ao.npz", "crease_ao_depth.png"]}))
    assert main(["render", "--scene", "nosuchscene", "--quiet", "--out", tmp_path]) == 2   # fails after the check
    assert "nosuchscene" in capsys.readouterr().err
    assert _snapshot(tmp_path) == {"crease_ao.npz": b"new", "crease_ao_depth.png": b"new"}


def test_the_next_estimate_removes_a_dead_writers_part(tmp_path, capsys):
    np.savez(tmp_path / "frame.npz", depth=np.full((8, 8), 2.0), normal=np.tile([0.0, 0.0, -1.0], (8, 8, 1)))
    out = tmp_path / "vo"
    out.mkdir()
    stale = _part(out, "frame_point-4.exr", _dead_pid())
    stale.write_bytes(b"killed mid-write")
    status = main(["estimate", "--depth", tmp_path / "frame.npz", "--fov", "40", "--radius", "0.5", "--method",
                   "point:4", "--quiet", "--out", out])
    assert status == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["frame_point-4.exr"]


# --------------------------------------------------------------------------- interrupted and concurrent sets
def test_a_compare_interrupted_mid_write_leaves_the_old_set(tmp_path, monkeypatch):
    out = tmp_path / "out"
    C.compare("slab", out=out, seed=0, **COMPARE)
    before = _snapshot(out)
    assert {"results.csv", "summary.json", "provenance.json", "gallery.png"} <= set(before)
    calls = []

    def failing(path, text):     # the second file: results.csv is written by then
        calls.append(path)
        raise KeyboardInterrupt("interrupted after the first file")

    monkeypatch.setattr(C, "write_text", failing)
    with pytest.raises(KeyboardInterrupt):
        C.compare("slab", out=out, seed=1, **COMPARE)
    assert [p.name for p in calls] == ["results.md"]
    assert _snapshot(out) == before
    assert not [p for p in out.iterdir() if p.name.endswith(".part")]


KILLER = textwrap.dedent("""
    import os, signal, sys
    from vobscure.experiments import common, compare as C
    real, calls = C.write_json, []
    def killing(path, record):
        calls.append(path)
        if len(calls) > 1:        # summary.json written: die before provenance.json
            os.kill(os.getpid(), signal.SIGKILL)
        return real(path, record)
    C.write_json = killing
    C.compare("slab", out=sys.argv[1], seed=1, **{kwargs})
""")


def test_a_compare_killed_mid_write_leaves_the_old_set_and_the_next_run_cleans_up(tmp_path):
    out = tmp_path / "out"
    C.compare("slab", out=out, seed=0, **COMPARE)
    before = _snapshot(out)
    script = KILLER.replace("{kwargs}", repr(COMPARE))
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", script, str(out)], env=env, capture_output=True, timeout=300)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()
    assert _snapshot(out) == before
    parts = [p for p in out.iterdir() if p.name.endswith(".part")]
    assert len(parts) == 1 and parts[0].is_dir()     # the killed run's staging folder
    C.compare("slab", out=out, seed=0, **COMPARE)
    assert not [p for p in out.iterdir() if p.name.endswith(".part")]


def test_two_runs_into_one_folder_end_with_one_runs_set(tmp_path, monkeypatch):
    # run A moves its files slowly; run B commits while A is half way: without the lock B's
    # files would land between A's, and A's later renames would leave a mixed set
    real = os.replace
    a_moving = threading.Event()

    def slow(src, dst):
        if Path(src).is_file() and Path(src).read_bytes() == b"A":
            a_moving.set()
            time.sleep(RENAME_DELAY)
        return real(src, dst)

    monkeypatch.setattr(_io.os, "replace", slow)
    names = [f"f{i}.txt" for i in range(6)]
    errors = []

    def run(tag):
        try:
            with _io.file_set(tmp_path, "run") as stage:
                for n in names:
                    (stage / n).write_text(tag)
                if tag == "B":
                    assert a_moving.wait(10.0)
        except Exception as exc:   # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(tag,)) for tag in ("A", "B")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    contents = [(tmp_path / n).read_text() for n in names]
    assert contents == ["B"] * len(names), f"not one run's set: {contents}"


def test_a_file_of_the_previous_set_that_the_new_one_lacks_is_removed(tmp_path):
    (tmp_path / "mine.txt").write_text("not written by any set")
    with _io.file_set(tmp_path, "run") as stage:
        (stage / "a.txt").write_text("1")
        (stage / "temporal.csv").write_text("1")
    with _io.file_set(tmp_path, "run") as stage:
        (stage / "a.txt").write_text("2")
    assert _snapshot(tmp_path) == {"a.txt": b"2", "mine.txt": b"not written by any set"}


# --------------------------------------------------------------------------- outputs that cannot be written
@pytest.mark.parametrize("command", [
    ["render", "--scene", "slab", "--size", "8", "8", "--rays", "4", "--quiet"],
    COMPARE_ARGS + ["--no-cache"],
    ["estimate", "--fov", "40", "--radius", "0.5", "--quiet"],
    ["figures", "fig4_noise"],
])
def test_an_output_under_a_regular_file_is_one_line_before_the_work(tmp_path, capsys, command):
    blocker = tmp_path / "file"
    blocker.write_text("a file, not a folder")
    if command[0] == "estimate":
        np.save(tmp_path / "d.npy", np.full((8, 8), 2.0))
        command = command + ["--depth", tmp_path / "d.npy"]
    t0 = time.perf_counter()
    status = main(command + ["--out", blocker / "sub" / "dir"])
    seconds = time.perf_counter() - t0
    _, err = capsys.readouterr()
    assert status == 2
    _one_line_error(err, blocker)
    assert "which is a file" in err or "is a file" in err
    assert seconds < 5.0, f"the error came after {seconds:.1f} s: after the work?"


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root writes into read-only folders; covered by the regular-file cases")
def test_an_unwritable_out_of_compare_is_one_line_before_the_work(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        status = main(COMPARE_ARGS + ["--no-cache", "--out", ro / "c"])
    finally:
        ro.chmod(0o700)
    assert status == 2
    _one_line_error(capsys.readouterr().err, ro / "c")


@pytest.mark.filterwarnings("default::vobscure.experiments.cache.CacheWarning")
def test_a_cache_that_is_a_file_warns_once_and_the_run_goes_on(tmp_path, capsys):
    blocker = tmp_path / "cachefile"
    blocker.write_text("not a folder")
    status = main(COMPARE_ARGS + ["--cache", blocker, "--out", tmp_path / "out"])
    out, err = capsys.readouterr()
    assert status == 0, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "warning: cannot write the reference cache directory" in lines[0], err
    assert str(blocker) in lines[0] and "continuing without caching" in lines[0]
    assert (tmp_path / "out" / "results.csv").is_file() and blocker.read_text() == "not a folder"
    assert json.loads((tmp_path / "out" / "provenance.json").read_text())["cache"] is None


@pytest.mark.filterwarnings("default::vobscure.experiments.cache.CacheWarning")
def test_a_folder_named_like_a_cache_entry_is_computed_around(tmp_path, capsys):
    cache = tmp_path / "cache"
    assert main(COMPARE_ARGS + ["--cache", cache, "--out", tmp_path / "a"]) == 0
    entries = sorted(cache.glob("*.npz"))
    assert entries
    for entry in entries:
        entry.unlink()
        entry.mkdir()
    capsys.readouterr()
    assert main(COMPARE_ARGS + ["--cache", cache, "--out", tmp_path / "b"]) == 0
    err = capsys.readouterr().err
    warned = [line for line in err.splitlines() if "warning:" in line]
    assert len(warned) == len(entries) and all("is not a file" in line for line in warned), err
    assert "Traceback" not in err
    rmse = [{k: v for k, v in row.items() if k.endswith("_rmse")}
            for run in "ab" for row in csv.DictReader(io.StringIO((tmp_path / run / "results.csv").read_text()))]
    assert rmse[0] and rmse[: len(rmse) // 2] == rmse[len(rmse) // 2:]    # the same references, computed


def test_a_cache_folder_that_cannot_be_written_warns_once_with_on_error_warn(tmp_path):
    cache = ReferenceCache(tmp_path / "file" / "cache", on_error="warn")
    (tmp_path / "file").write_text("x")
    with pytest.warns(CacheWarning, match="continuing without caching") as record:
        first, hit = cache.get_or_compute({"quantity": "demo"}, lambda: {"x": np.arange(3.0)})
        again, hit_again = cache.get_or_compute({"quantity": "demo"}, lambda: {"x": np.arange(3.0)})
    assert len(record) == 1 and not hit and not hit_again
    assert first["x"].tolist() == again["x"].tolist() == [0.0, 1.0, 2.0]


# --------------------------------------------------------------------------- damaged input files
def _npz_and_npy(tmp_path):
    np.savez(tmp_path / "frame.npz", depth=np.full((16, 16), 2.0), normal=np.tile([0.0, 0.0, -1.0], (16, 16, 1)))
    np.save(tmp_path / "depth.npy", np.full((16, 16), 2.0))
    cases = {}
    for name in ("frame.npz", "depth.npy"):
        data = (tmp_path / name).read_bytes()
        for how, cut in (("truncated", data[: len(data) // 2]), ("empty", b"")):
            path = tmp_path / f"{how}_{name}"
            path.write_bytes(cut)
            cases[path] = "NPZ" if name.endswith(".npz") else "NPY"
    return cases


def test_truncated_and_empty_numpy_files_are_named_unreadable(tmp_path):
    for path, kind in _npz_and_npy(tmp_path).items():
        with pytest.raises(ValueError, match=rf"^not a readable {kind} file: .*{path.name} \(\w+"):
            vio.read_buffers(path, normal_path=None if kind == "NPZ" else tmp_path / "depth.npy")
    gc.collect()    # a leaked file handle would now raise its ResourceWarning (filterwarnings = error)


def test_truncated_and_empty_numpy_files_via_the_cli(tmp_path, capsys):
    for path, kind in _npz_and_npy(tmp_path).items():
        status = main(["estimate", "--depth", path, "--fov", "40", "--radius", "0.5", "--quiet",
                       "--out", tmp_path / "vo.exr"])
        err = capsys.readouterr().err
        assert status == 2
        _one_line_error(err, path)
        assert f"not a readable {kind} file: {path} (" in err
    gc.collect()
    assert not (tmp_path / "vo.exr").exists()


def _exr_cases(tmp_path) -> dict:
    """A valid 64 x 64 EXR written by the library's writer, and three damaged copies."""
    good = tmp_path / "good.exr"
    vio.write_image(good, np.random.default_rng(0).random((64, 64)).astype(np.float32))
    data = good.read_bytes()
    cases = {}
    cases["truncated"] = data[: 3 * len(data) // 4]
    flipped = bytearray(data)
    for k in range(len(data) // 2, len(data), 5):      # the pixel chunks, past the header
        flipped[k] ^= 0xFF
    cases["flipped"] = bytes(flipped)
    # the header's dataWindow attribute: name, type, size (4 bytes), then box2i xmin ymin xmax ymax
    at = data.index(b"dataWindow\0box2i\0") + len(b"dataWindow\0box2i\0") + 4
    assert struct.unpack("<4i", data[at:at + 16]) == (0, 0, 63, 63)
    huge = bytearray(data)
    huge[at:at + 16] = struct.pack("<4i", 0, 0, 99999, 99999)
    cases["huge"] = bytes(huge)
    paths = {}
    for name, content in cases.items():
        paths[name] = tmp_path / f"{name}.exr"
        paths[name].write_bytes(content)
    return paths


def test_damaged_exr_files_are_named_unreadable_not_missing_a_channel(tmp_path, capfd):
    paths = _exr_cases(tmp_path)
    for name, path in paths.items():
        with pytest.raises(ValueError) as info:
            vio.read_buffers(path)
        message = str(info.value)
        assert message.startswith(f"not a readable EXR file: {path} ("), message
        assert "no depth channel" not in message
    assert "100000 x 100000 = 10000000000 pixels" in str(pytest.raises(ValueError, vio.exr_channels, paths["huge"]).value)
    out, err = capfd.readouterr()
    assert out == "" and err == ""      # what the bindings print is in the message, not on the terminal


def test_an_exr_larger_than_the_memory_available_is_refused_with_the_numbers(tmp_path, monkeypatch):
    good = tmp_path / "good.exr"
    vio.write_image(good, np.zeros((64, 64), np.float32))
    monkeypatch.setattr(vio, "_available_memory", lambda: 1024)
    with pytest.raises(ValueError, match=r"64 x 64 pixels need up to 16 KiB, and 1 KiB of memory is available"):
        vio.exr_channels(good)


def test_damaged_exr_files_via_the_cli(tmp_path, capsys):
    for name, path in _exr_cases(tmp_path).items():
        status = main(["estimate", "--depth", path, "--fov", "40", "--radius", "0.5", "--quiet",
                       "--out", tmp_path / "vo.exr"])
        err = capsys.readouterr().err
        assert status == 2
        _one_line_error(err, path)
        assert f"not a readable EXR file: {path} (" in err
