"""The reference cache: hits, keys, verification of every entry, atomic writes, folders."""

from __future__ import annotations

import json
import os
import pickle
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import vobscure as vo
from vobscure.experiments import cache as C
from vobscure.experiments.cache import CacheError, CacheWarning, ReferenceCache

SIZE = (8, 6)
RADIUS = 0.75


@pytest.fixture(scope="module")
def view():
    scene = vo.scenes.crease()
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=SIZE, fov_y=50.0)
    return scene, vo.render_gbuffer(scene, cam)


class Counter:
    """A compute function that counts its calls and returns fresh arrays each time."""

    def __init__(self, value=None):
        self.calls = 0
        self.value = np.arange(6.0).reshape(2, 3) if value is None else value

    def __call__(self):
        self.calls += 1
        return {"value": self.value.copy(), "stderr": np.full(self.value.shape, 0.5)}


FIELDS = {"kind": "test", "quantity": "ao", "radius": 0.5, "seed": 0}


def test_hit_is_bit_identical_and_skips_compute(tmp_path):
    cache = ReferenceCache(tmp_path)
    rng = np.random.default_rng(0)
    counter = Counter(rng.random((5, 7)))
    first, hit = cache.get_or_compute(FIELDS, counter)
    assert not hit and counter.calls == 1
    second, hit = cache.get_or_compute(dict(reversed(list(FIELDS.items()))), counter)   # key order irrelevant
    assert hit and counter.calls == 1
    for name in ("value", "stderr"):
        assert second[name].dtype == first[name].dtype
        assert second[name].tobytes() == first[name].tobytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == [cache.path(FIELDS).name]


