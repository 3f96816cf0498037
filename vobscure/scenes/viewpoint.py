"""Where to look from: a default view for a scene without a camera, the camera stored in a
glTF file, and how much a view shows (coverage, one plane, one depth) with the warnings the
verdict prints.

:func:`suggest_view` renders candidate views at a tiny size and keeps the one that covers
most of the image and is least one plane. Candidates are views from outside the bounding
sphere (several azimuths and elevations, each as close as keeps the scene in the frame, and
closer) and, when the scene is enclosed (rays from a probe point inside its bounding box hit
front faces in nearly every direction: a room, an atrium),
only views from inside, at a standing height above the floor found by a downward ray. A built
scene keeps the view it was made with; :attr:`Scene.view <vobscure.scenes.Scene.view>` calls
:func:`suggest_view` only for a scene without one, once.

:func:`gltf_view` reads the first camera of a ``.gltf`` / ``.glb`` file's scene: glTF 2.0,
Sec. 3.10 "Cameras": the camera looks down its local -z axis with +y up, ``yfov`` is the
vertical field of view in radians, an orthographic camera's ``ymag`` is half the view height;
node transforms are a column-major ``matrix`` or ``translation`` x ``rotation`` (unit
quaternion x, y, z, w) x ``scale`` (Sec. 3.5.3); lengths are metres (Sec. 3.4).

:func:`view_diagnostics` measures a rendered G-buffer and :func:`view_warnings` turns the
numbers into sentences.

Examples
--------
>>> import trimesh, vobscure as vo
>>> from vobscure.scenes.viewpoint import suggest_view
>>> view = suggest_view(vo.Scene(trimesh.creation.box()))
>>> sorted(view), view["fov_y"]
(['eye', 'fov_y', 'target', 'up'], 45.0)
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np

__all__ = ["suggest_view", "view_diagnostics", "view_warnings", "gltf_view", "file_view",
           "SUGGEST_SIZE", "LOW_COVERAGE", "ONE_PLANE", "ONE_DEPTH", "EYE_HEIGHT_M"]

#: (width, height) of the candidate renders: 576 rays a view, enough to tell a wall from a room.
SUGGEST_SIZE = (32, 18)
#: Vertical field of view (degrees) of the views from outside (the library's default camera).
OUTSIDE_FOV_Y = 45.0
#: Vertical field of view (degrees) of the views from inside an enclosed scene: a wider lens,
#: as a person standing in a room sees it.
INSIDE_FOV_Y = 60.0
#: Azimuths (degrees, about +y) and elevations (degrees above the horizon) of the outside views.
OUTSIDE_AZIMUTHS = tuple(range(0, 360, 45))
OUTSIDE_ELEVATIONS = (20.0, 45.0)
#: Outside views keep the scene this much inside the frame (5 % margin).
FIT_MARGIN = 1.05
#: Each outside view also comes closer, to these fractions of its fitting distance: a view
#: that crops a large, flat scene (a game level seen from above) covers more of the image.
OUTSIDE_CLOSER = (1.0, 0.6)
#: Vertices used to fit an outside view (every k-th of the triangles' corners).
_FIT_POINTS = 100_000
#: Horizontal directions (degrees) and downward pitch (degrees) of the inside views.
INSIDE_AZIMUTHS = tuple(range(0, 360, 45))
INSIDE_PITCH = -10.0
#: Rays cast from a probe point to decide whether the scene encloses it.
PROBE_RAYS = 64
#: A probe point is enclosed when at least this fraction of its rays hit geometry ...
ENCLOSED_HITS = 0.9
#: ... and an eye is inside a solid (rejected) when more than this fraction of its hits are
#: back faces (the triangle's normal points along the ray).
BACK_FACES = 0.5
#: Eye height above the floor in a scene that declares metres (a standing person's eyes),
#: never above half the clear height; without units the eye is at EYE_HEIGHT_FRACTION of the
#: clear height.
EYE_HEIGHT_M = 1.6
EYE_HEIGHT_FRACTION = 0.4
#: A covered pixel lies on a plane when it is within this fraction of the covered points'
#: bounding-box diagonal of it.
PLANE_TOLERANCE = 0.01
#: Below this coverage the verdict warns that the view shows little of the scene.
LOW_COVERAGE = 0.5
#: At or above this fraction of covered pixels on one plane the verdict warns of one plane.
ONE_PLANE = 0.9
#: Below this relative depth spread ((z_95 - z_5) / median z) the verdict warns of one depth.
ONE_DEPTH = 0.05
#: Candidate planes and points tested for the dominant plane (deterministic subsets).
_PLANE_CANDIDATES = 256
_PLANE_POINTS = 4096


# --------------------------------------------------------------------------- suggest_view
def suggest_view(scene, *, size=SUGGEST_SIZE) -> dict:
    """A view of ``scene`` that covers most of the image and is not one plane.

    Parameters
    ----------
    scene : Scene
    size : (int, int), optional
        (width, height) of the candidate renders.

    Returns
    -------
    dict
        ``eye``, ``target``, ``up`` (tuples of 3 floats) and ``fov_y`` (degrees): the keys of
        :attr:`Scene.view <vobscure.scenes.Scene.view>`.

    Notes
    -----
    Every candidate is traced at ``size`` (one ray per pixel) and scored by coverage times
    (1 - the fraction of its hits on the dominant plane) times (1 - the fraction of its hits
    on back faces); ties go to the larger coverage.
    When a probe point (the bounding box's centre, or one of four points halfway to its
    sides at the centre's height) sees front faces in at least :data:`ENCLOSED_HITS` of its
    directions, the scene is enclosed and only inside views compete: from above each such
    probe, the eye stands at :data:`EYE_HEIGHT_M` (metres declared in ``scene.metadata``) or
    :data:`EYE_HEIGHT_FRACTION` of the clear height above the floor a downward ray finds, and
    looks in :data:`INSIDE_AZIMUTHS`; eyes whose rays mostly hit back faces (inside a solid)
    are rejected. Otherwise the views come from outside the bounding sphere. World space is
    y up (the library's convention), so a file written z up is looked at sideways.

    Raises
    ------
    ValueError
        When no candidate sees any geometry (not expected for a scene with triangles).

    Examples
    --------
    >>> import vobscure as vo
    >>> v = suggest_view(vo.scenes.sphere_on_plane())
    >>> round(float(np.linalg.norm(np.subtract(v["eye"], v["target"]))), 3) > 0
    True
    """
    from ..camera import check_size

    W, H = check_size(size)
    candidates = _inside_views(scene)
    if not candidates:
        candidates = _outside_views(scene)
    best, best_key = None, None
    for view in candidates:
        d = _trace_diagnostics(scene, view, (W, H))
        score = (d["coverage"] * (1.0 - d["plane_fraction"]) * (1.0 - d["back_faces"])
                 if d["coverage"] > 0 else -1.0)
        key = (round(score, 12), d["coverage"])
        if best_key is None or key > best_key:
            best, best_key = view, key
    if best is None or best_key[1] <= 0:
        raise ValueError(f"no candidate view of scene {getattr(scene, 'name', '?')!r} sees any geometry")
    return best


def _view(eye, target, fov_y) -> dict:
    return {"eye": tuple(float(x) for x in eye), "target": tuple(float(x) for x in target),
            "up": (0.0, 1.0, 0.0), "fov_y": float(fov_y)}


def _outside_views(scene) -> list[dict]:
    """Views from outside, each as close as keeps every vertex inside the central square of
    the image (so any aspect ratio of 1 or wider shows the whole scene), at most as far as
    the library's default that frames the bounding sphere, and closer by :data:`OUTSIDE_CLOSER`;
    that default (+z) first."""
    centre = np.asarray(scene.center, dtype=np.float64)
    frame = 0.5 * float(scene.extent) / math.sin(math.radians(OUTSIDE_FOV_Y) / 2)
    views = [_view(centre + np.array([0.0, 0.0, FIT_MARGIN * frame]), centre, OUTSIDE_FOV_Y)]
    points = np.asarray(scene.triangles, dtype=np.float64).reshape(-1, 3)
    points = points[::max(1, len(points) // _FIT_POINTS)] - centre
    tan_half = math.tan(math.radians(OUTSIDE_FOV_Y) / 2)
    for el in OUTSIDE_ELEVATIONS:
        for az in OUTSIDE_AZIMUTHS:
            a, e = math.radians(az), math.radians(el)
            back = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
            right = np.cross((0.0, 1.0, 0.0), back)
            right /= np.linalg.norm(right)
            up = np.cross(back, right)
            # a point at offset q from the centre, seen from centre + D * back, lies at depth
            # D - q.back and inside the square when |q.right|, |q.up| <= tan_half x depth
            reach = np.maximum(np.abs(points @ right), np.abs(points @ up)) / tan_half + points @ back
            distance = min(FIT_MARGIN * float(reach.max()), FIT_MARGIN * frame)
            views += [_view(centre + factor * distance * back, centre, OUTSIDE_FOV_Y) for factor in OUTSIDE_CLOSER]
    return views


def _sphere_directions(n: int) -> np.ndarray:
    """(n, 3) unit directions spread evenly over the sphere (a Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    y = 1.0 - 2.0 * i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    s = np.sqrt(1.0 - y * y)
    return np.column_stack([s * np.cos(phi), y, s * np.sin(phi)])


def _probe(scene, point) -> tuple[float, float]:
    """(fraction of :data:`PROBE_RAYS` rays from ``point`` that hit, fraction of hits that
    are back faces)."""
    d = _sphere_directions(PROBE_RAYS)
    o = np.broadcast_to(np.asarray(point, dtype=np.float64), d.shape)
    hits = scene.tracer.intersect(o, d)
    hit = hits.primitive >= 0
    if not hit.any():
        return 0.0, 0.0
    back = np.einsum("ij,ij->i", scene.face_normals[hits.primitive[hit]], d[hit]) > 0
    return float(hit.mean()), float(back.mean())


def _first_hit(scene, origin, direction):
    """(point, distance) of the first hit of one ray, or (None, inf); the point is moved onto
    its triangle's plane (as the G-buffer does), which removes Embree's float32 error across it."""
    o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
    hits = scene.tracer.intersect(o[None], d[None])
    prim = int(hits.primitive[0])
    if prim < 0:
        return None, math.inf
    n = scene.face_normals[prim]
    p = o + float(hits.distance[0]) * d
    p = p - (float(np.dot(n, p)) - float(scene.plane_offsets[prim])) * n
    return p, float(np.dot(p - o, d))


def _inside_views(scene) -> list[dict]:
    """Views from inside, when the scene encloses one of its probe points; else []."""
    lo, hi = np.asarray(scene.bounds, dtype=np.float64)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    probes = [centre] + [centre + np.array([sx * 0.5 * half[0], 0.0, sz * 0.5 * half[2]])
                         for sx, sz in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
    metres = (getattr(scene, "metadata", None) or {}).get("units") == "m"
    eps = 1e-6 * float(scene.extent)
    views = []
    for p in probes:
        hit_fraction, back_fraction = _probe(scene, p)
        if hit_fraction < ENCLOSED_HITS or back_fraction > BACK_FACES:
            continue
        floor, _ = _first_hit(scene, p, (0.0, -1.0, 0.0))
        if floor is None:
            continue
        ceiling, _ = _first_hit(scene, floor + [0.0, eps, 0.0], (0.0, 1.0, 0.0))
        clear = (ceiling[1] if ceiling is not None else hi[1]) - floor[1]
        if not clear > 2 * eps:        # the probe lies on a surface with nothing above it
            continue
        height = min(EYE_HEIGHT_M, 0.5 * clear) if metres else EYE_HEIGHT_FRACTION * clear
        eye = floor + np.array([0.0, height, 0.0])
        if _probe(scene, eye)[1] > BACK_FACES:
            continue
        for az in INSIDE_AZIMUTHS:
            a, e = math.radians(az), math.radians(INSIDE_PITCH)
            d = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
            point, t = _first_hit(scene, eye, d)
            target = point if point is not None and t > eps else eye + 0.25 * float(scene.extent) * d
            views.append(_view(eye, target, INSIDE_FOV_Y))
    return views


def _trace_diagnostics(scene, view: dict, size) -> dict:
    """:func:`view_diagnostics` numbers of ``view`` traced at ``size`` (primary rays only)."""
    from ..camera import Camera

    cam = Camera.look_at(view["eye"], view["target"], view.get("up", (0.0, 1.0, 0.0)), size=size,
                         fov_y=view.get("fov_y"), ortho_height=view.get("ortho_height"))
    o, d = cam.primary_rays()
    o, d = np.ascontiguousarray(o.reshape(-1, 3)), d.reshape(-1, 3)
    hits = scene.tracer.intersect(o, d)
    hit = hits.primitive >= 0
    p = o[hit] + hits.distance[hit, None] * d[hit]
    n = scene.face_normals[hits.primitive[hit]]
    z = (p - cam.eye) @ cam.forward
    back = np.einsum("ij,ij->i", n, d[hit]) > 0
    return _diagnostics(hit.size, p, n, z, back)


# --------------------------------------------------------------------------- diagnostics
def _dominant_plane_fraction(points: np.ndarray, normals: np.ndarray) -> float:
    """Fraction of ``points`` within :data:`PLANE_TOLERANCE` x their bounding-box diagonal of
    the best plane among those through a subset of the points with their normals."""
    n = len(points)
    if n == 0:
        return math.nan
    if n > _PLANE_POINTS:
        keep = np.linspace(0, n - 1, _PLANE_POINTS).astype(np.int64)
        points, normals, n = points[keep], normals[keep], _PLANE_POINTS
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if diagonal == 0.0:
        return 1.0
    tol = PLANE_TOLERANCE * diagonal
    pick = np.unique(np.linspace(0, n - 1, min(n, _PLANE_CANDIDATES)).astype(np.int64))
    plane_n = normals[pick]
    plane_c = np.einsum("ij,ij->i", plane_n, points[pick])
    on_plane = np.abs(points @ plane_n.T - plane_c) <= tol          # (n, candidates)
    return float(on_plane.sum(axis=0).max() / n)


def _diagnostics(pixels: int, points, normals, depth, back) -> dict:
    covered = len(points)
    out = {"coverage": covered / pixels if pixels else 0.0, "covered_pixels": int(covered),
           "pixels": int(pixels), "plane_fraction": math.nan, "depth_min": math.nan,
           "depth_max": math.nan, "depth_spread": math.nan, "back_faces": math.nan}
    if covered == 0:
        return out
    z = np.asarray(depth, dtype=np.float64)
    z5, z50, z95 = np.percentile(z, [5, 50, 95])
    out.update(plane_fraction=_dominant_plane_fraction(np.asarray(points, float), np.asarray(normals, float)),
               depth_min=float(z.min()), depth_max=float(z.max()),
               depth_spread=float((z95 - z5) / z50) if z50 > 0 else math.nan)
    if back is not None:
        out["back_faces"] = float(np.mean(back))
    return out


def view_diagnostics(gbuffer, scene=None) -> dict:
    """How much of the scene a rendered view shows.

    Parameters
    ----------
    gbuffer : GBuffer
    scene : Scene, optional
        The scene ``gbuffer`` was rendered from (its ``primitive`` indexes the scene's
        triangles): adds ``back_faces``, the fraction of covered pixels that see the back of
        their triangle (a camera inside a solid sees only back faces).

    Returns
    -------
    dict
        ``coverage`` (fraction of pixels covered), ``covered_pixels``, ``pixels``,
        ``plane_fraction`` (fraction of covered pixels within :data:`PLANE_TOLERANCE` x the
        covered points' bounding-box diagonal of one plane, the best among the planes through
        covered pixels with their normals), ``depth_min``, ``depth_max`` (view z),
        ``depth_spread`` ((z_95 - z_5) / median z) and ``back_faces`` (NaN without
        ``scene``). The NaNs stand for "not measured" when no pixel is covered.

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(8, 8), ortho_height=1.0)
    >>> d = view_diagnostics(vo.render_gbuffer(vo.scenes.slab(), cam))
    >>> d["coverage"], d["plane_fraction"], d["depth_spread"]
    (1.0, 1.0, 0.0)
    """
    valid = np.asarray(gbuffer.valid, dtype=bool)
    depth = np.asarray(gbuffer.depth)[valid]
    points = np.asarray(gbuffer.position)[valid]
    normals = np.asarray(gbuffer.normal)[valid]
    back = None
    if scene is not None:
        prim = np.asarray(gbuffer.primitive)[valid]
        if np.any(prim < 0) or np.any(prim >= len(scene.face_normals)):
            raise ValueError("gbuffer was not rendered from scene: its primitive indices do not fit scene's "
                             f"{len(scene.face_normals)} triangles")
        cam = gbuffer.camera
        world = np.asarray(gbuffer.world_position)[valid]
        rays = world - cam.eye if cam.is_perspective else np.broadcast_to(cam.forward, world.shape)
        back = np.einsum("ij,ij->i", scene.face_normals[prim], rays) > 0
    return _diagnostics(valid.size, points, normals, depth, back)


def view_warnings(diagnostics: dict) -> list[str]:
    """Sentences for the verdict about a view that shows little: no or low coverage, nearly
    one plane, nearly one depth, back faces (a camera inside a solid).

    Parameters
    ----------
    diagnostics : dict
        :func:`view_diagnostics` of the view.

    Returns
    -------
    list of str
        Empty for a view that shows the scene well.

    Examples
    --------
    >>> view_warnings({"coverage": 0.2, "plane_fraction": 1.0, "depth_spread": 0.0})[0][:40]
    'The view covers 20% of the image: the er'
    """
    out = []
    coverage = float(diagnostics.get("coverage", math.nan))
    if not coverage > 0:
        return ["The view covers no pixel of the scene: there is nothing to measure; give a camera that "
                "looks at the geometry (--eye X Y Z --target X Y Z)."]
    if coverage < LOW_COVERAGE:
        out.append(f"The view covers {coverage:.0%} of the image: the errors describe that part only; a camera "
                   "closer to the geometry (--eye, --target) measures more of it.")
    plane = float(diagnostics.get("plane_fraction", math.nan))
    if plane >= ONE_PLANE:
        out.append(f"{plane:.0%} of the covered pixels lie on one plane: a flat surface is the easy case of every "
                   "estimator, so this verdict says little about creases, contacts and occluders.")
    spread = float(diagnostics.get("depth_spread", math.nan))
    if spread < ONE_DEPTH:
        out.append(f"The covered pixels are nearly at one depth (spread {spread:.1%} of the median depth): the "
                   "view shows little depth variation for the estimators to get wrong.")
    back = float(diagnostics.get("back_faces", math.nan))
    if back > BACK_FACES:
        out.append(f"{back:.0%} of the covered pixels see the back of their triangle: the camera may be inside a "
                   "solid.")
    return out


# --------------------------------------------------------------------------- glTF cameras
_GLB_MAGIC = 0x46546C67        # b"glTF", glTF 2.0 Sec. 4.4.2 (GLB header)
_GLB_JSON = 0x4E4F534A         # b"JSON", Sec. 4.4.3.1 (chunk type)


def _gltf_json(path: Path) -> dict:
    """The JSON document of a ``.gltf`` file or of a ``.glb`` file's first chunk."""
    data = path.read_bytes()
    if path.suffix.lower() == ".glb":
        if len(data) < 20:
            raise ValueError(f"{path}: too short for a GLB file (a 12-byte header and a JSON chunk)")
        magic, _version, _length = struct.unpack_from("<III", data, 0)
        chunk_length, chunk_type = struct.unpack_from("<II", data, 12)
        if magic != _GLB_MAGIC or chunk_type != _GLB_JSON:
            raise ValueError(f"{path}: not a GLB file (no glTF header followed by a JSON chunk)")
        data = data[20:20 + chunk_length]
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: the glTF JSON cannot be read: {exc}") from exc
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: the glTF JSON is not an object")
    return doc


def _node_matrix(node: dict) -> np.ndarray:
    """A node's local 4 x 4 transform: ``matrix`` (column-major) or T x R x S, glTF 2.0 Sec. 3.5.3."""
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T
    x, y, z, w = (float(v) for v in node.get("rotation", (0.0, 0.0, 0.0, 1.0)))
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    M = np.eye(4)
    M[:3, :3] = R * np.asarray(node.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)[None, :]
    M[:3, 3] = np.asarray(node.get("translation", (0.0, 0.0, 0.0)), dtype=np.float64)
    return M


def gltf_view(path, *, center=None) -> dict | None:
    """The view of the first camera node in a ``.gltf`` / ``.glb`` file's scene, or None.

    Parameters
    ----------
    path : str or os.PathLike
    center : (3,) float, optional
        A point of interest (the scene's bounding-box centre): the view's ``target`` is the
        point of the camera's axis nearest to it (``eye`` + 1 forward when it is behind the
        camera or not given). Only the direction matters for the image; the target is what
        a camera orbit turns about.

    Returns
    -------
    dict or None
        ``eye``, ``target``, ``up`` and ``fov_y`` (degrees, from ``yfov``; perspective) or
        ``ortho_height`` (2 ``ymag``; orthographic), plus ``aspect_ratio`` when the file gives
        one (width / height; the image size is the caller's). None when no node of the
        file's default scene (``scene``, else the first) holds a camera.

    Raises
    ------
    ValueError
        For a file whose JSON cannot be read, or a camera without its ``perspective`` /
        ``orthographic`` parameters (the message names the camera).

    Notes
    -----
    glTF 2.0 Sec. 3.10.1: "the camera is defined such that the local +X axis is to the
    right, the lens looks towards the local -Z axis, and the top of the camera is aligned
    with the local +Y axis"; its world transform is the product of the node transforms from
    the scene's root (Sec. 3.5.2). The first camera in depth-first order of the scene's
    nodes is used.

    Examples
    --------
    >>> import json, tempfile, pathlib
    >>> doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    ...        "nodes": [{"translation": [0, 1, 5], "camera": 0}],
    ...        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]}
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "cam.gltf"
    ...     _ = path.write_text(json.dumps(doc))
    ...     view = gltf_view(path)
    >>> view["eye"], view["target"], view["up"], round(view["fov_y"], 4)
    ((0.0, 1.0, 5.0), (0.0, 1.0, 4.0), (0.0, 1.0, 0.0), 28.6479)
    """
    path = Path(path)
    doc = _gltf_json(path)
    nodes = doc.get("nodes") or []
    cameras = doc.get("cameras") or []
    if not cameras or not nodes:
        return None
    scenes = doc.get("scenes") or []
    if scenes:
        roots = scenes[int(doc.get("scene", 0))].get("nodes", [])
    else:
        children = {c for n in nodes for c in n.get("children", [])}
        roots = [i for i in range(len(nodes)) if i not in children]
    stack = [(int(i), np.eye(4)) for i in reversed(roots)]
    while stack:
        index, parent = stack.pop()
        node = nodes[index]
        world = parent @ _node_matrix(node)
        if "camera" in node:
            return _camera_view(cameras[int(node["camera"])], int(node["camera"]), world, center, path)
        stack.extend((int(c), world) for c in reversed(node.get("children", [])))
    return None


def _camera_view(camera: dict, index: int, world: np.ndarray, center, path: Path) -> dict:
    eye = world[:3, 3]
    forward = -world[:3, 2]
    up = world[:3, 1]
    if not (np.linalg.norm(forward) > 0 and np.linalg.norm(up) > 0):
        raise ValueError(f"{path}: camera {index}'s node transform is singular")
    forward, up = forward / np.linalg.norm(forward), up / np.linalg.norm(up)
    distance = 1.0
    if center is not None:
        along = float(np.dot(np.asarray(center, dtype=np.float64) - eye, forward))
        distance = along if along > 0 else 1.0
    view = {"eye": tuple(float(v) for v in eye), "target": tuple(float(v) for v in eye + distance * forward),
            "up": tuple(float(v) + 0.0 for v in up)}
    kind = camera.get("type")
    params = camera.get(kind) if kind in ("perspective", "orthographic") else None
    if not isinstance(params, dict):
        raise ValueError(f"{path}: camera {index} ({camera.get('name', 'unnamed')!r}) has type {kind!r} without "
                         "its 'perspective' or 'orthographic' parameters")
    if kind == "perspective":
        view["fov_y"] = math.degrees(float(params["yfov"]))
        if params.get("aspectRatio") is not None:
            view["aspect_ratio"] = float(params["aspectRatio"])
    else:
        view["ortho_height"] = 2.0 * float(params["ymag"])
        view["aspect_ratio"] = float(params["xmag"]) / float(params["ymag"])
    return view


def file_view(path, meshes=None) -> dict:
    """The keyword arguments of :class:`~vobscure.scenes.Scene` that a mesh file declares:
    for ``.gltf`` / ``.glb``, ``metadata={"units": "m"}`` (glTF 2.0 Sec. 3.4: "the units for
    all linear distances are meters") and ``view`` when it holds a camera
    (:func:`gltf_view`, its target nearest the meshes' bounding-box centre); ``{}`` for
    other formats.

    Examples
    --------
    >>> file_view("bunny.obj")
    {}
    """
    path = Path(path)
    if path.suffix.lower() not in (".gltf", ".glb"):
        return {}
    center = None
    if meshes:
        v = np.concatenate([np.asarray(m.vertices, dtype=np.float64) for m in meshes.values()])
        center = 0.5 * (v.min(axis=0) + v.max(axis=0))
    view = gltf_view(path, center=center)
    return {"metadata": {"units": "m"}, **({"view": view} if view is not None else {})}
