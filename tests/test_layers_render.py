"""render_gbuffer(layers=K): depth peeling against hand-computed depths, analytic chords and
the scene's own inside test."""

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.layers import intervals_from_layers
from vobscure.scenes import AlphaMask

INF = np.inf
#: Depths of the peeled layers against hand-computed ones: the hit is rebuilt in float64 on its
#: triangle's plane, but its position in the plane comes from Embree's float32 hit distance
#: (relative error ~6e-8 of coordinates of size ~5), and for a tilted plane that moves the view
#: depth: 1e-5 leaves a wide margin.
DEPTH_TOL = 1e-5


def _box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(bounds=np.stack([lo, hi]))


def _quad(x0, x1, z0, z1, y, *, up=True):
    v = np.array([[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]], float)
    f = np.array([[0, 2, 1], [0, 3, 2]]) if up else np.array([[0, 1, 2], [0, 2, 3]])
    return trimesh.Trimesh(v, f, process=False)


def _down(size=(6, 5), eye_y=3.0, height=2.0):
    """Orthographic camera looking down -y from (0, eye_y, 0): view depth = eye_y - y."""
    return vo.Camera.look_at((0, eye_y, 0), (0, 0, 0), up=(0, 0, -1), size=size, ortho_height=height)


def _perspective(size=(7, 5)):
    return vo.Camera.look_at((0, 4.0, 0), (0, 0, 0), up=(0, 0, -1), size=size, fov_y=20)


# ------------------------------------------------------------------ the first layer
@pytest.mark.parametrize("name", ["cornell_box", "sphere_on_plane"])
@pytest.mark.parametrize("K", [2, 4])
def test_first_layer_is_the_one_layer_gbuffer_bit_for_bit(name, K):
    scene = vo.scenes.get(name)
    cam = scene.camera((40, 30))
    one = vo.render_gbuffer(scene, cam)
    many = vo.render_gbuffer(scene, cam, layers=K)
    assert one.intervals is None and vo.render_gbuffer(scene, cam, layers=1).intervals is None
    for attr in ("depth", "normal", "valid", "primitive"):
        assert np.array_equal(getattr(one, attr), getattr(many, attr)), attr
    for key in ("index", "world_position", "world_normal", "world_geometric_normal"):
        assert np.array_equal(one.hits[key], many.hits[key]), key
    layers = many.intervals.layers
    assert np.array_equal(layers.depth[0], one.depth.astype(np.float32))
    assert np.array_equal(layers.primitive[0], one.primitive)


# ------------------------------------------------------------------ what is stored
@pytest.mark.parametrize("K", [2, 4, 8])
def test_stored_layers_and_float32_intervals(K):
    """Layer 0 is borrowed from the G-buffer (1 byte a pixel stored for it, 9 for each layer
    behind), the intervals are float32 (8 bytes a slot), and they are the enter/leave rule
    of the public function on the same surfaces, rounded to float32."""
    scene = vo.scenes.get("cornell_box")
    cam = scene.camera((40, 30))
    gb = vo.render_gbuffer(scene, cam, layers=K)
    s, layers = gb.intervals, gb.intervals.layers
    n = 40 * 30
    assert layers.nbytes == (1 + 9 * (K - 1)) * n
    assert s.dtype == np.float32 and s.front.nbytes == s.back.nbytes == 4 * s.count * n
    # the rule on the whole image at once, in float64 from the G-buffer's own depth (the
    # camera is inside no solid of the Cornell box)
    depth = np.concatenate([np.asarray(gb.depth, np.float64)[None], layers.depth[1:]])
    ref = intervals_from_layers(layers, depth=depth, origin_inside=np.zeros((30, 40), bool))
    assert ref.count == s.count
    assert np.array_equal(ref.front.astype(np.float32), s.front)
    assert np.array_equal(ref.back.astype(np.float32), s.back)


