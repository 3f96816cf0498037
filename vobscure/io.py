"""G-buffers from files, and visibility images to files.

A renderer (Blender, a game engine, a capture device) writes its depth and normals to files;
:func:`read_gbuffer` reads them and hands the arrays to :meth:`GBuffer.from_arrays
<vobscure.gbuffer.GBuffer.from_arrays>`, which converts the renderer's conventions (depth
kind, normal space and encoding, axis convention, background value) to the library's
(``docs/conventions.md``). :func:`write_image` writes an estimator's visibility.

Formats, chosen by the file's suffix:

- **OpenEXR** (``.exr``, through the ``OpenEXR`` 3.x bindings): single- or multi-part,
  single- or multi-layer. Channels are found by name, with defaults for the names Blender
  writes (:data:`DEPTH_CHANNELS`, :data:`NORMAL_CHANNELS`): its multilayer render result
  (``ViewLayer.Depth.Z``, ``ViewLayer.Normal.X/Y/Z``), the compositor's File Output node in
  multilayer (``Depth.V``, ``Normal.X/Y/Z``) and single-layer files (depth as ``R = G = B``
  plus ``A``; normals as ``X, Y, Z`` plus ``A``: one file each). A part's channels are also
  reachable as ``"<part name>.<channel>"``.
- **NumPy** ``.npy`` (one array: a depth (H, W), or normals (H, W, 3) as the normal file) and
  ``.npz`` (arrays ``depth`` and ``normal``), always loaded with ``allow_pickle=False``.
- **PFM** (``.pfm``): ``Pf`` (one channel, depth) or ``PF`` (three channels, normals), the
  byte order given by the sign of the scale (negative: little endian), rows stored bottom
  to top.
- **PNG** (``.png``, through Pillow): 16-bit (or 8-bit) integer depth times ``depth_scale``
  (0 is no data: background); an RGB normal map is read as values in [0, 1]
  (``normal_encoding="unit"``), at 8 bits per channel (Pillow reads a 16-bit colour PNG at 8).

No reader executes anything from a file: no pickles, no ``eval``.

Every writer is atomic (:func:`vobscure._io.atomic_write`): a failed write leaves the old
file in place.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
import tempfile
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ._io import atomic_write

__all__ = ["DEPTH_CHANNELS", "NORMAL_CHANNELS", "SUFFIXES", "read_buffers", "read_gbuffer", "write_image",
           "write_gbuffer", "read_pfm", "write_pfm", "exr_channels", "EXR_MAX_PIXELS"]

#: Depth channel names tried in order when ``depth_channel`` is not given: what Blender's
#: compositor File Output node writes to a multilayer file for a float input named Depth
#: (``Depth.V``), its multilayer render output (``ViewLayer.Depth.Z``; ``View Layer`` in
#: files of older versions), a plain single-layer Z, and the usual variants. A bare ``Z`` is
#: not taken from a file that also has ``X`` and ``Y`` (a vector: normals). Failing these: a
#: single channel whose name ends in ``.Depth.Z`` or ``.Depth.V`` (a renamed view layer), a
#: bare ``V``, and the grey ``R`` of an ``R, G, B`` file whose three channels are equal
#: everywhere (the single-layer File Output node writes a float input as ``R = G = B``, plus
#: ``A``). Several candidates of one kind (two view layers) are an error that lists them.
DEPTH_CHANNELS = ("Depth.V", "View Layer.Depth.Z", "ViewLayer.Depth.Z", "Z", "depth.Z", "Depth.Z",
                  "depth.V", "depth", "Depth")

#: Normal channel triples tried in order when ``normal_channels`` is not given (Blender's
#: multilayer pass, the File Output node's vector and colour inputs, a bare ``N`` layer, and
#: the bare ``X, Y, Z`` of the single-layer File Output node's vector input).
#: Failing these, a single layer whose name ends in ``.Normal`` with X, Y, Z channels is taken.
NORMAL_CHANNELS = tuple(
    tuple(f"{layer}.{axis}" for axis in axes)
    for layer in ("Normal", "View Layer.Normal", "ViewLayer.Normal", "N", "normal", "normals")
    for axes in (("X", "Y", "Z"), ("R", "G", "B"))
) + (("X", "Y", "Z"),)

#: The file suffixes :func:`read_gbuffer` reads.
SUFFIXES = (".exr", ".npy", ".npz", ".pfm", ".png")


# --------------------------------------------------------------------------- reading
def read_gbuffer(path_or_paths, *, camera, normal_path=None, depth_channel=None, normal_channels=None,
                 depth_kind="linear", depth_scale=None, **from_arrays_kwargs):
    """A :class:`~vobscure.gbuffer.GBuffer` from a renderer's depth (and normal) files.

    Reads the arrays with :func:`read_buffers` and returns ``GBuffer.from_arrays(depth,
    normal, camera=camera, depth_kind=depth_kind, **from_arrays_kwargs)``, which converts the
    renderer's conventions to the library's.

    Parameters
    ----------
    path_or_paths : str or Path, or (depth_path, normal_path)
        One file holding the depth (and possibly the normals), or a pair of files.
        Formats by suffix: ``.exr``, ``.npy``, ``.npz``, ``.pfm``, ``.png`` (module docstring).
    camera : Camera
        The camera the frame was rendered with (its size must be the image's (W, H)).
    normal_path : str or Path, optional
        The file of the normals, when they are not in the depth file (same as a pair).
    depth_channel : str, optional
        EXR channel (or NPZ array) of the depth; default: the first of
        :data:`DEPTH_CHANNELS` present, then its fallbacks (a single ``*.Depth.Z`` layer, a
        bare ``V``, the grey ``R`` of ``R = G = B``); NPZ: ``depth``.
    normal_channels : str or (str, str, str), optional
        EXR channels of the normals: three names (a tuple, or one string ``"X,Y,Z"`` as on
        the command line), or a layer name such as ``"View Layer.Normal"`` (its ``.X .Y .Z``
        or ``.R .G .B``); NPZ: the array name.
        Default: the first of :data:`NORMAL_CHANNELS` present, and no normals (None is passed
        on) when the file has none.
    depth_kind : str, optional
        What the depth values are (default ``"linear"``, view-space z); passed on to
        ``from_arrays``.
    depth_scale : float, optional
        Factor from stored depth values to scene units; required for PNG (integer) depth,
        optional (default 1) for the float formats.
    **from_arrays_kwargs
        ``near``, ``far``, ``normal_space``, ``view``, ``normal_encoding``, ``convention``,
        ``background``, ... passed on to ``GBuffer.from_arrays``.

    Returns
    -------
    GBuffer
        Its ``conversion`` dict also holds ``source``: the ``found`` record of
        :func:`read_buffers` (which file and channels the depth and normals came from).

    Raises
    ------
    FileNotFoundError
        A file does not exist.
    ValueError
        An unknown suffix, an unreadable (truncated) file, a missing channel or a choice the
        defaults cannot make (two view layers, ``R, G, B`` that differ; the message lists the
        file's channels and the argument that picks them), an array of the wrong shape, a
        pickled object in an ``.npz``, a PNG without ``depth_scale``.
    """
    from .gbuffer import GBuffer

    depth, normal, found = read_buffers(path_or_paths, normal_path=normal_path, depth_channel=depth_channel,
                                        normal_channels=normal_channels, depth_scale=depth_scale)
    _check_camera(camera, depth.shape, path_or_paths)
    if found.get("normal_encoding") and "normal_encoding" not in from_arrays_kwargs:
        from_arrays_kwargs["normal_encoding"] = found["normal_encoding"]
    gb = GBuffer.from_arrays(depth, normal, camera=camera, depth_kind=depth_kind, **from_arrays_kwargs)
    gb.conversion["source"] = dict(found)
    return gb


def read_buffers(path_or_paths, *, normal_path=None, depth_channel=None, normal_channels=None,
                 depth_scale=None):
    """The raw depth and normal arrays of a frame, as stored (no convention converted).

    The reading half of :func:`read_gbuffer` (same parameters).

    Returns
    -------
    depth : (H, W) ndarray of float32 or float64
        The stored depth values times ``depth_scale`` (PNG: 0 -> +inf).
    normal : (H, W, 3) ndarray of float or None
        The stored normals, or None when the files hold none (and none were asked for).
    found : dict
        Where they came from: ``depth`` and ``normal`` (``"path:channel"``, for display),
        ``depth_channel`` and ``normal_channels`` (the EXR channel name and the three names
        used, for an EXR), and ``normal_encoding`` ``"unit"`` for a PNG normal map.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "frame.npz")
    >>> np.savez(path, depth=np.full((2, 3), 4.0), normal=np.tile([0.0, 0.0, -1.0], (2, 3, 1)))
    >>> depth, normal, found = read_buffers(path)
    >>> depth.shape, normal.shape, found["depth"].endswith("frame.npz:depth")
    ((2, 3), (2, 3, 3), True)
    """
    depth_path, normal_path = _paths(path_or_paths, normal_path)
    normal_channels = _check_normal_channels(normal_channels)
    if depth_channel is not None and not (isinstance(depth_channel, str) and depth_channel):
        raise ValueError(f"depth_channel must be a channel name (a non-empty string) or None, got {depth_channel!r}")
    depth_scale = _check_depth_scale(depth_scale)
    found: dict = {}
    cache: dict = {}   # each file is opened once; .npz archives are closed below
    try:
        depth = _read_depth(depth_path, depth_channel, depth_scale, found, cache)
        if normal_path is None:
            normal = _read_normal(depth_path, normal_channels, found, cache, required=normal_channels is not None,
                                  same_file=True)
        else:
            normal = _read_normal(normal_path, normal_channels, found, cache, required=True, same_file=False)
    finally:
        for value in cache.values():
            if hasattr(value, "close"):
                value.close()
    if normal is not None and normal.shape[:2] != depth.shape:
        raise ValueError(f"the normals {found['normal']} are {normal.shape[1]}x{normal.shape[0]} pixels but "
                         f"the depth {found['depth']} is {depth.shape[1]}x{depth.shape[0]}; they must match")
    return depth, normal, found


def _check_normal_channels(spec):
    """None, a layer name (or "X,Y,Z"), or three channel names; anything else is an error."""
    if spec is None or (isinstance(spec, str) and spec.strip()):
        return spec
    if not isinstance(spec, str):
        try:
            names = tuple(spec)
        except TypeError:
            names = None
        if names is not None and len(names) == 3 and all(isinstance(n, str) and n for n in names):
            return names
    raise ValueError(f"normal_channels must be None (found automatically), a layer name such as 'Normal' or "
                     f"'View Layer.Normal', or three channel names such as ('N.X', 'N.Y', 'N.Z') or "
                     f"'N.X,N.Y,N.Z'; got {spec!r}")


def _check_depth_scale(depth_scale):
    """None or a finite number > 0 (a numeric string as on the command line is accepted)."""
    if depth_scale is None:
        return None
    try:
        value = float(depth_scale)
    except (TypeError, ValueError):
        value = None
    if isinstance(depth_scale, bool) or value is None or not (np.isfinite(value) and value > 0):
        raise ValueError(f"depth_scale must be a finite number > 0 (scene units per stored depth unit), "
                         f"got {depth_scale!r}")
    return value


def _paths(path_or_paths, normal_path):
    if isinstance(path_or_paths, (str, os.PathLike)):
        depth_path = Path(path_or_paths)
    else:
        try:
            items = list(path_or_paths)
        except TypeError:
            raise ValueError(f"path_or_paths must be a path or a (depth, normal) pair of paths, "
                             f"got {path_or_paths!r}") from None
        if len(items) != 2:
            raise ValueError(f"path_or_paths must be a path or a (depth, normal) pair of paths, got "
                             f"{len(items)} items")
        if normal_path is not None:
            raise ValueError("give the normal file either in the pair or as normal_path, not both")
        depth_path, normal_path = (Path(p) for p in items)
    normal_path = None if normal_path is None else Path(normal_path)
    for p in (depth_path, normal_path):
        if p is None:
            continue
        if not p.is_file():
            raise FileNotFoundError(f"no such file: {p}" if not p.exists() else f"not a file: {p}")
        if p.suffix.lower() not in SUFFIXES:
            raise ValueError(f"{p}: unknown format {p.suffix!r}; expected one of {', '.join(SUFFIXES)}")
    return depth_path, normal_path


def _check_camera(camera, shape, source) -> None:
    size = getattr(camera, "size", None)
    if size is None:
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    H, W = shape
    if tuple(size) != (W, H):
        raise ValueError(f"the frame {source} is {W}x{H} pixels but the camera's size is "
                         f"{size[0]}x{size[1]}; they must match")


def _read_depth(path, channel, depth_scale, found, cache) -> np.ndarray:
    suffix = path.suffix.lower()
    depth_scale = _check_depth_scale(depth_scale)
    if suffix == ".exr":
        channels = _exr_cached(path, cache)
        name = channel if channel is not None else _default_depth(channels, path)
        if name is None or name not in channels:
            what = (f"no depth channel {channel!r}" if channel is not None else
                    f"no depth channel (tried {', '.join(DEPTH_CHANNELS)}, a *.Depth.Z layer, V, and R of "
                    f"R = G = B)")
            if channel is None and all(c in channels for c in "XYZ"):
                what += " (X, Y, Z is a vector: a normal file?)"
            raise ValueError(f"{path}: {what}; the file has the channels {_listing(channels)}; "
                             f"name one with depth_channel= (--depth-channel)")
        depth, where = channels[name], f"{path}:{name}"
        found["depth_channel"] = name
    elif suffix == ".npz":
        depth, where = _npz_array(path, channel or "depth", cache), f"{path}:{channel or 'depth'}"
    elif suffix == ".npy":
        depth, where = _npy(path), str(path)
    elif suffix == ".pfm":
        depth, where = read_pfm(path), str(path)
    else:  # .png
        if depth_scale is None:
            raise ValueError(f"{path}: a PNG stores integer depth; give depth_scale (--depth-scale), the "
                             f"scene units per stored unit (e.g. 0.001 for millimetres)")
        raw = _read_png(path)
        if raw.ndim == 3:
            raise ValueError(f"{path}: a PNG depth must be one channel (grey), got {raw.shape[2]} channels")
        depth = np.where(raw == 0, np.inf, raw.astype(np.float64) * depth_scale)
        found["depth"] = str(path)
        return _check_depth(depth, str(path))
    if depth.ndim == 3 and depth.shape[2] == 1:
        depth = depth[:, :, 0]
    depth = _check_depth(depth, where)
    if depth_scale is not None and depth_scale != 1.0:
        depth = depth * depth.dtype.type(depth_scale)
    found["depth"] = where
    return depth


def _check_depth(depth, where) -> np.ndarray:
    depth = np.asarray(depth)
    if depth.ndim != 2:
        raise ValueError(f"the depth {where} must be an (H, W) image, got an array of shape {depth.shape}")
    if depth.dtype.kind not in "fiu":
        raise ValueError(f"the depth {where} must be numbers, got dtype {depth.dtype}")
    if depth.dtype.kind != "f" or depth.dtype.itemsize < 4:
        depth = depth.astype(np.float32 if depth.dtype.itemsize <= 2 else np.float64)
    return depth


def _read_normal(path, channels_arg, found, cache, *, required, same_file):
    suffix = path.suffix.lower()
    if suffix == ".exr":
        channels = _exr_cached(path, cache)
        try:
            names = _normal_names(channels, channels_arg)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
        if names is None:
            if not required:
                return None
            what = (f"no normal channels {channels_arg!r}" if channels_arg is not None else
                    "no normal channels (tried Normal.X/Y/Z, View Layer.Normal.X/Y/Z, N.X/Y/Z, ... and "
                    "*.Normal.X/Y/Z)")
            raise ValueError(f"{path}: {what}; the file has the channels {_listing(channels)}; name them "
                             f"with normal_channels= (--normal-channels)")
        normal, where = np.stack([channels[n] for n in names], axis=-1), f"{path}:{'/'.join(names)}"
        found["normal_channels"] = names
    elif suffix == ".npz":
        key = channels_arg if isinstance(channels_arg, str) else "normal"
        if not required and key not in _npz_cached(path, cache).files:
            return None
        normal, where = _npz_array(path, key, cache), f"{path}:{key}"
    elif same_file:
        # .npy, .pfm and .png depth files hold only the depth
        if required:
            raise ValueError(f"{path} holds only a depth; give the normals in a second file (normal_path=, "
                             f"--normal)")
        return None
    elif suffix == ".npy":
        normal, where = _npy(path), str(path)
    elif suffix == ".pfm":
        normal, where = read_pfm(path), str(path)
    else:  # .png normal map: integer RGB in [0, 1]
        raw = _read_png(path)
        if raw.ndim != 3 or raw.shape[2] not in (3, 4):
            raise ValueError(f"{path}: a PNG normal map must be RGB, got shape {raw.shape}")
        top = 65535.0 if raw.dtype == np.uint16 else 255.0
        normal, where = raw[:, :, :3].astype(np.float32) / np.float32(top), str(path)
        found["normal_encoding"] = "unit"
    normal = np.asarray(normal)
    if normal.ndim != 3 or normal.shape[2] != 3:
        raise ValueError(f"the normals {where} must be an (H, W, 3) image, got an array of shape {normal.shape}")
    if normal.dtype.kind != "f":
        raise ValueError(f"the normals {where} must be floats, got dtype {normal.dtype}")
    found["normal"] = where
    return normal


def _default_depth(channels, path) -> str | None:
    """The depth channel of an EXR when none is named (:data:`DEPTH_CHANNELS`), or None;
    a ValueError when the file offers several and no rule picks one."""
    vector = "X" in channels and "Y" in channels      # bare X, Y, Z: a vector, not a depth
    for name in DEPTH_CHANNELS:
        if name in channels and not (name == "Z" and vector):
            return name
    tails = sorted(n for n in channels if n.endswith((".Depth.Z", ".Depth.V")))
    if len(tails) > 1:
        raise ValueError(f"{path}: several depth channels ({', '.join(tails)}: one per view layer?); the file "
                         f"has the channels {_listing(channels)}; pick one with depth_channel= (--depth-channel)")
    if tails:
        return tails[0]
    if "V" in channels:
        return "V"
    if all(c in channels for c in "RGB"):
        r, g, b = (channels[c] for c in "RGB")
        # the single-layer File Output node writes a float input (Depth) as R = G = B
        if r.shape == g.shape == b.shape and _same(r, g) and _same(r, b):
            return "R"
        raise ValueError(f"{path}: no depth channel, and R, G, B differ (a colour image, not a depth written as "
                         f"grey); the file has the channels {_listing(channels)}; name the depth with "
                         f"depth_channel= (--depth-channel)")
    return None


def _same(a, b) -> bool:
    """Bitwise-equal images (NaN equal to NaN)."""
    return bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))


def _normal_names(channels, spec):
    if spec is None:
        for names in NORMAL_CHANNELS:
            if all(n in channels for n in names):
                return names
        layers = {n[: -len(".X")] for n in channels if n.endswith(".Normal.X")}
        layers = sorted(lay for lay in layers if all(f"{lay}.{a}" in channels for a in "YZ"))
        if len(layers) > 1:
            raise ValueError(f"several normal layers ({', '.join(layers)}: one per view layer?); the file has the "
                             f"channels {_listing(channels)}; pick one with normal_channels= (--normal-channels)")
        return tuple(f"{layers[0]}.{a}" for a in "XYZ") if layers else None
    if isinstance(spec, str) and "," in spec:
        spec = tuple(c.strip() for c in spec.split(","))          # "X,Y,Z", as on the command line
    if isinstance(spec, str):
        for axes in ("XYZ", "RGB", "xyz", "rgb"):
            names = tuple(f"{spec}.{a}" for a in axes)
            if all(n in channels for n in names):
                return names
        return None
    names = tuple(spec)
    if len(names) != 3 or not all(isinstance(n, str) for n in names):
        raise ValueError(f"normal_channels must be a layer name or three channel names, got {spec!r}")
    return names if all(n in channels for n in names) else None


def _listing(names) -> str:
    names = sorted(names)
    return ", ".join(names) if names else "(none)"


# --------------------------------------------------------------------------- EXR
def _openexr():
    try:
        import OpenEXR
    except ImportError as exc:  # pragma: no cover - a core dependency
        raise ImportError("reading and writing EXR needs the OpenEXR bindings: python -m pip install "
                          "'openexr>=3.2'") from exc
    return OpenEXR


#: The most pixels an EXR's data windows may hold together (the parts' width x height summed):
#: 2^28, a 16384 x 16384 frame, 1 GiB per float32 channel. A header claiming more is refused
#: before any pixel is read (a damaged one can claim 10^10, and the reader would allocate it).
EXR_MAX_PIXELS = 1 << 28


def exr_channels(path) -> dict[str, np.ndarray]:
    """Every channel of an OpenEXR file, by name, as (H, W) arrays (float16/float32/uint32).

    The channels of every part are listed under their own names (the first part's win a
    clash) and also as ``"<part name>.<name>"`` for a named part, unless the name already
    starts with the part's name (Blender's multilayer files: part ``ViewLayer.Depth`` holds
    ``ViewLayer.Depth.Z``).

    The header is read first: data windows of more than :data:`EXR_MAX_PIXELS` pixels, or
    whose channels would not fit in the memory available, are refused before any pixel is read.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        ``not a readable EXR file: PATH (reason)``: a truncated or damaged file, another
        format, pixel data that cannot be decoded, or a data window too large.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such file: {path}")
    OpenEXR = _openexr()
    with _exr_messages() as said:
        try:
            head = OpenEXR.File(str(path), header_only=True)
        except Exception as exc:  # the bindings raise RuntimeError (and print the detail to stderr)
            error = exc
        else:
            error = None
    if error is not None:
        raise ValueError(f"not a readable EXR file: {path} ({_exr_reason(said, error)})") from None
    declared = [[c.name for c in part.header.get("channels", [])] for part in head.parts]
    _check_exr_size(path, head)
    with _exr_messages() as said:
        try:
            f = OpenEXR.File(str(path), separate_channels=True)
        except Exception as exc:
            error = exc
    if error is not None:
        raise ValueError(f"not a readable EXR file: {path} ({_exr_reason(said, error)})") from None
    if len(f.parts) != len(declared) or any(names and not part.channels for names, part in zip(declared, f.parts)):
        # the bindings print a failed pixel read and return the part without channels
        raise ValueError(f"not a readable EXR file: {path} (the pixel data cannot be read: "
                         f"{_exr_reason(said, None)})")
    out: dict[str, np.ndarray] = {}
    for part in f.parts:
        pname = part.name() if callable(getattr(part, "name", None)) else ""
        for name, channel in part.channels.items():
            pixels = np.asarray(channel.pixels)
            out.setdefault(name, pixels)
            if pname and not name.startswith(f"{pname}."):   # Blender names its parts after the layer
                out.setdefault(f"{pname}.{name}", pixels)
    return out


