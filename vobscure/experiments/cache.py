"""A disk cache of expensive references (ray-cast ground truths, converged screen-space VO).

A reference is stored under a key that is the SHA-256 of a canonical JSON record of
everything its numbers depend on: a hash of the scene's geometry or of the G-buffer, the
camera, the quantity and its parameters, the seed, :data:`REFERENCE_CODE_VERSION` and the
library's version. Each entry is one ``.npz`` file, written atomically (:mod:`vobscure._io`),
that holds the arrays and a provenance record: the key and its fields, the versions, the
date, the seconds the computation took, the shape and dtype of every array and a SHA-256
checksum of their bytes.

An entry is never trusted: on every load the file must parse, its stored key must equal
the requested one and its arrays must have the recorded (and, when the caller says, the
expected) shapes and dtypes and the recorded checksum. On any mismatch a
:class:`CacheWarning` says what was wrong with which file, and the reference is recomputed
and the entry overwritten.

Where the cache lives: the ``directory`` given, else the environment variable
``VOBSCURE_CACHE``, else the user cache folder of the platform (:func:`default_directory`;
on Linux ``$XDG_CACHE_HOME/vobscure``, else ``~/.cache/vobscure``). It is created on the
first write.

Examples
--------
>>> import tempfile, numpy as np, vobscure as vo
>>> from vobscure.experiments.cache import ReferenceCache, ground_truth_cached
>>> tmp = tempfile.TemporaryDirectory()
>>> cache = ReferenceCache(tmp.name)
>>> scene = vo.scenes.slab()
>>> gb = vo.render_gbuffer(scene, vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1),
...                                                  size=(4, 4), ortho_height=2.0))
>>> a, hit = ground_truth_cached(scene, gb, cache=cache, quantity="ao", radius=1.0, rays=16,
...                              seed=0, progress=False)
>>> b, hit_again = ground_truth_cached(scene, gb, cache=cache, quantity="ao", radius=1.0, rays=16,
...                                    seed=0, progress=False)
>>> hit, hit_again, bool(np.array_equal(a.value, b.value))
(False, True, True)
>>> tmp.cleanup()
"""

from __future__ import annotations

import datetime
import hashlib
import inspect
import json
import math
import os
import tempfile
import time
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import platformdirs

from .._io import save_npz
from .._validate import check_choice, check_int, check_positive
from ..estimate import Estimate
from .. import groundtruth as _groundtruth
from .. import screenspace as _screenspace
from ..scenes import as_scene

__all__ = ["ReferenceCache", "CacheWarning", "CacheError", "REFERENCE_CODE_VERSION", "CACHE_FORMAT",
           "CACHE_ENV", "default_directory", "cache_key", "canonical_json", "scene_digest",
           "gbuffer_digest", "array_digest", "ground_truth_cached", "screen_reference_cached",
           "GROUND_TRUTH_KEY_PARAMS"]

#: Version of the code that computes references (ground truth, G-buffer rendering,
#: ``vo_reference``). Bump it whenever a change alters their numbers: every cached entry made
#: before then stops matching and is recomputed.
REFERENCE_CODE_VERSION = "9"
#: Layout of an entry file (the provenance fields and array records read back by :meth:`load`).
CACHE_FORMAT = 1
#: Environment variable naming the default cache folder.
CACHE_ENV = "VOBSCURE_CACHE"

# Array name that save_npz uses for the provenance record; results may not use it.
_PROVENANCE = "provenance"
_ESTIMATE_ARRAYS = ("value", "stderr", "bent_normal")


class CacheWarning(UserWarning):
    """A cache entry was unreadable, foreign, stale or tampered with; it is being recomputed."""


class CacheError(OSError):
    """The cache folder cannot be created or written."""


# ----------------------------------------------------------------------------- keys
def default_directory() -> Path:
    """The default cache folder: ``$VOBSCURE_CACHE`` if set, else the user cache folder that
    ``platformdirs`` gives for ``vobscure``.

    That is ``$XDG_CACHE_HOME/vobscure``, else ``~/.cache/vobscure``, on Linux (platformdirs
    follows the XDG base directory specification; its recent versions ignore a relative
    ``XDG_CACHE_HOME``, as the specification asks), ``~/Library/Caches/vobscure`` on macOS and
    ``%LOCALAPPDATA%\\vobscure\\Cache`` on Windows.

    Examples
    --------
    >>> default_directory().name in ("vobscure", "Cache") or "VOBSCURE_CACHE" in os.environ
    True
    """
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    return platformdirs.user_cache_path("vobscure", appauthor=False)


