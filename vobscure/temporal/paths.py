"""Camera paths: the cameras of the frames of a sequence.

A path is a list of :class:`~vobscure.Camera`, one per frame, all with the first camera's
size and lens. ``static`` repeats the camera; ``orbit`` turns the eye about the vertical line
through the target; ``dolly`` moves the eye along the view direction towards the target; a
user's path is a list of camera records (:meth:`Camera.to_dict`), for example read from a JSON
file by :func:`cameras_from_file`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .._validate import check_choice, check_int, check_positive
from ..camera import Camera

__all__ = ["MOTIONS", "ORBIT_DEGREES_PER_FRAME", "DOLLY_FRACTION_PER_FRAME", "camera_path", "orbit_camera",
           "dolly_camera", "cameras_from_file", "cameras_from_records"]

#: The named camera motions of :func:`camera_path`.
MOTIONS = ("static", "orbit", "dolly")
#: Default turn of ``orbit`` per frame, in degrees: at 60 frames per second, 30 degrees a second,
#: a slow pan of a game camera.
ORBIT_DEGREES_PER_FRAME = 0.5
#: Default ``dolly`` step per frame, as a fraction of the first eye-to-target distance.
DOLLY_FRACTION_PER_FRAME = 0.005


def _look_at_record(camera) -> dict:
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure.Camera, got {type(camera).__name__}")
    d = camera.to_dict()
    if "eye" not in d:
        raise ValueError("camera must be a Camera.look_at camera (it has an eye and a target) to move it "
                         "along a path; give a list of cameras (cameras_from_records) instead")
    return d


def _lens(d: dict) -> dict:
    return dict(fov_y=d["fov_y"]) if d["ortho_height"] is None else dict(ortho_height=d["ortho_height"])


def orbit_camera(camera, degrees) -> Camera:
    """``camera`` with its eye turned by ``degrees`` about the vertical line (world y) through its
    target; the target, the up hint, the size and the lens stay.

    Examples
    --------
    >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(8, 8))
    >>> [round(float(v), 6) for v in orbit_camera(cam, 90).eye]
    [5.0, 0.0, 0.0]
    """
    d = _look_at_record(camera)
    eye, target = np.array(d["eye"], float), np.array(d["target"], float)
    rel = eye - target
    t = math.radians(float(degrees))
    c, s = math.cos(t), math.sin(t)
    # a right-handed turn about +y: (x, z) -> (c x + s z, -s x + c z)
    turned = np.array([c * rel[0] + s * rel[2], rel[1], -s * rel[0] + c * rel[2]])
    return Camera.look_at(target + turned, target, d["up"], size=tuple(d["size"]), **_lens(d))


def dolly_camera(camera, distance) -> Camera:
    """``camera`` with its eye moved ``distance`` (scene units; negative: backwards) along the view
    direction towards its target; refused when it would reach or pass the target.

    Examples
    --------
    >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(8, 8))
    >>> [round(float(v), 6) for v in dolly_camera(cam, 1.0).eye]
    [0.0, 0.0, 4.0]
    """
    d = _look_at_record(camera)
    eye, target = np.array(d["eye"], float), np.array(d["target"], float)
    length = float(np.linalg.norm(target - eye))
    if float(distance) >= length:
        raise ValueError(f"distance must be less than the eye-to-target distance {length:g}, got {distance!r}: "
                         "the eye would reach the target")
    moved = eye + (target - eye) / length * float(distance)
    return Camera.look_at(moved, target, d["up"], size=tuple(d["size"]), **_lens(d))


def camera_path(camera, frames: int, motion: str = "static", *, step=None) -> list[Camera]:
    """The ``frames`` cameras of a named motion that starts at ``camera``.

    Parameters
    ----------
    camera : Camera
        The first frame's camera; ``orbit`` and ``dolly`` need a :meth:`Camera.look_at` camera.
    frames : int
        Number of frames (>= 1).
    motion : {"static", "orbit", "dolly"}
        ``static``: the same camera every frame. ``orbit``: frame n turned by n x ``step``
        degrees about the vertical line through the target (:func:`orbit_camera`). ``dolly``:
        frame n moved n x ``step`` x the first eye-to-target distance towards the target
        (:func:`dolly_camera`).
    step : float, optional
        Per-frame step: degrees for ``orbit`` (default :data:`ORBIT_DEGREES_PER_FRAME`), a
        fraction of the eye-to-target distance for ``dolly`` (default
        :data:`DOLLY_FRACTION_PER_FRAME`; the path must stop short of the target). Unused by
        ``static``.

    Returns
    -------
    list of Camera

    Examples
    --------
    >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(8, 8))
    >>> path = camera_path(cam, 3, "dolly", step=0.1)
    >>> [round(float(c.eye[2]), 6) for c in path]
    [5.0, 4.5, 4.0]
    """
    frames = check_int(frames, "frames")
    check_choice(motion, "motion", MOTIONS)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure.Camera, got {type(camera).__name__}")
    if motion == "static":
        return [camera] * frames
    if motion == "orbit":
        step = ORBIT_DEGREES_PER_FRAME if step is None else check_positive(step, "step")
        return [camera] + [orbit_camera(camera, n * step) for n in range(1, frames)]
    step = DOLLY_FRACTION_PER_FRAME if step is None else check_positive(step, "step")
    d = _look_at_record(camera)
    length = float(np.linalg.norm(np.subtract(d["target"], d["eye"])))
    if (frames - 1) * step >= 1.0:
        raise ValueError(f"step x (frames - 1) must stay below 1 for a dolly (the eye would reach the target), "
                         f"got step={step:g} with frames={frames}")
    return [camera] + [dolly_camera(camera, n * step * length) for n in range(1, frames)]


def cameras_from_records(records, *, size=None) -> list[Camera]:
    """Cameras from a list of :meth:`Camera.to_dict` records (a user's camera path).

    Parameters
    ----------
    records : sequence of mapping
        One record per frame (``eye``, ``target``, ``size``, ... or intrinsics with a
        ``pose``); every camera must have the same size.
    size : (int, int), optional
        Replaces every record's ``size`` (the records may then omit it).

    Returns
    -------
    list of Camera
    """
    if isinstance(records, (str, bytes)) or not hasattr(records, "__len__") or len(records) == 0:
        raise ValueError("records must be a non-empty list of camera records (Camera.to_dict)")
    cams = []
    for n, rec in enumerate(records):
        if not isinstance(rec, dict):
            raise ValueError(f"records[{n}] must be a camera record (a dict), got {type(rec).__name__}")
        rec = dict(rec) if size is None else {**rec, "size": list(size)}
        try:
            cams.append(Camera.from_dict(rec))
        except ValueError as err:
            raise ValueError(f"records[{n}]: {err}") from None
    sizes = {c.size for c in cams}
    if len(sizes) > 1:
        raise ValueError(f"every camera of a path must have the same size, got {sorted(sizes)}")
    return cams


def cameras_from_file(path, *, size=None) -> list[Camera]:
    """The cameras of a JSON file holding a list of camera records (:meth:`Camera.to_dict`), or an
    object whose ``"cameras"`` entry is that list; see :func:`cameras_from_records`."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as err:
        raise ValueError(f"cameras file {str(p)!r} cannot be read: {err.strerror or err}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise ValueError(f"cameras file {str(p)!r} is not JSON: {err}") from None
    if isinstance(data, dict):
        if "cameras" not in data:
            raise ValueError(f"cameras file {str(p)!r} holds an object without a 'cameras' list")
        data = data["cameras"]
    try:
        return cameras_from_records(data, size=size)
    except ValueError as err:
        raise ValueError(f"cameras file {str(p)!r}: {err}") from None