def test_estimate_round_trip_and_provenance(tmp_path):
    cache = ReferenceCache(tmp_path)
    est = vo.Estimate(np.array([[0.25, np.nan]]), np.array([[0.01, np.nan]]), 128,
                      bent_normal=np.array([[[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]]))
    out, hit = cache.get_or_compute(FIELDS, lambda: est, info={"note": "demo"})
    assert out is est and not hit
    back, hit = cache.get_or_compute(FIELDS, lambda: pytest.fail("computed again"))
    assert hit and isinstance(back, vo.Estimate) and back.samples == 128
    np.testing.assert_array_equal(back.value, est.value)
    np.testing.assert_array_equal(back.bent_normal, est.bent_normal)
    prov = cache.provenance(FIELDS)
    assert prov["key"] == cache.key(FIELDS) and prov["kind"] == "estimate"
    assert prov["fields"]["radius"] == 0.5 and prov["fields"]["library_version"] == vo.__version__
    assert prov["reference_code_version"] == C.REFERENCE_CODE_VERSION and prov["info"] == {"note": "demo"}
    assert prov["compute_seconds"] >= 0 and prov["created"][:2] == "20"
    assert prov["arrays"]["value"] == {"dtype": "<f8", "shape": [1, 2]}


def test_ground_truth_cached_matches_ground_truth(tmp_path, view):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    a, hit_a = C.ground_truth_cached(scene, gb, cache=cache, quantity="ao", radius=RADIUS, rays=16,
                                     seed=1, progress=False)
    b, hit_b = C.ground_truth_cached(scene, gb, cache=cache, quantity="ao", radius=RADIUS, rays=16,
                                     seed=1, progress=False, threads=1)    # threads: not in the key
    direct = vo.ground_truth(scene, gb, quantity="ao", radius=RADIUS, rays=16, seed=1, progress=False)
    assert (hit_a, hit_b) == (False, True)
    for e in (a, b):
        assert e.value.tobytes() == direct.value.tobytes() and e.stderr.tobytes() == direct.stderr.tobytes()
        assert e.samples == direct.samples
    # the provenance names what was computed; its fields are the key
    prov = cache.provenance(_fields_of_only_entry(tmp_path))
    assert prov["info"] == {"scene_name": "crease"} and prov["fields"]["quantity"] == "ao"
    assert prov["fields"]["params"] == {"radius": RADIUS, "rays": 16, "weighting": "cosine", "groups": 8}
    assert prov["fields"]["camera"] == gb.camera.to_dict() and prov["fields"]["seed"] == 1


def _fields_of_only_entry(directory):
    """The key fields of the only entry in ``directory`` (read from its provenance)."""
    (path,) = directory.glob("*.npz")
    with np.load(path) as data:
        prov = json.loads(str(data["provenance"]))
    fields = dict(prov["fields"])
    del fields["reference_code_version"], fields["library_version"]
    return fields


def test_screen_reference_cached_matches_vo_reference(tmp_path, view):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    kw = dict(radius=RADIUS, samples=64, normal_clamp=True, seed=2)
    a, hit_a = C.screen_reference_cached(gb, scene, cache=cache, **kw)
    b, hit_b = C.screen_reference_cached(gb, cache=cache, **kw)       # the scene is not in the key
    direct = vo.vo_reference(gb, **kw)
    assert (hit_a, hit_b) == (False, True)
    assert isinstance(a, vo.Estimate) and isinstance(b, vo.Estimate)
    for name in ("value", "stderr"):
        x, y, z = getattr(a, name), getattr(direct, name), getattr(b, name)
        assert x.tobytes() == y.tobytes() == z.tobytes() and z.shape == gb.shape
    assert a.samples == direct.samples == b.samples
    # another G-buffer dtype is another input
    _, hit = C.screen_reference_cached(gb.astype(np.float32), cache=cache, **kw)
    assert not hit


def test_key_changes_with_every_input(tmp_path, view, monkeypatch):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    base = dict(quantity="volumetric", radius=RADIUS, samples=16, rays=16, seed=0, progress=False)

    def hit(scene=scene, gb=gb, **changes):
        return C.ground_truth_cached(scene, gb, cache=cache, **{**base, **changes})[1]

    assert not hit() and hit()
    other_scene = vo.scenes.crease(length=3.0)
    cam2 = vo.Camera.look_at((2.0, 2.1, 3.0), (0.5, 0.3, 0.0), size=SIZE, fov_y=50.0)
    assert not hit(scene=other_scene, gb=vo.render_gbuffer(other_scene, gb.camera))   # scene
    assert not hit(gb=vo.render_gbuffer(scene, cam2))                                  # camera
    assert not hit(quantity="obscurance")                                              # quantity
    assert not hit(radius=0.5)                                                         # parameters
    assert not hit(samples=32)
    assert not hit(falloff="quadratic")
    assert not hit(normal_clamp=True)
    assert not hit(seed=1)                                                             # seed
    assert hit(rays=64)                      # rays do not enter a volumetric reference
    monkeypatch.setattr(C, "REFERENCE_CODE_VERSION", C.REFERENCE_CODE_VERSION + "+test")
    assert not hit()                                                                   # code version
    monkeypatch.setattr(vo, "__version__", vo.__version__ + "+test")
    assert not hit()                                                                   # library version
    assert len(list(tmp_path.glob("*.npz"))) == 11


def test_equivalent_calls_share_an_entry(tmp_path, view):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    kw = dict(cache=cache, rays=16, seed=0, progress=False)
    assert not C.ground_truth_cached(scene, gb, quantity="ao", radius=None, **kw)[1]
    assert C.ground_truth_cached(scene, gb, quantity="ao", radius=float("inf"), samples=99, **kw)[1]
    assert not C.ground_truth_cached(scene, gb, quantity="obscurance", radius=RADIUS, **kw)[1]
    assert C.ground_truth_cached(scene, gb, quantity="obscurance", radius=RADIUS, falloff="linear", **kw)[1]
    assert C.ground_truth_cached(scene, gb, quantity="obscurance", radius=int(1) * RADIUS, groups=8, **kw)[1]


def test_key_fields_canonical():
    assert C.cache_key({"r": np.float64(0.5), "t": (1, 2)}) == C.cache_key({"t": [1, 2], "r": 0.5})
    assert C.cache_key({"r": 0.5}) != C.cache_key({"r": 0.5000000000000001})
    with pytest.raises(ValueError, match="key_fields"):
        C.cache_key({"a": np.zeros(3)})
    with pytest.raises(ValueError, match="key_fields"):
        C.cache_key({"a": object()})
    with pytest.raises(ValueError, match="key_fields"):
        C.cache_key({"library_version": "1"})
    with pytest.raises(ValueError, match="key_fields"):
        C.cache_key([1, 2])


# ----------------------------------------------------------------------------- never trusted
def _tamper_array(path):
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["value"] = arrays["value"].copy()
    arrays["value"].flat[0] += 1e-12
    np.savez_compressed(path, **arrays)


def _foreign_key(path):
    """Replace the entry by a complete, valid entry of another key."""
    other = ReferenceCache(path.parent / "other")
    other.get_or_compute({**FIELDS, "seed": 99}, Counter())
    (src,) = (path.parent / "other").glob("*.npz")
    os.replace(src, path)


def _bad_shape(path):
    with np.load(path) as data:
        prov = json.loads(str(data["provenance"]))
        arrays = {k: data[k] for k in data.files if k != "provenance"}
    arrays["value"] = arrays["value"].reshape(-1)
    prov["arrays"]["value"]["shape"] = list(arrays["value"].shape)
    np.savez_compressed(path, provenance=np.array(json.dumps(prov)), **arrays)


CORRUPTIONS = {
    "truncated": lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]),
    "empty": lambda p: p.write_bytes(b""),
    "random bytes": lambda p: p.write_bytes(np.random.default_rng(0).bytes(2000)),
    "foreign npz": lambda p: np.savez(p, value=np.zeros((2, 3))),
    "foreign zip": lambda p: zipfile.ZipFile(p, "w").writestr("x.txt", "hello"),
    "other key": _foreign_key,
    "tampered array": _tamper_array,
    "flipped byte": lambda p: p.write_bytes(_flip(p.read_bytes())),
    "reshaped array": _bad_shape,
    "npy file": lambda p: p.write_bytes(_npy_bytes()),
}