def _plain(value):
    """``json.dumps`` default: NumPy scalars, paths, tuples, Cameras; arrays are refused."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "to_dict") and callable(value.to_dict):
        return value.to_dict()
    if isinstance(value, np.ndarray):
        raise ValueError("key_fields must not hold arrays; hash them first (array_digest)")
    raise ValueError(f"key_fields holds a value of type {type(value).__name__} that has no "
                     f"canonical JSON form: {value!r}")


def canonical_json(fields: Mapping) -> str:
    """The one JSON text of ``fields``: sorted keys, no spaces, floats written exactly.

    NumPy scalars become Python numbers, tuples lists, paths strings and objects with a
    ``to_dict`` method (a :class:`~vobscure.Camera`) their dict. Note that ``1`` and ``1.0``
    differ: normalize numbers before building a key (the helpers of this module do).

    Examples
    --------
    >>> canonical_json({"b": (1, 2.5), "a": np.float64(0.1)})
    '{"a":0.1,"b":[1,2.5]}'
    """
    if not isinstance(fields, Mapping):
        raise ValueError(f"key_fields must be a mapping of str to JSON-able values, got {type(fields).__name__}")
    try:
        return json.dumps(fields, sort_keys=True, separators=(",", ":"), default=_plain)
    except TypeError as exc:  # e.g. non-string keys that cannot be sorted
        raise ValueError(f"key_fields cannot be written as canonical JSON: {exc}") from None


def _library_version() -> str:
    import vobscure

    return str(getattr(vobscure, "__version__", "unknown"))


def _versioned(fields: Mapping) -> dict:
    """``fields`` plus the versions of the reference code and of the library."""
    record = json.loads(canonical_json(fields))
    for name in ("reference_code_version", "library_version"):
        if name in record:
            raise ValueError(f"key_fields must not set {name!r}; the cache adds it")
    record["reference_code_version"] = REFERENCE_CODE_VERSION
    record["library_version"] = _library_version()
    return record


def cache_key(fields: Mapping) -> str:
    """SHA-256 (hex) of the canonical JSON of ``fields`` plus :data:`REFERENCE_CODE_VERSION`
    and the library's version.

    Examples
    --------
    >>> k = cache_key({"quantity": "ao", "radius": 0.5})
    >>> len(k), k == cache_key({"radius": 0.5, "quantity": "ao"}), k == cache_key({"quantity": "ao", "radius": 0.25})
    (64, True, False)
    """
    return hashlib.sha256(canonical_json(_versioned(fields)).encode()).hexdigest()


def array_digest(*arrays) -> str:
    """SHA-256 (hex) of arrays: dtype, shape and C-order bytes of each, in order."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def scene_digest(scene) -> str:
    """SHA-256 (hex) of a scene's geometry: every mesh's name, vertices, faces and smoothing
    angle (which decides its shading normals), and the alpha test of alpha-tested meshes.
    The scene's name and suggested view are not part of it.

    Examples
    --------
    >>> import vobscure as vo
    >>> scene_digest(vo.scenes.slab()) == scene_digest(vo.scenes.slab())
    True
    >>> scene_digest(vo.scenes.slab()) == scene_digest(vo.scenes.slab(thickness=2.0))
    False
    """
    scene = as_scene(scene)
    h = hashlib.sha256()
    for name, mesh in scene.meshes.items():
        h.update(json.dumps([name, scene.smooth_angle.get(name)]).encode())
        h.update(array_digest(np.asarray(mesh.vertices, dtype=np.float64),
                              np.asarray(mesh.faces, dtype=np.int64)).encode())
    for name, mask in scene.alpha.items():   # alpha-tested meshes: their holes change every ray
        h.update(json.dumps(["alpha", name, mask.cutoff]).encode())
        h.update(array_digest(mask.uv, mask.texture).encode())
    return h.hexdigest()