def test_chunks_of_the_peeling_assemble_the_same_image(monkeypatch):
    """Peeled in chunks of 7 rays (the pixels of one chunk need fewer slots than the image's
    M), the layers and intervals are those of one chunk per band."""
    import vobscure.render as render

    scene = vo.Scene({"sheet": _quad(-3, 0.1, -3, 3, 1.5), "inner": _quad(-3, 3, -3, 3, 0.0, up=False),
                      "box": _box((-3, -0.5, -3), (3, 0.5, 3))})
    cam = _perspective(size=(9, 8))
    whole = vo.render_gbuffer(scene, cam, layers=4)
    monkeypatch.setattr(render, "PEEL_RAYS", 7)
    chunked = vo.render_gbuffer(scene, cam, layers=4)
    a, b = whole.intervals, chunked.intervals
    assert a.count == b.count == 2
    assert np.isinf(a.front[1]).any() and np.isfinite(a.front[1]).any()   # some pixels need one slot
    assert np.array_equal(a.front, b.front) and np.array_equal(a.back, b.back)
    for attr in ("depth", "primitive", "entering", "open_surface"):
        assert np.array_equal(getattr(a.layers, attr), getattr(b.layers, attr)), attr


# ------------------------------------------------------------------ closed boxes, by hand
@pytest.mark.parametrize("camera", ["ortho", "perspective"])
def test_closed_box_seen_through(camera):
    # box y in [-0.5, 0.25]; camera above looking down: enter at the top, leave at the bottom
    scene = vo.Scene(_box((-3, -0.5, -3), (3, 0.25, 3)))
    cam = _down() if camera == "ortho" else _perspective()
    eye_y = cam.eye[1]
    gb = vo.render_gbuffer(scene, cam, layers=2)
    s, layers = gb.intervals, gb.intervals.layers
    assert s.count == 1
    # a plane perpendicular to the view axis has one view depth: eye_y - y, every pixel
    np.testing.assert_allclose(s.front[0], eye_y - 0.25, rtol=0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[0], eye_y + 0.5, rtol=0, atol=DEPTH_TOL)
    assert np.array_equal(s.front[0], gb.depth)           # the first surface, unrounded
    assert layers.entering[0].all() and not layers.entering[1].any()
    # the normals as the mesh winds them: up (towards the camera) at the top, down at the bottom
    n = layers.normal
    np.testing.assert_allclose(n[0], np.broadcast_to([0, 0, -1], n[0].shape), atol=1e-6)
    np.testing.assert_allclose(n[1], np.broadcast_to([0, 0, 1], n[1].shape), atol=1e-6)
    bottom = np.isin(layers.primitive[1], np.flatnonzero(scene.face_normals[:, 1] < -0.99))
    assert bottom.all()


def test_two_boxes_one_behind_the_other_and_more_layers_than_surfaces():
    scene = vo.Scene({"near": _box((-3, 0.5, -3), (3, 1.0, 3)), "far": _box((-3, -1.0, -3), (3, -0.25, 3))})
    gb = vo.render_gbuffer(scene, _down(), layers=6)
    s, layers = gb.intervals, gb.intervals.layers
    assert s.count == 2
    # view depth 3 - y: [2, 2.5] and [3.25, 4]
    for m, (a, b) in enumerate([(2.0, 2.5), (3.25, 4.0)]):
        np.testing.assert_allclose(s.front[m], a, atol=DEPTH_TOL)
        np.testing.assert_allclose(s.back[m], b, atol=DEPTH_TOL)
    assert layers.entering[:4, 0, 0].tolist() == [True, False, True, False]
    # four surfaces: layers 4 and 5 are empty
    assert np.isinf(layers.depth[4:]).all() and (layers.primitive[4:] == -1).all()
    assert not layers.entering[4:].any()