def _npy_bytes() -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, np.zeros((2, 3)))
    return buf.getvalue()


def _flip(data: bytes) -> bytes:
    b = bytearray(data)
    b[len(b) // 3] ^= 0xFF
    return bytes(b)


@pytest.mark.parametrize("corruption", sorted(CORRUPTIONS))
def test_corrupted_entries_are_detected_and_recomputed(tmp_path, corruption):
    cache = ReferenceCache(tmp_path)
    counter = Counter()
    good, _ = cache.get_or_compute(FIELDS, counter)
    path = cache.path(FIELDS)
    CORRUPTIONS[corruption](path)
    with pytest.warns(CacheWarning, match="not usable"):
        again, hit = cache.get_or_compute(FIELDS, counter, expected={"value": (2, 3)})
    assert not hit and counter.calls == 2
    np.testing.assert_array_equal(again["value"], good["value"])
    # the entry was overwritten with a good one: the next call is a clean hit
    third, hit = cache.get_or_compute(FIELDS, counter, expected={"value": (2, 3)})
    assert hit and counter.calls == 2 and third["value"].tobytes() == good["value"].tobytes()


def test_unexpected_shape_is_recomputed(tmp_path):
    cache = ReferenceCache(tmp_path)
    counter = Counter()
    cache.get_or_compute(FIELDS, counter)
    with pytest.warns(CacheWarning, match="expected"):
        _, hit = cache.get_or_compute(FIELDS, counter, expected={"value": (3, 2)})
    assert not hit and counter.calls == 2


# ----------------------------------------------------------------------------- atomic writes
class Interrupted(Exception):
    pass


def _failing_savez(fh, **arrays):
    fh.write(b"PK\x03\x04 partial")
    raise Interrupted("killed during the write")


def test_interrupted_write_keeps_the_previous_entry(tmp_path, monkeypatch):
    cache = ReferenceCache(tmp_path)
    good, _ = cache.get_or_compute(FIELDS, Counter())
    before = cache.path(FIELDS).read_bytes()
    monkeypatch.setattr(np, "savez_compressed", _failing_savez)
    with pytest.raises(Interrupted):
        cache.store(FIELDS, {"value": np.ones((2, 3)), "stderr": np.ones((2, 3))})
    with pytest.raises(Interrupted):      # a new entry: nothing is left behind
        cache.get_or_compute({**FIELDS, "seed": 5}, Counter())
    monkeypatch.undo()
    assert cache.path(FIELDS).read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [cache.path(FIELDS).name]   # no .part files
    back, hit = cache.get_or_compute(FIELDS, Counter())
    assert hit and back["value"].tobytes() == good["value"].tobytes()


def test_keyboard_interrupt_during_write_leaves_no_file(tmp_path, monkeypatch):
    def interrupt(fh, **arrays):
        fh.write(b"partial")
        raise KeyboardInterrupt

    cache = ReferenceCache(tmp_path)
    monkeypatch.setattr(np, "savez_compressed", interrupt)
    with pytest.raises(KeyboardInterrupt):
        cache.get_or_compute(FIELDS, Counter())
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- folders
def test_missing_directory_is_created(tmp_path):
    cache = ReferenceCache(tmp_path / "a" / "b")
    assert not (tmp_path / "a").exists()       # nothing is made until the first write
    _, hit = cache.get_or_compute(FIELDS, Counter())
    assert not hit and cache.path(FIELDS).is_file()


def test_unwritable_directory_is_a_clear_error_before_computing(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    cache = ReferenceCache(blocker / "cache")
    counter = Counter()
    with pytest.raises(CacheError, match="cannot write the reference cache directory.*enabled=False"):
        cache.get_or_compute(FIELDS, counter)
    assert counter.calls == 0


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root may write to read-only folders")
def test_read_only_directory_is_a_clear_error(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(CacheError, match="cannot write"):
            ReferenceCache(ro).get_or_compute(FIELDS, Counter())
    finally:
        ro.chmod(0o700)


def test_disabled_cache_always_computes_and_writes_nothing(tmp_path, view):
    cache = ReferenceCache(tmp_path / "never", enabled=False)
    counter = Counter()
    for _ in range(2):
        _, hit = cache.get_or_compute(FIELDS, counter)
        assert not hit
    assert counter.calls == 2 and not (tmp_path / "never").exists()
    scene, gb = view
    _, hit = C.ground_truth_cached(scene, gb, cache=None, rays=8, progress=False)
    assert not hit


def test_default_directory(monkeypatch, tmp_path):
    monkeypatch.setenv("VOBSCURE_CACHE", str(tmp_path / "env"))
    assert ReferenceCache().directory == tmp_path / "env"
    monkeypatch.setenv("VOBSCURE_CACHE", "~/env")
    assert C.default_directory() == Path("~/env").expanduser()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the XDG base directories are Linux's")
def test_default_directory_follows_xdg_on_linux(monkeypatch, tmp_path):
    monkeypatch.delenv("VOBSCURE_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert C.default_directory() == tmp_path / "xdg" / "vobscure"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert C.default_directory() == tmp_path / "home" / ".cache" / "vobscure"


def test_pickles_for_workers(tmp_path):
    cache = ReferenceCache(tmp_path, enabled=False)
    assert pickle.loads(pickle.dumps(cache)) == cache


def test_bad_arguments(tmp_path, view):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    with pytest.raises(ValueError, match="compute"):
        cache.get_or_compute(FIELDS, "not callable")
    with pytest.raises(ValueError, match="compute"):
        cache.get_or_compute(FIELDS, lambda: [1, 2, 3])
    with pytest.raises(ValueError, match="compute"):
        cache.get_or_compute(FIELDS, lambda: {"provenance": np.zeros(2)})
    with pytest.raises(ValueError, match="directory"):
        ReferenceCache(3)
    with pytest.raises(ValueError, match="seed"):
        C.ground_truth_cached(scene, gb, cache=cache, seed=np.random.default_rng(0))
    with pytest.raises(ValueError, match="seed"):
        C.screen_reference_cached(gb, cache=cache, radius=1.0, seed=None)
    with pytest.raises(ValueError, match="cache"):
        C.screen_reference_cached(gb, cache=str(tmp_path), radius=1.0)
    with pytest.raises(ValueError, match="quantity"):
        C.ground_truth_cached(scene, gb, cache=cache, quantity="vo")
    with pytest.raises(ValueError, match="radius"):
        C.ground_truth_cached(scene, gb, cache=cache, quantity="volumetric")
    with pytest.raises(ValueError, match="gbuffer"):
        C.ground_truth_cached(scene, gb.depth, cache=cache)
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- defaults from the cached function
def test_cached_wrappers_take_the_defaults_of_what_they_cache(tmp_path, view, monkeypatch):
    """The cached call with no options computes what the direct call with no options does;
    the wrappers' signatures are those of ground_truth / vo_reference plus cache."""
    import inspect

    scene, gb = view
    for wrapper, fn, first in ((C.ground_truth_cached, vo.ground_truth, ["scene", "gbuffer"]),
                               (C.screen_reference_cached, vo.vo_reference, ["gbuffer", "scene"])):
        sig, own = inspect.signature(wrapper), inspect.signature(fn)
        keywords = {n: p.default for n, p in own.parameters.items() if p.kind is p.KEYWORD_ONLY}
        assert list(sig.parameters) == first + ["cache"] + list(keywords)
        assert {n: sig.parameters[n].default for n in keywords} == keywords
    cached, _ = C.ground_truth_cached(scene, gb, cache=None, quantity="volumetric", radius=RADIUS)
    direct = vo.ground_truth(scene, gb, quantity="volumetric", radius=RADIUS)
    assert cached.value.tobytes() == direct.value.tobytes() and cached.samples == direct.samples
    screen, _ = C.screen_reference_cached(gb, cache=None, radius=RADIUS)
    assert screen.value.tobytes() == vo.vo_reference(gb, radius=RADIUS).value.tobytes()
    # an unknown keyword is an error, not a silently ignored key field
    with pytest.raises(TypeError, match="ray_count"):
        C.ground_truth_cached(scene, gb, cache=None, ray_count=3)
    with pytest.raises(TypeError, match="radius"):
        C.screen_reference_cached(gb, cache=None)


def test_defaults_fill_the_key(tmp_path, view):
    scene, gb = view
    cache = ReferenceCache(tmp_path)
    kw = dict(cache=cache, quantity="volumetric", radius=RADIUS, samples=16, seed=0)
    assert not C.ground_truth_cached(scene, gb, **kw)[1]
    assert C.ground_truth_cached(scene, gb, votes=3, groups=8, normal_clamp=False, falloff="constant",
                                 progress=True, threads=1, **kw)[1]
    assert C.ground_truth_cached("crease", gb, **kw)[1]                  # the same scene, by name
    assert not C.ground_truth_cached(scene, gb, votes=5, **kw)[1]        # votes change the numbers
    screen = dict(cache=cache, radius=RADIUS, samples=32, seed=0)
    assert not C.screen_reference_cached(gb, **screen)[1]
    assert C.screen_reference_cached(gb, "crease", groups=8, fetch="bilinear", progress=True, **screen)[1]
    assert not C.screen_reference_cached(gb, groups=4, **screen)[1]