def gbuffer_digest(gbuffer, *, world: bool = False) -> str:
    """SHA-256 (hex) of what a reference reads from a G-buffer.

    ``world=False``: the view-space ``depth`` and ``normal`` images and ``valid`` (the
    inputs of the screen-space estimators, in their dtype). ``world=True``: ``valid`` and the
    per-hit world positions, shading and geometric normals (the inputs of the ground truth).
    """
    if world:
        hits = gbuffer.hits
        return array_digest(gbuffer.valid, hits["index"], hits["world_position"], hits["world_normal"],
                            hits["world_geometric_normal"])
    return array_digest(gbuffer.depth, gbuffer.normal, gbuffer.valid)


# ----------------------------------------------------------------------------- entries
def _as_arrays(result, name: str = "compute()") -> tuple[str, dict, dict]:
    """(kind, arrays, extra provenance) of an Estimate or a dict of arrays."""
    if isinstance(result, Estimate):
        arrays = {"value": np.asarray(result.value), "stderr": np.asarray(result.stderr)}
        if result.bent_normal is not None:
            arrays["bent_normal"] = np.asarray(result.bent_normal)
        return "estimate", arrays, {"samples": int(result.samples)}
    if isinstance(result, Mapping) and result:
        arrays = {}
        for key, value in result.items():
            if not isinstance(key, str) or not key or key == _PROVENANCE:
                raise ValueError(f"{name} returned a dict with the key {key!r}; keys must be "
                                 f"non-empty strings other than {_PROVENANCE!r}")
            arr = np.asarray(value)
            if arr.dtype.hasobject:
                raise ValueError(f"{name} returned {key!r} of dtype object; only numeric arrays are cached")
            arrays[key] = arr
        return "arrays", arrays, {}
    raise ValueError(f"{name} must return an Estimate or a non-empty dict of arrays, "
                     f"got {type(result).__name__}")


def _checksum(arrays: Mapping) -> str:
    names = sorted(arrays)
    h = hashlib.sha256(json.dumps(names).encode())
    h.update(array_digest(*(arrays[n] for n in names)).encode())
    return h.hexdigest()


class _Invalid(Exception):
    """A cache entry that must not be used; the message says why."""