def test_box_standing_on_a_slab_is_one_interval():
    """Touching faces (box bottom on the slab's top at y = 0): the peeling sees only one of
    them; the enter/leave rule still gives one solid from the box's top to the slab's bottom."""
    scene = vo.Scene({"slab": _box((-3, -1.0, -3), (3, 0.0, 3)), "box": _box((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5))})
    gb = vo.render_gbuffer(scene, _down(size=(9, 9), height=3.0), layers=4)
    s = gb.intervals
    on_box = np.isclose(gb.depth, 2.0, atol=DEPTH_TOL)
    assert on_box.sum() > 4 and (~on_box).sum() > 20
    np.testing.assert_allclose(s.front[0][on_box], 2.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[0][on_box], 4.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.front[0][~on_box], 3.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[0][~on_box], 4.0, atol=DEPTH_TOL)
    assert np.isinf(s.front[1:]).all()


def test_camera_inside_a_box():
    # camera at y = 3 inside the box y in [2, 4]: the ray leaves at the bottom (depth 1),
    # then crosses the slab y in [-1, 0] (depths 3 and 4)
    scene = vo.Scene({"room": _box((-5, 2.0, -5), (5, 4.0, 5)), "slab": _box((-3, -1.0, -3), (3, 0.0, 3))})
    gb = vo.render_gbuffer(scene, _down(), layers=3)
    s, layers = gb.intervals, gb.intervals.layers
    assert not layers.entering[0].any() and layers.entering[1].all()
    np.testing.assert_allclose(gb.depth, 1.0, atol=DEPTH_TOL)
    assert (s.front[0] == 0.0).all()                          # from the near plane
    np.testing.assert_allclose(s.back[0], 1.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.front[1], 3.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[1], 4.0, atol=DEPTH_TOL)


# ------------------------------------------------------------------ open meshes and alpha
def test_open_sheet_is_a_zero_thickness_interval():
    # an open quad at y = 1.5 above a closed box y in [-0.5, 0.5], and one inside the box
    scene = vo.Scene({"sheet": _quad(-3, 3, -3, 3, 1.5), "inner": _quad(-3, 3, -3, 3, 0.0, up=False),
                      "box": _box((-3, -0.5, -3), (3, 0.5, 3))})
    assert sorted(scene.open_meshes) == ["inner", "sheet"]
    gb = vo.render_gbuffer(scene, _down(), layers=4)
    s, layers = gb.intervals, gb.intervals.layers
    assert s.count == 2
    np.testing.assert_allclose(s.front[0], 1.5, atol=DEPTH_TOL)
    assert np.array_equal(s.front[0], s.back[0])              # zero thickness
    np.testing.assert_allclose(s.front[1], 2.5, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[1], 3.5, atol=DEPTH_TOL)   # the inner sheet changes nothing
    assert layers.open_surface[:3, 0, 0].tolist() == [True, False, True]
    assert layers.nbytes == (1 + 9 * 3) * gb.depth.size       # the open flags are made from the triangles
    # the sheet's winding normal points up, towards the camera: "entering", whatever the rule
    assert layers.entering[0].all() and not layers.entering[2].any()
    # nothing is inside a zero-thickness interval except its own depth
    idx = np.zeros(3, dtype=np.int64)
    assert s.inside(np.array([1.5 - 1e-9, 1.5 + 1e-9, 3.0]), idx).tolist() == [False, False, True]


