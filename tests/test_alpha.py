"""Alpha-tested geometry: holes made by an alpha texture behave as holes cut in the geometry.

Every check builds the same shape twice: a card whose alpha texture has holes, and a mesh made
of the card's solid texels only (two triangles per texel), and compares what the tracer, the
G-buffer and the ray-cast references see through them, from below and from above.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import vobscure as vo
from conftest import t_threshold
from vobscure.raytrace import Tracer, TriangleAlpha, texel_lookup
from vobscure.scenes import AlphaMask

#: Height of the floor (y = 0), the card and the roof, whose underside faces the card.
CARD_Y, ROOF_Y = 0.3, 0.6
#: Texture coordinates closer than this to a texel edge are "grazing" in the G-buffer
#: comparison: the float32 barycentrics Embree reports carry errors of ~1e-7 in u and v,
#: so a ray that close to an edge may fall in either texel (1e-5 leaves a 100x margin).
EDGE_UV = 1e-5
#: Distances agree to Embree's float32 precision (relative 6e-8 of coordinates ~1): 1e-5.
DEPTH_ATOL = 1e-5


def _quad(x0, x1, z0, z1, y):
    """Two triangles spanning [x0, x1] x [z0, z1] at height y, normal +y."""
    v = np.array([[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]], float)
    return v, np.array([[0, 2, 1], [0, 3, 2]])


def _card(texture, *, y=CARD_Y, cutoff=0.5, repeat=1.0):
    """The unit card [-0.5, 0.5]^2 at height y, u = x + 1/2, v = z + 1/2 (times ``repeat``)."""
    v, f = _quad(-0.5, 0.5, -0.5, 0.5, y)
    uv = repeat * np.column_stack([v[:, 0] + 0.5, v[:, 2] + 0.5])
    return trimesh.Trimesh(v, f, process=False), AlphaMask(uv[f], texture, cutoff=cutoff)


def _texel_mesh(solid, *, y=CARD_Y):
    """The solid texels of a (h, w) grid on the unit card as real geometry (row 0 at v = 1)."""
    h, w = solid.shape
    vs, fs = [], []
    for i, j in zip(*np.nonzero(solid)):
        # texel (i, j) covers u in [j/w, (j+1)/w), v in [1 - (i+1)/h, 1 - i/h)
        v, f = _quad(j / w - 0.5, (j + 1) / w - 0.5, 0.5 - (i + 1) / h, 0.5 - i / h, y)
        fs.append(f + 4 * len(vs))
        vs.append(v)
    return trimesh.Trimesh(np.concatenate(vs), np.concatenate(fs), process=False)


def _surroundings(roof_x):
    floor = trimesh.Trimesh(*_quad(-2, 2, -2, 2, 0.0), process=False)
    roof = trimesh.Trimesh(*_quad(*roof_x, -2, 2, ROOF_Y), process=False)
    return {"floor": floor, "roof": roof}


def _scenes(texture, cutoff=0.5, roof_x=(-2.0, -0.01)):
    """(scene with the alpha-tested card, scene with the solid texels as geometry), between a
    floor and a roof over x in ``roof_x`` (by default half of the card is under open sky)."""
    card, mask = _card(texture, cutoff=cutoff)
    alpha = vo.Scene({**_surroundings(roof_x), "card": card}, alpha={"card": mask}, smooth_angle=0)
    holes = vo.Scene({**_surroundings(roof_x), "card": _texel_mesh(np.asarray(texture) >= cutoff)},
                     smooth_angle=0)
    return alpha, holes


def _checker():
    """8 x 8 texels, a random pattern with both kinds of cells along every row."""
    rng = np.random.default_rng(20)
    return (rng.random((8, 8)) < 0.5).astype(np.float32)


def _disc():
    """32 x 32 texels: a disc of alpha 1 with a ring of partial alpha, 0 outside."""
    i, j = np.mgrid[0:32, 0:32]
    r = np.hypot(i + 0.5 - 16, j + 0.5 - 16) / 16
    return np.clip((0.8 - r) / 0.2, 0.0, 1.0).astype(np.float32)


TEXTURES = {"checker": _checker, "disc": _disc}


# -- the tracer ----------------------------------------------------------------------------
def test_texel_lookup_convention():
    """Nearest texel, row 0 at the top (v = 1), repeat outside [0, 1], texel edges exact."""
    tex = np.arange(6, dtype=np.float32).reshape(2, 3) / 5   # 2 rows, 3 columns
    uv = np.array([[0.0, 0.0], [0.999, 0.0], [0.0, 0.5], [1 / 3, 0.999], [2.0, 1.0], [-1e-20, -1e-20],
                   [-0.5, 3.25]])
    # bottom-left is row 1 col 0; u = 0.999 column 2; v = 0.5 is the top row; u = 1/3 column 1;
    # u = 2, v = 1 wrap to (0, 0); a tiny negative u, v wrap into the last column, top row
    expected = tex[[1, 1, 0, 0, 1, 0, 1], [0, 2, 0, 1, 0, 2, 1]]
    np.testing.assert_array_equal(texel_lookup(tex, uv), expected)


@pytest.mark.parametrize("direction", [-1.0, 1.0])
def test_rays_pass_holes_both_ways_and_keep_primitive_ids(direction):
    """A ray through a hole reaches what lies behind it, from either side; the primitive it
    reports indexes the full triangle array; max_distance still limits the whole path."""
    alpha, holes = _scenes(_checker(), roof_x=(-2.0, 2.0))
    solid = _checker() >= 0.5
    # one ray through the centre of every texel, downwards from the roof or up from the floor
    i, j = np.mgrid[0:8, 0:8]
    x, z = (j.ravel() + 0.5) / 8 - 0.5, 0.5 - (i.ravel() + 0.5) / 8
    y0 = ROOF_Y - 0.01 if direction < 0 else 0.01
    o = np.column_stack([x, np.full_like(x, y0), z])
    d = np.tile([0.0, direction, 0.0], (len(o), 1))
    hits = alpha.tracer.intersect(o, d)
    behind = "floor" if direction < 0 else "roof"
    names = np.array(list(alpha.meshes))[alpha.mesh_index[hits.primitive]]
    np.testing.assert_array_equal(names, np.where(solid.ravel(), "card", behind))
    expected = np.where(solid.ravel(), abs(CARD_Y - y0), abs((0.0 if direction < 0 else ROOF_Y) - y0))
    np.testing.assert_allclose(hits.distance, expected, atol=DEPTH_ATOL)
    np.testing.assert_array_equal(alpha.tracer.occluded(o, d), holes.tracer.occluded(o, d))
    # the rays through holes stop short of the floor/roof: nothing within 0.9 of the gap
    short = alpha.tracer.occluded(o, d, max_distance=0.9 * expected)
    assert not short.any()
    limited = alpha.tracer.intersect(o, d, np.where(solid.ravel(), 1.0, 0.9 * expected))
    np.testing.assert_array_equal(limited.hit, solid.ravel())


def test_stacked_cards_need_several_passes():
    """Ten cards with shifted holes above one another: each ray crosses holes of several
    cards before it stops, and the tracer agrees with the same cards cut as geometry."""
    rng = np.random.default_rng(3)
    meshes, alpha, cut = {}, {}, {}
    for k in range(10):
        tex = (rng.random((6, 6)) < 0.25).astype(np.float32)        # mostly holes
        card, mask = _card(tex, y=0.05 * (k + 1))
        meshes[f"card{k}"], alpha[f"card{k}"] = card, mask
        if tex.any():
            cut[f"card{k}"] = _texel_mesh(tex >= 0.5, y=0.05 * (k + 1))
    floor = trimesh.Trimesh(*_quad(-2, 2, -2, 2, 0.0), process=False)
    with_alpha = vo.Scene({"floor": floor, **meshes}, alpha=alpha, smooth_angle=0)
    as_geometry = vo.Scene({"floor": floor, **cut}, smooth_angle=0)
    o = np.column_stack([rng.uniform(-0.45, 0.45, 4000), np.full(4000, 0.01), rng.uniform(-0.45, 0.45, 4000)])
    d = rng.normal(size=(4000, 3))
    d[:, 1] = np.abs(d[:, 1]) + 0.2
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    a, b = with_alpha.tracer.intersect(o, d), as_geometry.tracer.intersect(o, d)
    np.testing.assert_array_equal(a.hit, b.hit)
    np.testing.assert_allclose(a.distance[a.hit], b.distance[b.hit], atol=DEPTH_ATOL)
    assert np.mean(a.hit) > 0.5
    np.testing.assert_array_equal(with_alpha.tracer.occluded(o, d), as_geometry.tracer.occluded(o, d))
    # a length limit holds for the whole path, across the passes
    limit = rng.uniform(0.05, 0.6, len(o))
    np.testing.assert_array_equal(with_alpha.tracer.occluded(o, d, limit), as_geometry.tracer.occluded(o, d, limit))
    np.testing.assert_array_equal(with_alpha.tracer.intersect(o, d, limit).primitive >= 0,
                                  as_geometry.tracer.intersect(o, d, limit).primitive >= 0)
    # hits are on the same card (heights) in both scenes
    np.testing.assert_allclose(with_alpha.tracer.hit_points(a)[a.hit, 1],
                               as_geometry.tracer.hit_points(b)[b.hit, 1], atol=DEPTH_ATOL)


def test_cutoff_edges_and_repeat():
    """cutoff 0: every texel solid; cutoff 1: only alpha exactly 1 solid; uv outside [0, 1]
    repeat the texture (a 2 x 2 texture tiled twice is the 4 x 4 texture it tiles)."""
    rng = np.random.default_rng(5)
    o = np.column_stack([rng.uniform(-0.5, 0.5, 3000), np.full(3000, 0.01), rng.uniform(-0.5, 0.5, 3000)])
    d = np.tile([0.0, 1.0, 0.0], (3000, 1))
    tex = np.array([[1.0, 0.999], [0.0, 1.0]], np.float32)

    def blocked(texture, cutoff, repeat=1.0):
        card, mask = _card(texture, cutoff=cutoff, repeat=repeat)
        return vo.Scene({"card": card}, alpha={"card": mask}).tracer.occluded(o, d)

    def inside(grid):   # which texel of a (h, w) grid each ray crosses
        h, w = grid.shape
        col = np.floor((o[:, 0] + 0.5) * w).astype(int)
        row = h - 1 - np.floor((o[:, 2] + 0.5) * h).astype(int)
        return grid[row, col]

    assert blocked(tex, 0.0).all()
    assert blocked(np.zeros((3, 3), np.float32), 0.0).all()
    np.testing.assert_array_equal(blocked(tex, 1.0), inside(tex == 1.0))
    np.testing.assert_array_equal(blocked(tex, 0.5), inside(tex >= 0.5))
    np.testing.assert_array_equal(blocked(tex, 0.5, repeat=2.0), inside(np.tile(tex, (2, 2)) >= 0.5))
    np.testing.assert_array_equal(blocked(tex, 0.5, repeat=-1.0), inside(tex[::-1, ::-1] >= 0.5))


def test_without_alpha_the_tracer_is_the_plain_one():
    """No masked triangle: the same queries, bit for bit, and no second Embree scene."""
    scene = vo.scenes.crease()
    rng = np.random.default_rng(1)
    o = rng.uniform(-1, 1, (5000, 3)) * scene.extent
    d = rng.normal(size=(5000, 3))
    none = TriangleAlpha(np.full(len(scene.triangles), -1), np.zeros((len(scene.triangles), 3, 2)), [], [])
    plain = Tracer(scene.triangles, face_normals=scene.face_normals)
    opaque = Tracer(scene.triangles, face_normals=scene.face_normals, alpha=none)
    assert opaque.alpha is None and opaque._masked is None
    a, b = plain.intersect(o, d), opaque.intersect(o, d)
    for x, y in zip((a.distance, a.primitive, a.barycentric), (b.distance, b.primitive, b.barycentric)):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(plain.occluded(o, d, 0.3), opaque.occluded(o, d, 0.3))
    assert scene.triangle_alpha is None


def test_threads_give_identical_results_with_alpha():
    alpha, _ = _scenes(_disc())
    rng = np.random.default_rng(2)
    o = np.column_stack([rng.uniform(-0.6, 0.6, 70000), np.full(70000, 0.01), rng.uniform(-0.6, 0.6, 70000)])
    d = rng.normal(size=(70000, 3))
    d[:, 1] = np.abs(d[:, 1])
    a, b = alpha.tracer.intersect(o, d, threads=1), alpha.tracer.intersect(o, d, threads=2)
    np.testing.assert_array_equal(a.distance, b.distance)
    np.testing.assert_array_equal(a.primitive, b.primitive)
    np.testing.assert_array_equal(alpha.tracer.occluded(o, d, threads=1), alpha.tracer.occluded(o, d, threads=2))


# -- the G-buffer --------------------------------------------------------------------------
@pytest.mark.parametrize("texture", list(TEXTURES))
@pytest.mark.parametrize("side", ["above", "below"])
def test_gbuffer_matches_real_holes(texture, side):
    """Pixel for pixel, except where the primary ray passes within EDGE_UV of a texel edge."""
    tex = TEXTURES[texture]()
    alpha, holes = _scenes(tex)
    if side == "above":
        cam = vo.Camera.look_at((0, ROOF_Y - 0.05, 0), (0, 0, 0), up=(0, 0, -1), size=(97, 89), ortho_height=1.3)
    else:
        cam = vo.Camera.look_at((0, 0.05, 0), (0, 1, 0), up=(0, 0, 1), size=(97, 89), ortho_height=1.3)
    a, b = vo.render_gbuffer(alpha, cam), vo.render_gbuffer(holes, cam)
    origins, _ = cam.primary_rays()
    uv = np.stack([origins[..., 0] + 0.5, origins[..., 2] + 0.5], axis=-1)
    h, w = tex.shape
    on_card = np.all((uv > -EDGE_UV) & (uv < 1 + EDGE_UV), axis=-1)
    near_edge = np.minimum(np.abs(uv[..., 0] * w - np.round(uv[..., 0] * w)) / w,
                           np.abs(uv[..., 1] * h - np.round(uv[..., 1] * h)) / h) < EDGE_UV
    ok = ~(on_card & near_edge)
    assert ok.mean() > 0.9
    np.testing.assert_array_equal(a.valid[ok], b.valid[ok])
    np.testing.assert_allclose(a.depth[ok], b.depth[ok], atol=DEPTH_ATOL)
    np.testing.assert_array_equal(a.normal[ok], b.normal[ok])
    # both depths occur: the card where it is solid, what lies behind it in the holes
    card_depth = abs(ROOF_Y - 0.05 - CARD_Y) if side == "above" else abs(CARD_Y - 0.05)
    seen = np.isclose(a.depth[ok & on_card], card_depth, atol=DEPTH_ATOL)
    assert 0.05 < seen.mean() < 0.95


# -- the ray-cast references ---------------------------------------------------------------
#: Independent randomizations per estimate: the t-test below has GROUPS - 1 degrees of freedom.
GROUPS = 32
REFERENCES = {
    "ao": lambda s, p, n, seed: vo.ambient_occlusion(s, p, n, rays=512, max_distance=0.5, seed=seed,
                                                     groups=GROUPS),
    "sky": lambda s, p, n, seed: vo.ambient_occlusion(s, p, n, rays=512, seed=seed, groups=GROUPS),
    "ao_bounces": lambda s, p, n, seed: vo.ambient_occlusion(s, p, n, rays=512, bounces=2, albedo=0.6,
                                                             seed=seed, groups=GROUPS),
    "obscurance": lambda s, p, n, seed: vo.obscurance(s, p, n, radius=0.5, rays=512, seed=seed,
                                                      groups=GROUPS),
    # the half-ball on the normal's side: the part of the ball the card cuts through
    "volumetric": lambda s, p, n, seed: vo.volumetric_obscurance(s, p, n, radius=0.45, samples=4096,
                                                                 normal_clamp=True, allow_open=True, seed=seed,
                                                                 groups=GROUPS),
}


def _points():
    """Floor points under the open half of the card (rays up through it to the sky) and roof
    points over the other half (rays down through it to the floor)."""
    rng = np.random.default_rng(7)
    x, z = rng.uniform(0.0, 0.55, 16), rng.uniform(-0.55, 0.55, 16)
    floor = np.column_stack([x, np.zeros(16), z])
    roof = np.column_stack([-x, np.full(16, ROOF_Y), z])
    normals = np.concatenate([np.tile([0.0, 1.0, 0.0], (16, 1)), np.tile([0.0, -1.0, 0.0], (16, 1))])
    return np.concatenate([floor, roof]), normals


def _max_t(a, b):
    """Largest |a - b| / sqrt(se_a^2 + se_b^2); entries with both errors 0 must be equal."""
    se = np.hypot(a.stderr, b.stderr)
    exact = se == 0
    np.testing.assert_array_equal(a.value[exact], b.value[exact])
    return float(np.max(np.abs(a.value - b.value)[~exact] / se[~exact]))


@pytest.mark.parametrize("texture", list(TEXTURES))
@pytest.mark.parametrize("quantity", list(REFERENCES))
def test_references_match_real_holes(texture, quantity):
    """The alpha-tested card and its solid texels cut as geometry give the same reference
    within the Monte Carlo error (independent seeds; t-test on the reported standard errors,
    Bonferroni over the points); the same test tells the card without holes apart."""
    tex = TEXTURES[texture]()
    alpha, holes = _scenes(tex)
    points, normals = _points()
    run = REFERENCES[quantity]
    a, b = run(alpha, points, normals, 1), run(holes, points, normals, 2)
    limit = t_threshold(GROUPS - 1, tests=2 * len(points))
    assert _max_t(a, b) < limit
    # power: the card with every texel solid differs visibly from the one with holes
    solid, _ = _scenes(np.ones_like(tex))
    assert _max_t(run(solid, points, normals, 3), b) > limit


# -- loading -------------------------------------------------------------------------------
_OBJ = """mtllib scene.mtl
v -2 0 -2
v 2 0 -2
v 2 0 2
v -2 0 2
v -0.5 0.3 -0.5
v 0.5 0.3 -0.5
v 0.5 0.3 0.5
v -0.5 0.3 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
o room
usemtl stone
f 1 3 2
f 1 4 3
usemtl leaf
f 5/1 7/3 6/2
f 5/1 6/2 6/2
f 5/1 8/4 7/3
"""


def _rays_up(count=4000, seed=5):
    rng = np.random.default_rng(seed)
    o = np.column_stack([rng.uniform(-0.5, 0.5, count), np.full(count, 0.01), rng.uniform(-0.5, 0.5, count)])
    return o, np.tile([0.0, 1.0, 0.0], (count, 1))


def _texel_of(o, grid):
    """The texel of a (h, w) grid on the unit card that each vertical ray crosses."""
    h, w = grid.shape
    col = np.floor((o[:, 0] + 0.5) * w).astype(int)
    row = h - 1 - np.floor((o[:, 2] + 0.5) * h).astype(int)
    return grid[row, col]


def _write_obj(folder, leaf_statements, *, obj=_OBJ):
    (folder / "scene.mtl").write_text("newmtl stone\nKd 0.5 0.5 0.5\nd 1.0\n\nnewmtl leaf\nKd 0.1 0.6 0.1\n"
                                      + leaf_statements)
    path = folder / "scene.obj"
    path.write_text(obj)
    return path


def _png(path, values, mode):
    from PIL import Image

    Image.fromarray(values, mode).save(path)


@pytest.mark.parametrize("kind", ["map_d grey", "map_d rgba", "map_Kd alpha", "map_d -imfchan r"])
def test_load_obj_alpha_texture(tmp_path, kind):
    """An OBJ + MTL + PNG written here: the card's holes are the texels below 0.5, read from
    the grey map_d, the alpha channel of an RGBA map_d, the alpha of map_Kd, or the channel
    -imfchan names; the card's faces (one degenerate, dropped) keep their corner texture
    coordinates."""
    alpha = np.random.default_rng(20).random((8, 8))
    grey = (alpha * 255).astype(np.uint8)
    rgba = np.zeros((8, 8, 4), np.uint8)
    rgba[..., 1], rgba[..., 3] = 180, grey
    if kind == "map_d grey":
        _png(tmp_path / "mask.png", grey, "L")
        path = _write_obj(tmp_path, "map_d mask.png\n")
    elif kind == "map_d rgba":
        _png(tmp_path / "leaf.png", rgba, "RGBA")
        path = _write_obj(tmp_path, "map_Kd leaf.png\nmap_d leaf.png\n")
    elif kind == "map_Kd alpha":
        _png(tmp_path / "leaf.png", rgba, "RGBA")
        path = _write_obj(tmp_path, "map_Kd leaf.png\n")
    else:   # the red channel is the mask; the luminance would not be
        rgb = np.stack([grey, 255 - grey, 255 - grey], axis=-1)
        _png(tmp_path / "mask.png", rgb, "RGB")
        path = _write_obj(tmp_path, "map_d -imfchan r mask.png\n")
    with pytest.warns(vo.scenes.DegenerateFacesWarning):
        if kind == "map_Kd alpha":
            with pytest.warns(vo.scenes.AlphaWarning, match=r"scene\.obj, material 'leaf'.*map_Kd"):
                scene = vo.scenes.load(path)
        else:
            scene = vo.scenes.load(path)
    assert set(scene.meshes) == {"scene", "scene/leaf"} and list(scene.alpha) == ["scene/leaf"]
    assert len(scene.alpha["scene/leaf"].uv) == 2
    o, d = _rays_up()
    np.testing.assert_array_equal(scene.tracer.occluded(o, d, 1.0), _texel_of(o, grey / 255.0 >= 0.5))


def test_load_obj_dissolve_and_tr(tmp_path):
    """A constant dissolve below 0.5 makes the card a hole, above it solid (said in a
    warning); Tr alone is read as 1 - d."""
    o, d = _rays_up(500)
    for statements, blocked in [("d 0.3\n", False), ("d 0.7\n", True), ("Tr 0.8\n", False), ("Tr 0.2\n", True)]:
        path = _write_obj(tmp_path, statements)
        with pytest.warns(vo.scenes.AlphaWarning, match="material 'leaf'"), \
                pytest.warns(vo.scenes.DegenerateFacesWarning):
            scene = vo.scenes.load(path)
        hits = scene.tracer.occluded(o, d, 1.0)
        assert (hits.all() if blocked else not hits.any()), statements


def test_load_gltf_mask_and_blend(tmp_path):
    """A glTF written by trimesh with alphaMode MASK, alphaCutoff 0.3 and an RGBA base colour
    texture times baseColorFactor alpha 0.8 (trimesh exports alphaMode and alphaCutoff); glTF
    texture coordinates have v down, and the card comes back the right way up."""
    from PIL import Image

    values = np.random.default_rng(4).random((8, 8))
    rgba = np.zeros((8, 8, 4), np.uint8)
    rgba[..., 3] = np.round(values * 255).astype(np.uint8)
    card, _ = _card(np.ones((1, 1)))
    uv = np.column_stack([card.vertices[:, 0] + 0.5, card.vertices[:, 2] + 0.5])
    for mode in ("MASK", "BLEND"):
        material = trimesh.visual.material.PBRMaterial(
            name="leaf", alphaMode=mode, alphaCutoff=0.3 if mode == "MASK" else None,
            baseColorFactor=[1.0, 1.0, 1.0, 0.8], baseColorTexture=Image.fromarray(rgba, "RGBA"))
        card.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
        floor = trimesh.Trimesh(*_quad(-2, 2, -2, 2, 0.0), process=False)
        path = tmp_path / f"{mode}.glb"
        trimesh.Scene({"floor": floor, "card": card}).export(path)
        if mode == "MASK":
            scene = vo.scenes.load(path)
            cutoff = 0.3
        else:
            with pytest.warns(vo.scenes.AlphaWarning, match="BLEND is read as a mask at 0.5"):
                scene = vo.scenes.load(path)
            cutoff = 0.5
        (key,) = scene.alpha
        o, d = _rays_up()
        alpha = rgba[..., 3] / 255.0 * np.float32(0.8)
        # away from the cutoff by more than the float32 rounding of alpha x factor
        clear = np.abs(_texel_of(o, alpha) - cutoff) > 1e-6
        np.testing.assert_array_equal(scene.tracer.occluded(o, d, 1.0)[clear], _texel_of(o, alpha >= cutoff)[clear])


def test_load_alpha_false(tmp_path):
    _png(tmp_path / "mask.png", np.zeros((4, 4), np.uint8), "L")
    path = _write_obj(tmp_path, "map_d mask.png\n")
    with pytest.warns(vo.scenes.AlphaWarning, match="alpha=False"), pytest.warns(vo.scenes.DegenerateFacesWarning):
        scene = vo.scenes.load(path, alpha=False)
    assert scene.alpha == {} and list(scene.meshes) == ["scene"]
    o, d = _rays_up(200)
    assert scene.tracer.occluded(o, d, 1.0).all()
    with pytest.raises(ValueError, match="alpha must be True or False"):
        vo.scenes.load(path, alpha="yes")


@pytest.mark.parametrize("case", ["missing file", "unreadable", "no uv", "transform option"])
def test_load_bad_material_names_file_material_mesh(tmp_path, case):
    """What cannot be honoured is named (file, material, mesh) and loaded solid."""
    obj = _OBJ
    if case == "missing file":
        statements, match = "map_d nowhere.png\n", "not found"
    elif case == "unreadable":
        (tmp_path / "broken.png").write_bytes(b"not an image at all")
        statements, match = "map_d broken.png\n", "cannot be read"
    elif case == "no uv":
        _png(tmp_path / "mask.png", np.zeros((4, 4), np.uint8), "L")
        statements, match = "map_d mask.png\n", "no texture coordinates|without texture coordinates"
        obj = _OBJ.replace("5/1 7/3 6/2", "5 7 6").replace("5/1 8/4 7/3", "5 8 7").replace("5/1 6/2 6/2", "5 6 6")
    else:
        _png(tmp_path / "mask.png", np.zeros((4, 4), np.uint8), "L")
        statements, match = "map_d -o 0.5 0 mask.png\n", "-o 0.5 0"
    path = _write_obj(tmp_path, statements, obj=obj)
    with pytest.warns(vo.scenes.AlphaWarning, match=rf"scene\.obj, material 'leaf' \(mesh 'scene'\): .*({match})"), \
            pytest.warns(vo.scenes.DegenerateFacesWarning):
        scene = vo.scenes.load(path)
    assert scene.alpha == {}
    o, d = _rays_up(200)
    assert scene.tracer.occluded(o, d, 1.0).all()


def _masked_card_gltf():
    """The files of a .gltf export of one card with an alpha-masked base colour texture (as
    trimesh writes them) and its parsed JSON header, for a test to alter."""
    import json

    from PIL import Image

    card, _ = _card(np.ones((1, 1)))
    uv = np.column_stack([card.vertices[:, 0] + 0.5, card.vertices[:, 2] + 0.5])
    material = trimesh.visual.material.PBRMaterial(
        name="leaf", alphaMode="MASK", baseColorTexture=Image.fromarray(np.zeros((4, 4, 4), np.uint8), "RGBA"))
    card.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    files = trimesh.Scene({"card": card}).export(file_type="gltf")
    return files, json.loads(files["model.gltf"])


def test_load_gltf_texcoord_1_is_named(tmp_path):
    """A base colour texture read through TEXCOORD_1 cannot be honoured: named, solid."""
    import json

    files, header = _masked_card_gltf()
    header["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1
    files["model.gltf"] = json.dumps(header).encode()
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    with pytest.warns(vo.scenes.AlphaWarning, match=r"model\.gltf, material 'leaf' \(mesh 'model'\): .*coordinate set 1"):
        scene = vo.scenes.load(tmp_path / "model.gltf")
    assert scene.alpha == {}


def test_docs_example_runs(capsys):
    """The example of docs/alpha.md runs as written and prints what the page says."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "alpha.md").read_text()
    code = re.findall(r"```python\n(.*?)```", page, flags=re.S)
    printed = re.findall(r"```text\n(.*?)```", page, flags=re.S)
    assert len(code) == 1 and len(printed) == 1, "docs/alpha.md lost its example"
    exec(compile(code[0], "docs/alpha.md", "exec"), {})
    assert capsys.readouterr().out == printed[0]