class ReferenceCache:
    """A folder of cached references, each verified on load and recomputed when in doubt.

    Parameters
    ----------
    directory : str or Path, optional
        The cache folder; default :func:`default_directory`. Created on the first write.
    enabled : bool
        False: :meth:`get_or_compute` always computes and nothing is read or written.
    on_error : {"raise", "warn"}
        When the folder or an entry cannot be written: ``"raise"`` a :class:`CacheError`
        (before any computing), or ``"warn"`` once with a :class:`CacheWarning` and go on
        without storing (entries already there are still read).

    Notes
    -----
    Entries are ``<quantity>-<key>.npz`` files. Two processes that compute the same entry at
    once both write it atomically; the last rename wins and both files are complete. Delete
    the folder to clear the cache.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> tmp = tempfile.TemporaryDirectory()
    >>> cache = ReferenceCache(tmp.name)
    >>> fields = {"quantity": "demo", "n": 3}
    >>> result, hit = cache.get_or_compute(fields, lambda: {"x": np.arange(3.0)})
    >>> hit, result["x"].tolist()
    (False, [0.0, 1.0, 2.0])
    >>> result, hit = cache.get_or_compute(fields, lambda: {"x": np.zeros(3)})
    >>> hit, result["x"].tolist()
    (True, [0.0, 1.0, 2.0])
    >>> tmp.cleanup()
    """

    def __init__(self, directory=None, *, enabled: bool = True, on_error: str = "raise"):
        check_choice(on_error, "on_error", ("raise", "warn"))
        if directory is None:
            directory = default_directory()
        elif not isinstance(directory, (str, os.PathLike)):
            raise ValueError(f"directory must be a path (str or Path) or None, got {type(directory).__name__}")
        self.directory = Path(directory).expanduser()
        self.enabled = bool(enabled)
        self.on_error = on_error
        self._writable = False
        self._unwritable = False   # on_error="warn" and the folder cannot be written: read only

    def __repr__(self) -> str:
        return f"ReferenceCache({str(self.directory)!r}, enabled={self.enabled})"

    def __eq__(self, other):
        return (isinstance(other, ReferenceCache) and other.directory == self.directory
                and other.enabled == self.enabled)

    def __hash__(self):
        return hash((self.directory, self.enabled))

    def __getstate__(self):
        # the writability probe is per process: a worker on another machine checks again
        return {"directory": self.directory, "enabled": self.enabled, "on_error": self.on_error,
                "_writable": False, "_unwritable": False}

    # ------------------------------------------------------------------ paths
    def key(self, key_fields: Mapping) -> str:
        """The entry's key: :func:`cache_key` of ``key_fields``."""
        return cache_key(key_fields)

    def path(self, key_fields: Mapping) -> Path:
        """Where the entry of ``key_fields`` lives (whether or not it exists)."""
        label = str(key_fields.get("quantity", "entry")) if isinstance(key_fields, Mapping) else "entry"
        label = "".join(c if c.isalnum() or c in "-_" else "_" for c in label)[:40] or "entry"
        return self.directory / f"{label}-{self.key(key_fields)}.npz"

    def _ensure_writable(self) -> bool:
        """Create the folder and check that a file can be made in it, before any computing.

        False (after one :class:`CacheWarning`) when it cannot and ``on_error="warn"``: the
        cache is then read only; else a :class:`CacheError`.
        """
        if self._writable or self._unwritable:
            return self._writable
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryFile(dir=self.directory, prefix=".probe-"):
                pass
        except OSError as exc:
            reason = f"{type(exc).__name__}: {exc.strerror or exc}"
            if self.on_error == "warn":
                self._unwritable = True
                if not self.directory.is_dir():
                    self.enabled = False   # nothing to read either (a job's provenance then names no cache)
                warnings.warn(f"cannot write the reference cache directory {str(self.directory)!r} ({reason}); "
                              f"continuing without caching (references are computed, not stored)",
                              CacheWarning, stacklevel=4)
                return False
            raise CacheError(
                f"cannot write the reference cache directory {str(self.directory)!r} "
                f"({reason}). Choose another directory "
                f"(ReferenceCache(directory=...), the {CACHE_ENV} environment variable) or "
                f"disable the cache (ReferenceCache(enabled=False))."
            ) from exc
        self._writable = True
        return True

    # ------------------------------------------------------------------ load / store
    def load(self, key_fields: Mapping, *, expected: Mapping | None = None):
        """The verified entry of ``key_fields``, or None when there is none or it fails a check.

        Parameters
        ----------
        key_fields : mapping
        expected : mapping of str to tuple, optional
            Shapes the named arrays must have (e.g. ``{"value": (H, W)}``).

        Returns
        -------
        Estimate, dict of str to ndarray, or None
            A failed check issues a :class:`CacheWarning` naming the file and the reason.
        """
        if not self.enabled:
            return None
        key = self.key(key_fields)
        path = self.path(key_fields)
        if not path.exists():
            return None
        if not path.is_file():
            warnings.warn(f"reference cache entry {str(path)!r} is not a file (a folder of that name?); "
                          f"computing the reference without the cache", CacheWarning, stacklevel=3)
            return None
        try:
            return self._read(path, key, expected)
        except _Invalid as exc:
            reason = str(exc)
        except Exception as exc:   # noqa: BLE001 - any failure to parse means: do not trust it
            reason = f"unreadable ({type(exc).__name__}: {exc})"
        warnings.warn(f"reference cache entry {str(path)!r} is not usable: {reason}; recomputing it",
                      CacheWarning, stacklevel=3)
        return None

    def _read(self, path: Path, key: str, expected: Mapping | None):
        # our own handle: np.load leaks the one it opens when the zip directory is damaged
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
            if _PROVENANCE not in data.files:
                raise _Invalid("it holds no provenance record (not a vobscure cache entry)")
            try:
                prov = json.loads(str(data[_PROVENANCE][()]))
            except (ValueError, TypeError) as exc:
                raise _Invalid(f"its provenance record is not JSON ({exc})") from None
            if not isinstance(prov, dict) or prov.get("format") != CACHE_FORMAT:
                got = prov.get("format") if isinstance(prov, dict) else type(prov).__name__
                raise _Invalid(f"its format is {got!r}, expected {CACHE_FORMAT}")
            if prov.get("key") != key:
                raise _Invalid(f"it was stored under another key ({str(prov.get('key'))[:16]}..., "
                               f"requested {key[:16]}...)")
            records = prov.get("arrays")
            if not isinstance(records, dict) or not records:
                raise _Invalid("its provenance lists no arrays")
            missing = sorted(set(records) - set(data.files))
            if missing:
                raise _Invalid(f"arrays {missing} listed in its provenance are missing")
            arrays = {}
            for name, rec in records.items():
                arr = data[name]
                if arr.dtype.str != rec.get("dtype") or list(arr.shape) != rec.get("shape"):
                    raise _Invalid(f"array {name!r} is {arr.dtype.str} {arr.shape}, its record says "
                                   f"{rec.get('dtype')} {tuple(rec.get('shape') or ())}")
                arrays[name] = arr
        for name, shape in (expected or {}).items():
            if name not in arrays:
                raise _Invalid(f"it has no array {name!r}")
            if arrays[name].shape != tuple(shape):
                raise _Invalid(f"array {name!r} has shape {arrays[name].shape}, expected {tuple(shape)}")
        if _checksum(arrays) != prov.get("checksum"):
            raise _Invalid("the checksum of its arrays does not match (modified or damaged)")
        if prov.get("kind") == "estimate":
            if not {"value", "stderr"} <= set(arrays) or not set(arrays) <= set(_ESTIMATE_ARRAYS):
                raise _Invalid(f"an Estimate entry with the arrays {sorted(arrays)}")
            samples = prov.get("samples")
            if not isinstance(samples, int):
                raise _Invalid(f"an Estimate entry whose sample count is {samples!r}")
            return Estimate(value=arrays["value"], stderr=arrays["stderr"], samples=samples,
                            bent_normal=arrays.get("bent_normal"))
        if prov.get("kind") != "arrays":
            raise _Invalid(f"unknown kind of entry {prov.get('kind')!r}")
        return arrays

    def store(self, key_fields: Mapping, result, *, compute_seconds: float | None = None,
              info: Mapping | None = None) -> Path | None:
        """Write ``result`` (an Estimate or a dict of arrays) as the entry of ``key_fields``.

        Atomic: an interrupted write leaves the previous entry (or none) in place. ``info``
        is extra provenance (JSON-able, not part of the key). Returns the file, or None when
        the cache is disabled.

        Raises
        ------
        CacheError
            When the folder cannot be created or written (with ``on_error="warn"``: a
            :class:`CacheWarning`, and None is returned).
        """
        kind, arrays, extra = _as_arrays(result, "result")
        if not self.enabled or not self._ensure_writable():
            return None
        versioned = _versioned(key_fields)
        provenance = {
            "format": CACHE_FORMAT,
            "key": self.key(key_fields),
            "fields": versioned,
            "reference_code_version": REFERENCE_CODE_VERSION,
            "library_version": _library_version(),
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "compute_seconds": None if compute_seconds is None else round(float(compute_seconds), 6),
            "kind": kind,
            "arrays": {n: {"dtype": a.dtype.str, "shape": list(a.shape)} for n, a in arrays.items()},
            "checksum": _checksum(arrays),
            "info": json.loads(canonical_json(info or {})),
            **extra,
        }
        path = self.path(key_fields)
        if self.on_error == "warn" and path.exists() and not path.is_file():
            return None     # load() warned about what is in the way
        try:
            return save_npz(path, provenance, **arrays)
        except OSError as exc:
            if self.on_error == "warn":
                warnings.warn(f"cannot write the reference cache entry {str(path)!r} ({type(exc).__name__}: "
                              f"{exc.strerror or exc}); continuing without caching it", CacheWarning, stacklevel=3)
                return None
            raise CacheError(f"cannot write the reference cache entry {str(path)!r} "
                             f"({type(exc).__name__}: {exc})") from exc

    def provenance(self, key_fields: Mapping) -> dict | None:
        """The provenance record of the (verified) entry of ``key_fields``, or None."""
        if self.load(key_fields) is None:
            return None
        with open(self.path(key_fields), "rb") as fh, np.load(fh, allow_pickle=False) as data:
            return json.loads(str(data[_PROVENANCE][()]))

    def get_or_compute(self, key_fields: Mapping, compute: Callable[[], object], *,
                       expected: Mapping | None = None, info: Mapping | None = None) -> tuple[object, bool]:
        """The cached result of ``key_fields``, or ``compute()`` stored under it.

        Parameters
        ----------
        key_fields : mapping of str to JSON-able values
            Everything the result depends on (hash arrays with :func:`array_digest`,
            :func:`scene_digest` or :func:`gbuffer_digest` first). The versions are added.
        compute : callable
            Called with no argument on a miss; returns an :class:`~vobscure.Estimate` or a
            non-empty dict of numeric arrays.
        expected : mapping of str to tuple, optional
            Shapes that the named arrays of a cached entry must have (see :meth:`load`).
        info : mapping, optional
            Extra provenance stored with a new entry (not part of the key).

        Returns
        -------
        result : Estimate or dict of str to ndarray
            Bit for bit what ``compute`` returned, now or on the run that stored it.
        hit : bool
            True when it came from the cache.

        Raises
        ------
        CacheError
            When the folder cannot be written; raised before ``compute`` is called (with
            ``on_error="warn"``: one :class:`CacheWarning`, then computed and not stored).
        """
        if not callable(compute):
            raise ValueError(f"compute must be a callable with no arguments, got {type(compute).__name__}")
        canonical_json(key_fields)   # reject bad fields before any work
        canonical_json(info or {})
        if self.enabled:
            cached = self.load(key_fields, expected=expected)
            if cached is not None:
                return cached, True
            self._ensure_writable()
        t0 = time.perf_counter()
        result = compute()
        seconds = time.perf_counter() - t0
        _as_arrays(result)   # check the type even when nothing is stored
        if self.enabled:
            self.store(key_fields, result, compute_seconds=seconds, info=info)
        return result, False