@contextlib.contextmanager
def _exr_messages():
    """Collect what the OpenEXR bindings print while reading: their warnings go to Python's
    stdout, the library's error detail to the process's stderr (file descriptor 2). Yields a
    list that holds the lines once the block is left."""
    said: list[str] = []
    sys.stderr.flush()
    with tempfile.TemporaryFile() as tmp, contextlib.redirect_stdout(io.StringIO()) as printed:
        saved = os.dup(2)
        os.dup2(tmp.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            said.extend(tmp.read().decode("utf-8", "replace").splitlines())
            said.extend(printed.getvalue().splitlines())


def _exr_reason(said, error) -> str:
    """The library's own detail (its first line, the file's path dropped) else the exception's."""
    for line in said:
        line = " ".join(line.split())
        if line:
            head, sep, tail = line.partition(": ")
            return tail if sep and head.endswith(".exr") else line
    return " ".join(str(error).split()) if error is not None else "no detail given"


def _check_exr_size(path, head) -> None:
    """Refuse data windows above :data:`EXR_MAX_PIXELS` pixels or above the memory available."""
    pixels, values, sizes = 0, 0, []
    for part in head.parts:
        lo, hi = (np.asarray(v, dtype=np.int64) for v in part.header["dataWindow"])
        W, H = (int(n) for n in hi - lo + 1)
        if W <= 0 or H <= 0:
            raise ValueError(f"not a readable EXR file: {path} (its data window is {W} x {H} pixels)")
        sizes.append(f"{W} x {H}")
        pixels += W * H
        values += W * H * max(len(part.header.get("channels", [])), 1)
    if pixels > EXR_MAX_PIXELS:
        raise ValueError(f"not a readable EXR file: {path} (its header claims a data window of {', '.join(sizes)} "
                         f"= {pixels} pixels, more than the {EXR_MAX_PIXELS} this reader accepts; a damaged header?)")
    available = _available_memory()
    if available is not None and 4 * values > available:
        raise ValueError(f"not a readable EXR file: {path} (its {', '.join(sizes)} pixels need up to "
                         f"{_bytes(4 * values)}, and {_bytes(available)} of memory is available)")


def _bytes(n: int) -> str:
    """A byte count for people: ``16 KiB``, ``37.3 GiB``."""
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{n} B"
        n /= 1024


def _available_memory() -> int | None:
    """Bytes of physical memory available now (None where the system does not say)."""
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _exr_cached(path, cache) -> dict:
    key = ("exr", Path(path).resolve())
    if key not in cache:
        cache[key] = exr_channels(path)
    return cache[key]


def _exr_bytes(channels: dict, *, compression="zip"):
    """A writer of an EXR with ``channels`` (name -> (H, W) float32/float16/uint32 array)."""
    OpenEXR = _openexr()
    comp = {"zip": OpenEXR.ZIP_COMPRESSION, "none": OpenEXR.NO_COMPRESSION, "piz": OpenEXR.PIZ_COMPRESSION}
    header = {"compression": comp[compression], "type": OpenEXR.scanlineimage}
    exr = OpenEXR.File(header, {k: np.ascontiguousarray(v) for k, v in channels.items()})

    def write(fh):
        exr.write(fh)

    return write


# --------------------------------------------------------------------------- NumPy
#: What NumPy raises for a damaged ``.npy`` or ``.npz`` file: a truncated or empty file, a bad
#: zip directory or member, a broken compressed stream.
_NUMPY_FILE_ERRORS = (ValueError, OSError, EOFError, zlib.error, zipfile.BadZipFile)


def _reason(exc: BaseException) -> str:
    """A damaged file's error as one line, its type named."""
    text = " ".join(str(exc).split())
    if isinstance(exc, EOFError):
        text = "the file is empty or ends early"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _npy(path) -> np.ndarray:
    # our own handle, closed on every path: np.load(path) leaks it when the file is damaged
    with open(path, "rb") as fh:
        try:
            array = np.load(fh, allow_pickle=False)
            if not isinstance(array, np.ndarray):
                array.close()
                raise ValueError("a zip archive of named arrays (.npz content), not one array")
            return array
        except _NUMPY_FILE_ERRORS as exc:
            if "allow_pickle" in str(exc):
                raise ValueError(f"not a readable NPY file: {path} (it holds pickled Python objects; pickled "
                                 f"objects are refused: a pickle can run code when loaded)") from None
            raise ValueError(f"not a readable NPY file: {path} ({_reason(exc)})") from None


def _npz_cached(path, cache):
    key = ("npz", Path(path).resolve())
    if key not in cache:
        fh = open(path, "rb")   # closed by read_buffers with the archive: np.load(path) leaks on a damaged file
        try:
            archive = np.load(fh, allow_pickle=False)
            if not hasattr(archive, "files"):
                raise ValueError("a single array (.npy content), not a zip archive of named arrays")
        except _NUMPY_FILE_ERRORS as exc:
            fh.close()
            raise ValueError(f"not a readable NPZ file: {path} ({_reason(exc)})") from None
        cache[key], cache[key + ("handle",)] = archive, fh
    return cache[key]


def _npz_array(path, key, cache) -> np.ndarray:
    archive = _npz_cached(path, cache)
    if key not in archive.files:
        raise ValueError(f"{path}: no array {key!r}; the archive has the arrays {_listing(archive.files)}")
    try:
        return archive[key]
    except ValueError as exc:
        if "allow_pickle" not in str(exc):
            raise ValueError(f"not a readable NPZ file: {path} (array {key!r}: {_reason(exc)})") from None
        raise ValueError(f"{path}: the array {key!r} holds Python objects, which are refused (a pickle can run "
                         f"code when loaded); save plain numeric arrays ({exc})") from None
    except _NUMPY_FILE_ERRORS as exc:
        raise ValueError(f"not a readable NPZ file: {path} (array {key!r}: {_reason(exc)})") from None


# --------------------------------------------------------------------------- PFM
_PFM_HEADER = re.compile(rb"\A(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s")


def read_pfm(path) -> np.ndarray:
    """A Portable Float Map: (H, W) for ``Pf``, (H, W, 3) for ``PF``, float32, row 0 the top.

    The header is ``Pf`` or ``PF``, the width and height, and a scale whose sign gives the
    byte order (negative: little endian); rows are stored bottom to top.
    """
    path = Path(path)
    data = path.read_bytes()
    m = _PFM_HEADER.match(data[:256])
    if m is None:
        raise ValueError(f"{path}: not a PFM file (expected a 'Pf' or 'PF' header, width, height and scale)")
    magic, W, H = m.group(1), int(m.group(2)), int(m.group(3))
    try:
        scale = float(m.group(4))
    except ValueError:
        raise ValueError(f"{path}: the PFM scale line must be a number (its sign gives the byte order), "
                         f"got {m.group(4).decode('ascii', 'replace')!r}") from None
    if scale == 0 or not np.isfinite(scale):
        raise ValueError(f"{path}: the PFM scale must be a non-zero number, got {scale}")
    C = 3 if magic == b"PF" else 1
    count = W * H * C
    body = data[m.end():]
    if len(body) != 4 * count:
        raise ValueError(f"{path}: a {W}x{H} PFM with {C} channel(s) holds {4 * count} bytes of pixels, "
                         f"found {len(body)}")
    dtype = np.dtype("<f4" if scale < 0 else ">f4")
    image = np.frombuffer(body, dtype=dtype, count=count).reshape(H, W, C)[::-1]
    image = image.astype(np.float32)
    return image[:, :, 0] if C == 1 else image


def write_pfm(path, image) -> Path:
    """Write an (H, W) or (H, W, 3) float image as a little-endian PFM, atomically."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 3)):
        raise ValueError(f"a PFM image must be (H, W) or (H, W, 3), got shape {a.shape}")
    magic = b"Pf" if a.ndim == 2 else b"PF"
    H, W = a.shape[:2]
    body = np.ascontiguousarray(a[::-1]).astype("<f4").tobytes()
    return atomic_write(path, lambda fh: fh.write(magic + f"\n{W} {H}\n-1.0\n".encode() + body))


# --------------------------------------------------------------------------- PNG
# Pillow reads and writes the PNGs; it is imported on first use, so that `import vobscure` stays light.
def _read_png(path) -> np.ndarray:
    """The pixels of a PNG: (H, W) grey or (H, W, C) colour, uint8 or uint16 (16-bit grey).

    Pillow reads a 16-bit colour PNG at 8 bits (the high byte of each sample), and a palette
    image as the colours of its palette.
    """
    from PIL import Image

    try:
        with Image.open(path) as image:
            if image.mode == "P":
                image = image.convert(image.palette.mode)
            raw = np.asarray(image)
    except (OSError, ValueError, SyntaxError) as exc:  # Pillow's errors for a file it cannot decode
        raise ValueError(f"{path}: not a readable PNG ({exc})") from None
    if raw.dtype.kind in "iu" and raw.dtype.itemsize > 2:
        # a 16-bit grey PNG opened as 32-bit integers: a PNG sample has at most 16 bits
        raw = raw.astype(np.uint16)
    return raw


def _write_png(path, image: np.ndarray) -> Path:
    """Write an (H, W) uint8 / uint16 or (H, W, 3) uint8 image as a grey or RGB PNG, atomically."""
    from PIL import Image

    picture = Image.fromarray(np.ascontiguousarray(image))
    return atomic_write(path, lambda fh: picture.save(fh, format="PNG"))


# --------------------------------------------------------------------------- writing
def write_image(path, visibility, *, background=None, bits=8, channel="Y") -> Path:
    """Write a visibility image, atomically; the format follows the suffix.

    Parameters
    ----------
    path : str or Path
        ``.exr`` (one float32 channel, NaN kept on background), ``.png`` (8 or 16 bit,
        visibility 0 black, 1 white, clipped to [0, 1]; background in the ``background``
        colour), ``.npy`` (the array as float32, NaN kept) or ``.pfm`` (float32, NaN kept).
    visibility : (H, W) array_like of float
        Visibility in [0, 1], NaN on background (what every estimator returns).
    background : float or (r, g, b), optional
        PNG only: the colour of NaN pixels, in [0, 1]; a grey level or an RGB triple (an
        8-bit RGB PNG). Default 0 (black).
    bits : {8, 16}, optional
        PNG bit depth (default 8); 16 bits are for grey PNGs only.
    channel : str, optional
        EXR channel name (default ``"Y"``, what viewers show as luminance; ``"V"`` also usual).

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> out = os.path.join(tempfile.mkdtemp(), "vo.exr")
    >>> _ = write_image(out, np.array([[0.5, np.nan]]))
    >>> exr_channels(out)["Y"].tolist()
    [[0.5, nan]]
    """
    path = Path(path)
    v = np.asarray(visibility)
    if v.ndim != 2:
        raise ValueError(f"visibility must be an (H, W) image, got shape {v.shape}")
    if v.dtype.kind not in "fiu":
        raise ValueError(f"visibility must be numbers, got dtype {v.dtype}")
    if v.size == 0:
        raise ValueError(f"visibility is an empty {v.shape[0]} x {v.shape[1]} image; an image file needs at "
                         f"least one pixel")
    suffix = path.suffix.lower()
    if suffix != ".png" and background is not None:
        raise ValueError(f"background is a PNG colour; {suffix} files keep NaN on background")
    if suffix == ".exr":
        if not isinstance(channel, str) or not channel:
            raise ValueError(f"channel must be a non-empty string, got {channel!r}")
        return atomic_write(path, _exr_bytes({channel: v.astype(np.float32)}))
    if suffix == ".npy":
        return atomic_write(path, lambda fh: np.save(fh, v.astype(np.float32), allow_pickle=False))
    if suffix == ".pfm":
        return write_pfm(path, v)
    if suffix == ".png":
        if bits not in (8, 16):
            raise ValueError(f"bits must be 8 or 16, got {bits!r}")
        top = (1 << bits) - 1
        bg = np.atleast_1d(np.asarray(0.0 if background is None else background, dtype=np.float64))
        if bg.shape not in ((1,), (3,)) or not np.all((bg >= 0) & (bg <= 1)):
            raise ValueError(f"background must be a grey level or an (r, g, b) triple in [0, 1], got {background!r}")
        if bits == 16 and bg.size == 3:
            raise ValueError("a 16-bit PNG is grey (Pillow writes colour PNGs at 8 bits): give a grey background, "
                             "or bits=8 for an (r, g, b) background")
        undefined = ~np.isfinite(v)
        levels = np.rint(np.clip(np.where(undefined, 0.0, v.astype(np.float64)), 0.0, 1.0) * top)
        if bg.size == 3:
            levels = np.repeat(levels[:, :, None], 3, axis=2)
        levels[undefined] = np.rint(bg * top)
        image = levels.astype(np.uint16 if bits == 16 else np.uint8)
        return _write_png(path, image)
    raise ValueError(f"{path}: unknown output format {path.suffix!r}; expected .exr, .png, .npy or .pfm")


def write_gbuffer(path, gbuffer, *, layer="View Layer", world_normals=False) -> Path:
    """Write a G-buffer's depth and normals, atomically: ``.exr`` (float32 channels
    ``<layer>.Depth.Z`` and ``<layer>.Normal.X/Y/Z``, Blender's names) or ``.npz`` (arrays
    ``depth`` and ``normal``).

    The depth is the linear view depth (+inf on background); the normals are view-space
    (``normal_space="view"`` when read back), or world-space with ``world_normals=True``.
    """
    path = Path(path)
    depth = np.asarray(gbuffer.depth)
    normal = np.asarray(gbuffer.world_normal if world_normals else gbuffer.normal)
    suffix = path.suffix.lower()
    if suffix == ".exr":
        channels = {f"{layer}.Depth.Z": depth.astype(np.float32)}
        for k, axis in enumerate("XYZ"):
            channels[f"{layer}.Normal.{axis}"] = normal[:, :, k].astype(np.float32)
        return atomic_write(path, _exr_bytes(channels))
    if suffix == ".npz":
        return atomic_write(path, lambda fh: np.savez_compressed(fh, depth=depth, normal=normal))
    raise ValueError(f"{path}: write_gbuffer writes .exr or .npz, got {path.suffix!r}")