def test_alpha_holes_are_passed_by_the_peeling():
    # a card with a hole in its left half (alpha 0 at u < 0.5) over a closed box
    card = _quad(-0.5, 0.5, -0.5, 0.5, 1.0)
    uv = np.column_stack([card.vertices[:, 0] + 0.5, card.vertices[:, 2] + 0.5])
    mask = AlphaMask(uv[card.faces], np.array([[0.0, 1.0]]), cutoff=0.5)
    scene = vo.Scene({"card": card, "box": _box((-2, -0.5, -2), (2, 0.5, 2))}, alpha={"card": mask})
    cam = _down(size=(8, 8), height=1.0)         # pixels span x in [-0.5, 0.5]
    gb = vo.render_gbuffer(scene, cam, layers=3)
    s, layers = gb.intervals, gb.intervals.layers
    x = cam.primary_rays()[0][..., 0]            # the orthographic rays' world x
    hole, solid = x < -1e-3, x > 1e-3
    assert hole.sum() == solid.sum() == 32
    # through the hole: the box first, the card never
    np.testing.assert_allclose(layers.depth[0][hole], 2.5, atol=DEPTH_TOL)
    np.testing.assert_allclose(layers.depth[1][hole], 3.5, atol=DEPTH_TOL)
    assert np.isinf(layers.depth[2][hole]).all()
    np.testing.assert_allclose(s.front[0][hole], 2.5, atol=DEPTH_TOL)
    # on the solid texels: the card (a zero-thickness interval), then the box
    np.testing.assert_allclose(layers.depth[0][solid], 2.0, atol=DEPTH_TOL)
    assert layers.open_surface[0][solid].all()
    np.testing.assert_allclose(s.back[0][solid], 2.0, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.front[1][solid], 2.5, atol=DEPTH_TOL)
    np.testing.assert_allclose(s.back[1][solid], 3.5, atol=DEPTH_TOL)


# ------------------------------------------------------------------ analytic chord
def test_sphere_chord_against_the_analytic_one():
    r, subdivisions = 1.0, 4
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=r)
    scene = vo.Scene(sphere, smooth_angle=0)
    cam = vo.Camera.look_at((0.2, 0.1, 4.0), (0, 0, 0), size=(48, 48), fov_y=35)
    gb = vo.render_gbuffer(scene, cam, layers=3)
    s = gb.intervals
    origins, dirs = cam.primary_rays()
    e, d = cam.eye, dirs.reshape(-1, 3)
    # |e + t d|^2 = r^2: t = -b -+ sqrt(b^2 - c), with b = e . d, c = |e|^2 - r^2
    b = d @ e
    disc = b * b - (e @ e - r * r)
    # the impact parameter: distance of the ray's line from the centre
    impact = np.sqrt(np.maximum(e @ e - b * b, 0.0))
    # away from the silhouette: the chord's ends meet the sphere at cos(incidence) >= COS_MIN
    COS_MIN = 0.4
    core = impact < r * np.sqrt(1 - COS_MIN ** 2)
    assert core.sum() > 300
    root = np.sqrt(disc[core])
    to_z = d[core] @ cam.forward                       # view depth per unit ray length
    z_in, z_out = (-b[core] - root) * to_z, (-b[core] + root) * to_z
    # The mesh is inscribed in the sphere: its faces lie at most SAG inside it, which moves a
    # chord's end by at most SAG / cos(incidence) along the ray (times to_z <= 1 in depth).
    planes = np.abs(np.einsum("ij,ij->i", sphere.face_normals, sphere.triangles[:, 0]))
    SAG = r - planes.min()
    tol = SAG / COS_MIN + DEPTH_TOL
    front, back = s.front[0].reshape(-1)[core], s.back[0].reshape(-1)[core]
    assert np.abs(front - z_in).max() <= tol
    assert np.abs(back - z_out).max() <= tol
    # the faceted chord is never longer than the true one (the mesh lies inside the sphere)
    assert (back - front <= z_out - z_in + DEPTH_TOL).all()
    assert np.isinf(s.front[1:]).all()
    assert SAG < 0.01                                  # the check is tight: subdivisions=4