# ----------------------------------------------------------------------------- helpers
def open_cache(cache) -> ReferenceCache:
    """The cache a job's ``cache`` argument names: True the default user folder, a path that
    folder, False or None no cache, a :class:`ReferenceCache` itself. A folder it opens warns
    and is used read only when it cannot be written (``on_error="warn"``): the job goes on."""
    if isinstance(cache, ReferenceCache):
        return cache
    if cache is True:
        return ReferenceCache(on_error="warn")
    if cache is False or cache is None:
        return ReferenceCache(enabled=False)
    return ReferenceCache(cache, on_error="warn")


def _as_cache(cache) -> ReferenceCache:
    if cache is None:
        return ReferenceCache(enabled=False)
    if not isinstance(cache, ReferenceCache):
        raise ValueError(f"cache must be a ReferenceCache or None, got {type(cache).__name__}")
    return cache


def _seed(seed) -> int:
    """A cached result must be reproducible: only an integer seed names one."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative int to cache a reference (a Generator or None "
                         f"gives numbers no key can name), got {seed!r}")
    return int(seed)


def _scene_info(scene) -> dict:
    """Provenance of the scene (not part of the key)."""
    name = getattr(scene, "name", None)
    return {"scene_name": None if name is None else str(name)}


def _keyword_defaults(fn) -> dict:
    """The keyword-only parameters of ``fn`` and their defaults (read from its signature)."""
    return {n: p.default for n, p in inspect.signature(fn).parameters.items() if p.kind is p.KEYWORD_ONLY}


# Read once from the functions themselves, so that a cached call and a direct one with the
# same arguments always compute the same thing.
_GROUND_TRUTH_DEFAULTS = _keyword_defaults(_groundtruth.ground_truth)
_SCREEN_REFERENCE_DEFAULTS = _keyword_defaults(_screenspace.vo_reference)


def _with_defaults(defaults: Mapping, params: Mapping, name: str, of: str) -> dict:
    """``params`` with ``defaults`` filled in; unknown names are an error."""
    unknown = sorted(set(params) - set(defaults))
    if unknown:
        raise TypeError(f"{name}() got unexpected keyword argument(s) {', '.join(unknown)}; it takes "
                        f"those of {of}: {', '.join(defaults)}")
    return {**defaults, **params}


def _cached_signature(fn, positional: list) -> inspect.Signature:
    """The signature of a cached wrapper: ``positional``, then ``cache``, then ``fn``'s keywords."""
    keywords = [p for p in inspect.signature(fn).parameters.values() if p.kind is p.KEYWORD_ONLY]
    cache = inspect.Parameter("cache", inspect.Parameter.KEYWORD_ONLY)
    return inspect.Signature([*positional, cache, *keywords], return_annotation="tuple[Estimate, bool]")