def test_cache_digest_tells_alpha_apart():
    """A cached reference of the scene with holes is never reused for the same triangles
    without them (or with another texture or cutoff)."""
    from vobscure.experiments.cache import scene_digest

    card, mask = _card(_checker())
    plain = vo.Scene({"card": card})
    digests = {scene_digest(plain), scene_digest(vo.Scene({"card": card}, alpha={"card": mask})),
               scene_digest(vo.Scene({"card": card}, alpha={"card": _card(_checker(), cutoff=0.7)[1]})),
               scene_digest(vo.Scene({"card": card}, alpha={"card": _card(_disc())[1]}))}
    assert len(digests) == 4
    assert scene_digest(vo.Scene({"card": card}, alpha={"card": mask})) == scene_digest(
        vo.Scene({"card": card}, alpha={"card": _card(_checker())[1]}))


def test_missing_material_library_is_named(tmp_path):
    path = tmp_path / "scene.obj"
    path.write_text(_OBJ)
    with pytest.warns(vo.scenes.AlphaWarning, match=r"scene\.obj: its material library 'scene\.mtl' is not found"), \
            pytest.warns(vo.scenes.DegenerateFacesWarning):
        scene = vo.scenes.load(path)
    assert scene.alpha == {}


def test_load_gltf_missing_texture_is_named(tmp_path):
    """A .gltf whose base colour image file is missing: named, loaded solid."""
    import json

    files, header = _masked_card_gltf()
    header["images"] = [{"uri": "leaf_missing.png"}]
    files["model.gltf"] = json.dumps(header).encode()
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    with pytest.warns(vo.scenes.AlphaWarning, match=r"model\.gltf, material 'leaf' \(mesh 'model'\): .*could not be read"):
        scene = vo.scenes.load(tmp_path / "model.gltf")
    assert scene.alpha == {}