def test_torus_two_chords():
    """A ray along the view axis through both sides of a torus: two intervals, by the quartic."""
    R, rr = 1.0, 0.3
    torus = trimesh.creation.torus(major_radius=R, minor_radius=rr, major_sections=128, minor_sections=64)
    scene = vo.Scene(torus, smooth_angle=0)
    assert scene.is_watertight
    # trimesh's torus lies in the xy plane around the z axis; the camera looks along -x
    cam = vo.Camera.look_at((4.0, 0.0, 0.0), (0, 0, 0), up=(0, 1, 0), size=(3, 9), ortho_height=0.4)
    gb = vo.render_gbuffer(scene, cam, layers=6)
    s = gb.intervals
    # orthographic rays along -x at (y, z) = pixel offsets; torus (in the xy plane, axis z):
    # (sqrt(x^2 + y^2) - R)^2 + z^2 = rr^2  ->  x^2 = (R +- sqrt(rr^2 - z^2))^2 - y^2
    origins = cam.primary_rays()[0]
    y, z = origins[..., 1], origins[..., 2]
    w = np.sqrt(rr ** 2 - z ** 2)
    x_outer = np.sqrt((R + w) ** 2 - y ** 2)
    x_inner = np.sqrt((R - w) ** 2 - y ** 2)
    # view depth 4 - x: [4 - x_outer, 4 - x_inner] and [4 + x_inner, 4 + x_outer]
    # The mesh's vertices lie on the torus and its faces inside it, by at most the sagitta of
    # the major sections (at the outer radius) plus that of the minor ones. At these pixels
    # (|y| <= 0.2, |z| <= 0.07) the rays meet the surface within 25 degrees of its normal
    # (cos >= 0.9: asin(0.2 / 0.7) and asin(0.07 / 0.3) combined), so a depth moves by at
    # most SAG_T / 0.9.
    SAG_T = (R + rr) * (1 - np.cos(np.pi / 128)) + rr * (1 - np.cos(np.pi / 64))
    TOL = SAG_T / 0.9 + DEPTH_TOL
    assert s.count == 2
    np.testing.assert_allclose(s.front[0], 4 - x_outer, atol=TOL)
    np.testing.assert_allclose(s.back[0], 4 - x_inner, atol=TOL)
    np.testing.assert_allclose(s.front[1], 4 + x_inner, atol=TOL)
    np.testing.assert_allclose(s.back[1], 4 + x_outer, atol=TOL)


# ------------------------------------------------------------------ the scene's own inside test
def test_inside_agrees_with_the_scenes_inside_test():
    """Random view depths at random pixels of the Cornell box (closed meshes, boxes standing on
    the floor): ``intervals.inside`` against trimesh's ``contains`` of the same world points."""
    scene = vo.scenes.get("cornell_box")
    assert scene.is_watertight
    cam = scene.camera((48, 48))
    gb = vo.render_gbuffer(scene, cam, layers=8)
    s, layers = gb.intervals, gb.intervals.layers
    rng = np.random.default_rng(7)
    n = 4000
    index = rng.integers(0, 48 * 48, n)
    # up to the last surface found (beyond it the intervals hold what the layers did not see)
    last = np.where(np.isfinite(layers.depth), layers.depth, 0).max(axis=0).reshape(-1)
    z = rng.uniform(0.0, 1.0, n) * last[index]
    _, dirs = cam.primary_rays()
    d = dirs.reshape(-1, 3)[index]
    p = cam.eye + (z / (d @ cam.forward))[:, None] * d
    truth = np.zeros(n, dtype=bool)
    for mesh in scene.meshes.values():
        truth |= mesh.contains(p)
    got = s.inside(z, index)
    # points closer to a surface than the peeling's offset (1e-5 of the scale) may fall on
    # either side; they are a fraction ~1e-5 of the samples: allow none beyond those.
    near = np.abs(layers.depth.reshape(8, -1)[:, index] - z).min(axis=0) < 1e-4 * scene.extent
    disagree = (got != truth) & ~near
    assert truth.sum() > 200 and (~truth).sum() > 200
    assert disagree.sum() == 0, np.flatnonzero(disagree)[:10]


# ------------------------------------------------------------------ arguments
@pytest.mark.parametrize("layers", [0, -1, 1.5, True, "2", None])
def test_bad_layers(layers):
    with pytest.raises(ValueError, match="layers must be an integer >= 1"):
        vo.render_gbuffer(vo.scenes.slab(), _down(), layers=layers)