#: Parameters of :func:`vobscure.ground_truth` that enter the key, per quantity (besides the
#: radius, the groups and the seed); the others do not change its numbers for that quantity.
GROUND_TRUTH_KEY_PARAMS = {"ao": ("rays", "weighting"), "obscurance": ("rays", "weighting", "falloff"),
                           "volumetric": ("samples", "falloff", "normal_clamp", "votes", "thickness")}


def ground_truth_cached(scene, gbuffer, *, cache, **params) -> tuple[Estimate, bool]:
    """:func:`vobscure.ground_truth`, cached.

    Takes the arguments of :func:`vobscure.ground_truth`, with its defaults (read from its
    signature, so the two never disagree), plus ``cache``.

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts.
    gbuffer : GBuffer
    cache : ReferenceCache or None
        None computes without caching.
    **params
        The keyword arguments of :func:`vobscure.ground_truth` (``quantity``, ``radius``,
        ``rays``, ``samples``, ``falloff``, ``weighting``, ``normal_clamp``, ``seed``,
        ``votes``, ``groups``, ``allow_open``, ``threads``, ``progress``); ``seed`` must be
        an int. The key holds only the parameters that ``quantity`` uses
        (:data:`GROUND_TRUTH_KEY_PARAMS`: rays for ao and obscurance, samples, falloff,
        normal_clamp and votes for volumetric, ...) with the defaults filled in, so
        equivalent calls share an entry. ``allow_open``, ``threads`` and ``progress`` do not
        change the numbers and are not part of it.

    Returns
    -------
    estimate : Estimate
        (H, W) value and stderr, NaN on background.
    hit : bool
        True when it came from the cache.

    Raises
    ------
    TypeError
        For a keyword that :func:`vobscure.ground_truth` does not take.

    Notes
    -----
    The key holds :func:`scene_digest` of the scene, :func:`gbuffer_digest` (world) of the
    G-buffer's hits and its camera, the parameters, the seed and the versions.
    """
    from ..gbuffer import GBuffer
    from ..groundtruth import DEFAULT_FALLOFF, OBSCURANCE_FALLOFFS, QUANTITIES, VO_FALLOFFS

    cache = _as_cache(cache)
    scene = as_scene(scene)
    if not isinstance(gbuffer, GBuffer):
        raise ValueError(f"gbuffer must be a vobscure GBuffer (from render_gbuffer), got {type(gbuffer).__name__}")
    args = _with_defaults(_GROUND_TRUTH_DEFAULTS, params, "ground_truth_cached", "vobscure.ground_truth")
    quantity = check_choice(args["quantity"], "quantity", QUANTITIES)
    args["seed"] = seed = _seed(args["seed"])
    radius = args["radius"]
    if radius is not None:
        radius = check_positive(radius, "radius", allow_inf=(quantity == "ao"))
    elif quantity != "ao":
        raise ValueError(f"radius is required for quantity={quantity!r}")
    if args["falloff"] is None and quantity in DEFAULT_FALLOFF:
        args["falloff"] = DEFAULT_FALLOFF[quantity]
    key = {"radius": radius, "groups": check_int(args["groups"], "groups", minimum=2)}
    if quantity == "ao" and radius is not None and math.isinf(radius):
        key["radius"] = None   # the same computation as radius=None
    for name in GROUND_TRUTH_KEY_PARAMS[quantity]:
        value = args[name]
        if name in ("rays", "samples"):
            value = check_int(value, name, minimum=2)
        elif name == "votes":
            value = check_int(value, name)   # ground_truth checks that it is odd
        elif name == "normal_clamp":
            value = bool(value)
        elif name == "falloff" and not isinstance(value, str):
            raise ValueError("falloff must be the name of a falloff to cache a reference "
                             f"({', '.join(OBSCURANCE_FALLOFFS if quantity == 'obscurance' else VO_FALLOFFS)}), "
                             f"got {type(value).__name__}")
        key[name] = value
    fields = {"kind": "ground_truth", "quantity": quantity, "scene": scene_digest(scene),
              "gbuffer": gbuffer_digest(gbuffer, world=True), "camera": gbuffer.camera.to_dict(),
              "params": key, "seed": seed}

    def compute():
        return _groundtruth.ground_truth(scene, gbuffer, **args)

    return cache.get_or_compute(fields, compute, expected={"value": gbuffer.shape, "stderr": gbuffer.shape},
                                info=_scene_info(scene))