def test_holes_open_a_closed_mesh():
    """A closed box whose alpha test has holes has no inside: it is open for the references."""
    box = trimesh.creation.box()
    uv = np.zeros((len(box.faces), 3, 2))
    with_holes = vo.Scene({"box": box}, alpha={"box": AlphaMask(uv, [[0.0, 1.0]])})
    without = vo.Scene({"box": box}, alpha={"box": AlphaMask(uv, [[0.6, 1.0]])})
    assert with_holes.open_meshes == ["box"] and not with_holes.is_watertight
    assert without.open_meshes == [] and without.is_watertight
    with pytest.raises(ValueError, match="closed"):
        vo.volumetric_obscurance(with_holes, [[0, 0.5, 0]], radius=0.1, samples=16)


def test_cutoff_compared_in_float64_everywhere():
    """A float32 alpha just below a float64 cutoff that rounds down to it in float32 is a hole
    for the tracer, for AlphaMask.solid and for the scene's hole count alike."""
    cutoff = float(np.float32(0.1)) + 1e-10    # rounds to float32(0.1) (spacing 7e-9 there)
    texel = np.float32(0.1)
    assert np.float32(cutoff) <= texel and float(texel) < cutoff
    card, mask = _card(np.full((2, 2), texel), cutoff=cutoff)
    scene = vo.Scene({"card": card}, alpha={"card": mask})
    assert mask.has_holes and not mask.solid([[0.5, 0.5]])[0]
    assert not scene.tracer.occluded([[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])[0]
    # and a mask without holes is traced as an opaque mesh, with no alpha pass at all
    solid = vo.Scene({"card": card}, alpha={"card": _card(np.full((2, 2), texel), cutoff=0.05)[1]})
    assert solid.triangle_alpha is None and solid.tracer.occluded([[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])[0]