# ------------------------------------------------------------------ an engine's back-face pass
def _ndc(z, n, f):
    """OpenGL's window depth in [-1, 1] of linear depth z (glFrustum)."""
    return (f + n) / (f - n) - 2 * f * n / ((f - n) * z)


@pytest.mark.parametrize("kind", ["linear", "ndc", "reversed", "distance"])
def test_back_depth_is_one_interval(kind):
    """A back-face pass of the closed box, encoded as an engine would store it, read back as
    the box's interval found by the peeling."""
    scene = vo.Scene(_box((-3, -0.5, -3), (3, 0.25, 3)))
    cam = _perspective()
    peeled = vo.render_gbuffer(scene, cam, layers=2)
    # the peeled intervals are float32; the encodings are tested in float64
    z_f, z_b = peeled.depth, peeled.intervals.back[0].astype(np.float64)
    n, f = 0.5, 10.0
    rays = np.linalg.norm(cam.unproject(cam.pixel_centers(), 1.0), axis=-1)
    encode = {"linear": lambda z: z, "ndc": lambda z: _ndc(z, n, f),
              "reversed": lambda z: n / (n - f) - f * n / ((n - f) * z), "distance": lambda z: z * rays}[kind]
    gb = vo.GBuffer.from_arrays(encode(z_f), camera=cam, depth_kind=kind, near=n, far=f, back_depth=encode(z_b))
    s = gb.intervals
    assert s.count == 1 and s.layers is None
    # the encodings round-trip to ~1e-15 relative in float64
    np.testing.assert_allclose(s.front[0], z_f, rtol=1e-12)
    np.testing.assert_allclose(s.back[0], z_b, rtol=1e-12)
    assert gb.conversion["back_clamped"] == 0 and gb.conversion["back_background"] == 0


def test_back_depth_background_clamp_and_errors():
    cam = _down(size=(4, 3))
    front = np.full((3, 4), 2.0)
    front[0, 0] = np.inf                         # background pixel
    back = np.full((3, 4), 2.5)
    back[1, 1] = np.nan                          # no back face seen: +inf
    back[1, 2] = 1e10                            # background by the threshold: +inf
    back[2, 3] = 2.0 - 1e-9                      # in front of the front by rounding: clamped
    gb = vo.GBuffer.from_arrays(front, camera=cam, back_depth=back, background=1e9)
    s = gb.intervals
    assert np.isinf(s.front[0, 0, 0]) and np.isinf(s.back[0, 0, 0])
    assert np.isinf(s.back[0, 1, 1]) and np.isinf(s.back[0, 1, 2])
    assert s.back[0, 2, 3] == 2.0 and s.back[0, 2, 2] == 2.5
    assert gb.conversion["back_background"] == 2 and gb.conversion["back_clamped"] == 1
    # rows stored bottom-up are flipped like the depth
    up = vo.GBuffer.from_arrays(front[::-1], camera=cam, back_depth=back[::-1], background=1e9, origin="lower")
    assert np.array_equal(up.intervals.back, s.back)
    # float32 frames give float32 intervals
    assert vo.GBuffer.from_arrays(front.astype(np.float32), camera=cam, back_depth=back).intervals.dtype == np.float32
    with pytest.raises(ValueError, match="back_depth must have shape"):
        vo.GBuffer.from_arrays(front, camera=cam, back_depth=np.ones((4, 3)))
    with pytest.raises(ValueError, match="back_depth must give a positive linear depth"):
        vo.GBuffer.from_arrays(front, camera=cam, back_depth=-back)
    with pytest.raises(ValueError, match=r"back_depth \(depth_kind='ndc01'\) must lie in"):
        vo.GBuffer.from_arrays(np.full((3, 4), 0.5), camera=cam, depth_kind="ndc01", near=1, far=3,
                               back_depth=np.full((3, 4), -0.5))
    assert vo.GBuffer.from_arrays(front, camera=cam).intervals is None
    assert "back_clamped" not in vo.GBuffer.from_arrays(front, camera=cam).conversion