def screen_reference_cached(gbuffer, scene=None, *, cache, **params) -> tuple[Estimate, bool]:
    """:func:`vobscure.vo_reference` (the converged screen-space VO), cached.

    Takes the arguments of :func:`vobscure.vo_reference`, with its defaults (read from its
    signature), plus ``scene`` and ``cache``.

    Parameters
    ----------
    gbuffer : GBuffer
    scene : Scene, trimesh.Trimesh, str or os.PathLike, optional
        Recorded in the entry's provenance only: the G-buffer alone decides the numbers.
    cache : ReferenceCache or None
        None computes without caching.
    **params
        The keyword arguments of :func:`vobscure.vo_reference` (``radius``, ``samples``,
        ``normal_clamp``, ``thickness``, ``falloff``, ``seed``, ``fetch``, ``offscreen``,
        ``groups``, ``progress``); ``seed`` must be an int and ``samples`` a count (a
        SamplePattern has no key). All but ``progress`` enter the key, with the defaults
        filled in.

    Returns
    -------
    estimate : Estimate
        (H, W) value and stderr, NaN on background.
    hit : bool
        True when it came from the cache.

    Raises
    ------
    TypeError
        For a keyword that :func:`vobscure.vo_reference` does not take.

    Notes
    -----
    The key holds :func:`gbuffer_digest` of the G-buffer's depth and normal images (in
    their dtype), its camera, the parameters, the seed and the versions.
    """
    from ..gbuffer import GBuffer

    cache = _as_cache(cache)
    if not isinstance(gbuffer, GBuffer):
        raise ValueError(f"gbuffer must be a vobscure GBuffer (from render_gbuffer), got {type(gbuffer).__name__}")
    args = _with_defaults(_SCREEN_REFERENCE_DEFAULTS, params, "screen_reference_cached", "vobscure.vo_reference")
    if args["radius"] is inspect.Parameter.empty:
        raise TypeError("screen_reference_cached() missing the keyword argument 'radius'")
    args["seed"] = seed = _seed(args["seed"])
    args["radius"] = check_positive(args["radius"], "radius")
    args["samples"] = check_int(args["samples"], "samples", minimum=2)
    args["groups"] = check_int(args["groups"], "groups", minimum=2)
    if args["thickness"] is not None:
        args["thickness"] = check_positive(args["thickness"], "thickness")
    args["normal_clamp"] = bool(args["normal_clamp"])
    key = {name: (value if value is None or isinstance(value, (bool, int, float)) else str(value))
           for name, value in args.items() if name not in ("seed", "progress")}
    fields = {"kind": "screen_reference", "quantity": "screen",
              "gbuffer": gbuffer_digest(gbuffer), "camera": gbuffer.camera.to_dict(),
              "params": key, "seed": seed}

    def compute():
        return _screenspace.vo_reference(gbuffer, **args)

    info = None if scene is None else _scene_info(as_scene(scene))
    return cache.get_or_compute(fields, compute, expected={"value": gbuffer.shape, "stderr": gbuffer.shape},
                                info=info)


ground_truth_cached.__signature__ = _cached_signature(
    _groundtruth.ground_truth, [inspect.Parameter(n, inspect.Parameter.POSITIONAL_OR_KEYWORD) for n in ("scene", "gbuffer")])
screen_reference_cached.__signature__ = _cached_signature(
    _screenspace.vo_reference, [inspect.Parameter("gbuffer", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                   inspect.Parameter("scene", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None)])
