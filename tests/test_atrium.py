"""Tests of vobscure.scenes.atrium: the procedural interior in metres.

The expected dimensions are worked out by hand from the defaults (courtyard 20 x 12 m,
8 x 5 bays, storeys of 4 m, walks 3 m deep) and the part sizes of the module, and measured
with rays or from the meshes' own vertices, not from the builder's intermediate values.
The alpha test of the leaf cards is not honoured here (the tracer sees the cards as solid);
only the texture and its mapping are tested.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.scenes import AlphaMask, atrium, get, names
from vobscure.scenes.atrium import LEAF_CUTOFF, leaf_texture

#: Coordinates built by adding and multiplying a few decimal numbers in float64.
COORD_ATOL = 1e-9
#: Distances measured by Embree, which traces in float32 (relative rounding about 6e-8 of
#: coordinates up to 14 m, plus the hit rebuilt on the triangle): 1e-5 m is ample.
RAY_ATOL = 1e-5
#: Coverage the default view must reach at 64 x 36 (the issue's bar: "most of the image").
MIN_COVERAGE = 0.8
#: Ratio of the 95th to the 5th percentile of the covered pixels' depths: a view with many
#: depths (near columns and far walls), not one wall.
MIN_DEPTH_RATIO = 5.0
#: Hand-computed heights of the defaults (metres): arches of radius (2.5 - 0.6) / 2 = 0.95
#: reach CROWN_CLEARANCE = 0.3 below a slab 0.3 thick under the next floor at 4 m, so they
#: spring at 4 - 0.3 - 0.3 - 0.95 = 2.45 m: the height of a ground column with its capital.
SPRING = 2.45
CROWN = 3.4
#: Half thickness of the arcade wall, 0.25 m: the courtyard's clear width between the arch
#: faces at 3.5 m height is W - 0.5.
ARCH_HALF = 0.25


@pytest.fixture(scope="module")
def scene():
    return atrium()


def _hits(scene, origins, directions):
    tracer = scene.tracer
    hits = tracer.intersect(np.asarray(origins, float), np.asarray(directions, float))
    return hits, scene.mesh_index[np.maximum(hits.primitive, 0)]


# --------------------------------------------------------------------------------------
# closed and open meshes
# --------------------------------------------------------------------------------------

def test_structural_meshes_are_closed_outward_solids(scene):
    structural = scene.metadata["structural_meshes"]
    assert set(structural) | set(scene.metadata["open_meshes"]) == set(scene.meshes)
    for name in structural:
        mesh = scene.meshes[name]
        assert mesh.is_watertight and mesh.is_winding_consistent, name
        # every part (a box, a shaft, a link, an arcade wall) encloses a positive volume:
        # outward normals, part by part
        volumes = np.array([part.volume for part in mesh.split(only_watertight=False)])
        assert np.all(volumes > 0), (name, volumes.min())
    for name in scene.metadata["open_meshes"]:
        assert not scene.meshes[name].is_watertight, name
    assert not scene.is_watertight


def test_parts_per_mesh(scene):
    """Counted by hand: 26 columns per storey (9 on each long line, 4 more on each short
    one), 3 parts each; one arcade wall per side and storey; 8 slab strips; a parapet and
    its coping per upper bay (26 bays); chains and lanterns in every second bay of the long
    sides' ground floor (4 per side), 20 links of pitch 49 mm each to make a 1 m chain;
    a pot per even bay of the long sides (8)."""
    parts = {name: len(m.split(only_watertight=False)) for name, m in scene.meshes.items()}
    assert parts == {"floor": 1, "walls": 4, "slabs": 8, "columns": 2 * 26 * 3, "arches": 8,
                     "parapets": 2 * 26, "pots": 8, "lanterns": 8, "chains": 8 * 20,
                     "banners": 10, "leaves": 8 * 24}
    assert len(scene.metadata["column_centers"]) == 26


# --------------------------------------------------------------------------------------
# sizes in metres
# --------------------------------------------------------------------------------------

def test_metadata_declares_metres(scene):
    md = scene.metadata
    assert md["units"] == "m" and md["kind"] == "atrium"
    assert md["courtyard"] == (20.0, 12.0) and md["storey_height"] == 4.0
    assert md["springing_height"] == pytest.approx(SPRING, abs=COORD_ATOL)


def test_outer_bounds(scene):
    """Walls 0.5 m thick behind walks 3 m deep; the ground slab 0.3 m; walls 0.6 m above
    the roof at 8 m."""
    np.testing.assert_allclose(scene.bounds, [[-13.5, -0.3, -9.5], [13.5, 8.6, 9.5]], atol=COORD_ATOL)


def test_columns_stand_on_the_lines_at_the_bay_spacing(scene):
    centres = np.asarray(scene.metadata["column_centers"])
    on_long = np.isclose(np.abs(centres[:, 1]), 6.0)
    on_short = np.isclose(np.abs(centres[:, 0]), 10.0)
    assert np.all(on_long | on_short)
    xs = np.unique(np.round(centres[on_long, 0], 9))
    zs = np.unique(np.round(centres[on_short, 1], 9))
    np.testing.assert_allclose(np.diff(xs), 2.5, atol=COORD_ATOL)
    np.testing.assert_allclose(np.diff(zs), 2.4, atol=COORD_ATOL)
    # the parts of the columns mesh, by their own vertices: the parts of each column
    # (plinth or pedestal, shaft, capital) stack without gaps from the storey's floor to the
    # springing height, 2.45 m above it
    parts = scene.meshes["columns"].split(only_watertight=False)
    spans = {}
    for p in parts:
        key = (round(float(p.centroid[0]), 6), round(float(p.centroid[2]), 6), p.bounds[0, 1] >= 4.0)
        spans.setdefault(key, []).append((p.bounds[0, 1], p.bounds[1, 1]))
    assert len(spans) == 2 * 26
    for (x, z, upper), intervals in spans.items():
        intervals.sort()
        assert len(intervals) == 3
        base = 4.0 if upper else 0.0
        assert intervals[0][0] == pytest.approx(base, abs=COORD_ATOL)
        assert intervals[-1][1] == pytest.approx(base + SPRING, abs=COORD_ATOL)
        for (_, top), (bottom, _) in zip(intervals[:-1], intervals[1:]):
            assert bottom == pytest.approx(top, abs=COORD_ATOL)


def test_courtyard_measured_with_rays(scene):
    """From the courtyard's centre at 3.5 m (above the arches' crowns at 3.35 and 3.4 m,
    below the banners), horizontal rays meet the arcade walls' faces at L/2 - 0.25 and
    W/2 - 0.25; vertical rays meet nothing: the courtyard is open to the sky."""
    o = [[0.0, 3.5, 0.0]] * 4
    d = [[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1]]
    hits, mesh = _hits(scene, o, d)
    np.testing.assert_allclose(hits.distance, [10 - ARCH_HALF] * 2 + [6 - ARCH_HALF] * 2, atol=RAY_ATOL)
    assert {list(scene.meshes)[i] for i in mesh} == {"arches"}
    grid = np.array([(x, 0.01, z) for x in np.linspace(-9.3, 9.3, 9) for z in (-3.0, 0.0, 3.0)])
    hits, _ = _hits(scene, grid, np.tile([0.0, 1.0, 0.0], (len(grid), 1)))
    assert not hits.hit.any()


def test_storeys_measured_with_rays(scene):
    """In the south walk: up from the floor to the gallery slab's underside (4 - 0.3 m);
    down from 6 m to the gallery floor (4 m); up from there to the roof's underside
    (8 - 0.3 m). Under a ground arch's crown the intrados is at 3.4 m."""
    # 1 cm beside the crown of the third bay (x in [-5, -2.5], no chain): the intrados is
    # the chord from the crown vertex falling by tan(180 / 24 / 2 degrees) per metre
    crown_offset = 0.01
    o = [[0.0, 0.01, 7.5], [0.0, 6.0, 7.5], [0.0, 4.01, 7.5], [-3.75 + crown_offset, 0.01, 6.0]]
    d = [[0, 1, 0], [0, -1, 0], [0, 1, 0], [0, 1, 0]]
    hits, mesh = _hits(scene, o, d)
    intrados = CROWN - crown_offset * np.tan(np.radians(180.0 / 24 / 2))
    np.testing.assert_allclose(hits.distance, [3.69, 2.0, 3.69, intrados - 0.01], atol=RAY_ATOL)
    assert [list(scene.meshes)[i] for i in mesh] == ["slabs", "slabs", "slabs", "arches"]


# --------------------------------------------------------------------------------------
# the views
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("view", ["arcade", "gallery"])
def test_views_cover_the_image_with_many_depths(scene, view):
    v = scene.metadata["views"][view]
    cam = vo.Camera.look_at(v["eye"], v["target"], v["up"], size=(64, 36), fov_y=v["fov_y"])
    gb = vo.render_gbuffer(scene, cam)
    assert gb.valid.mean() >= MIN_COVERAGE
    depth = gb.depth[gb.valid]
    assert np.percentile(depth, 95) / np.percentile(depth, 5) >= MIN_DEPTH_RATIO
    # what the view is for: columns, arches, floor, banners and the plants are all in it
    seen = {list(scene.meshes)[i] for i in np.unique(scene.mesh_index[gb.primitive[gb.valid]])}
    assert {"columns", "arches", "floor", "banners", "leaves", "pots"} <= seen


def test_default_view_is_the_arcade_inside_the_walls(scene):
    assert scene.view == scene.metadata["views"]["arcade"]
    eye = np.asarray(scene.view["eye"])
    assert eye[1] == pytest.approx(1.6)
    # inside the south walk: behind the column line (z = 6), before the wall (z = 9)
    assert 6.0 < eye[2] < 9.0 and abs(eye[0]) < 13.0
    # not inside a solid: every ray from the eye meets the front of what it hits
    rng = np.random.default_rng(0)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hits, _ = _hits(scene, np.tile(eye, (len(d), 1)), d)
    assert hits.hit.mean() > 0.5
    n = scene.face_normals[hits.primitive[hits.hit]]
    solid = ~np.isin(scene.mesh_index[hits.primitive[hits.hit]],
                     [list(scene.meshes).index(m) for m in scene.metadata["open_meshes"]])
    assert np.all(np.einsum("ij,ij->i", n, d[hits.hit])[solid] < 0)


# --------------------------------------------------------------------------------------
# thin parts
# --------------------------------------------------------------------------------------

def test_chain_links_are_one_centimetre_wire_and_do_not_overlap(scene):
    """Each link's vertices lie 5 mm from its centreline (an ellipse of half axes 30 and
    18 mm); consecutive links, in perpendicular planes, interlock with their centrelines
    more than one wire diameter (10 mm) apart everywhere."""
    links = scene.meshes["chains"].split(only_watertight=False)
    links = sorted(links, key=lambda m: (round(m.centroid[2], 6), round(m.centroid[0], 6), -m.centroid[1]))
    first, second = links[0], links[1]
    width = np.ptp(first.vertices, axis=0)
    assert width[1] == pytest.approx(2 * (0.03 + 0.005))           # outer length 70 mm
    thin, wide = sorted([width[0], width[2]])
    assert wide == pytest.approx(2 * (0.018 + 0.005))             # outer width 46 mm
    # across its plane the wire is a hexagon of circumradius 5 mm: 8.7 to 10 mm thick
    assert 2 * 0.005 * np.cos(np.pi / 6) - COORD_ATOL <= thin <= 2 * 0.005 + COORD_ATOL

    def centreline(mesh):
        c = mesh.bounds.mean(axis=0)
        axis = 0 if np.ptp(mesh.vertices[:, 0]) > np.ptp(mesh.vertices[:, 2]) else 2
        u = np.linspace(0, 2 * np.pi, 720, endpoint=False)
        pts = np.tile(c, (len(u), 1))
        pts[:, axis] += 0.018 * np.cos(u)
        pts[:, 1] += 0.03 * np.sin(u)
        return pts

    a, b = centreline(first), centreline(second)
    assert np.ptp(a[:, 0]) > 0.03 and np.ptp(b[:, 2]) > 0.03   # the two planes: xy, then zy
    gaps = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    assert gaps.min() > 2 * 0.005
    # interlocked: the second link's wire at its top passes above the first link's wire at
    # its bottom (their centrelines 2 r + 1 mm apart there)
    assert b[:, 1].max() - a[:, 1].min() == pytest.approx(2 * 0.005 + 0.001)
    # the wire: every vertex at 5 mm from the nearest centreline point (up to the chord error)
    dist = np.linalg.norm(first.vertices[:, None, :] - a[None, :, :], axis=2).min(axis=1)
    np.testing.assert_allclose(dist, 0.005, atol=2e-4)  # 720 samples: chord error < 0.03 * 2pi / 720


def test_banners_are_thin_open_sheets(scene):
    for part in scene.meshes["banners"].split(only_watertight=False):
        extent = np.sort(np.ptp(part.vertices, axis=0))
        assert extent[0] <= 0.03 + COORD_ATOL      # the folds: a few cm deep
        assert extent[1:] == pytest.approx([1.2, 3.0])
        assert not part.is_watertight


# --------------------------------------------------------------------------------------
# the leaf cards and their alpha texture
# --------------------------------------------------------------------------------------

def _alpha_at(texture, u, v):
    """Texel of ``texture`` containing (u, v), row 0 at v = 1 (AlphaMask's convention)."""
    h, w = texture.shape
    return texture[min(int((1.0 - v) * h), h - 1), min(int(u * w), w - 1)]


def test_leaf_texture_has_holes():
    alpha = leaf_texture()
    assert alpha.shape == (128, 128) and alpha.dtype == np.float32
    assert alpha.min() == 0.0 and alpha.max() == 1.0
    holes = np.mean(alpha < LEAF_CUTOFF)
    # the leaf is a union of ellipses and a midrib whose areas sum to 0.386 of the card
    # (0.068 + 6 x 0.047 + 0.036), an upper bound of the solid part; the terminal leaflet
    # alone, 0.068, is a lower bound. Antialiasing moves either by about one texel's border.
    assert 1 - 0.386 - 0.03 <= holes <= 1 - 0.068
    # hand-placed points: the leaflets and the midrib are solid, the card's corners and the
    # gaps beside the terminal leaflet are holes
    for u, v in [(0.5, 0.8), (0.5, 0.1), (0.5 + 0.22, 0.27), (0.5 - 0.22, 0.67)]:
        assert _alpha_at(alpha, u, v) == 1.0, (u, v)
    for u, v in [(0.01, 0.01), (0.99, 0.99), (0.2, 0.9), (0.8, 0.9), (0.5, 0.995), (0.3, 0.05)]:
        assert _alpha_at(alpha, u, v) == 0.0, (u, v)
    # antialiased: some texels are partly covered
    assert np.any((alpha > 0) & (alpha < 1))


def test_leaf_texture_is_symmetric_and_validated():
    alpha = leaf_texture(64)
    np.testing.assert_array_equal(alpha, alpha[:, ::-1])  # the leaf is symmetric in u
    with pytest.raises(ValueError, match="size"):
        leaf_texture(4)


def test_leaf_cards_carry_the_alpha_mask(scene):
    mask = scene.alpha["leaves"]
    assert isinstance(mask, AlphaMask) and mask.cutoff == LEAF_CUTOFF
    np.testing.assert_array_equal(mask.texture, leaf_texture())
    leaves = scene.meshes["leaves"]
    assert mask.uv.shape == (len(leaves.faces), 3, 2)
    # each card is two triangles sharing a diagonal; its corners map to the unit square with
    # v = 0 at the base (the corner nearer the pot's axis) and v = 1 at the tip
    uv = mask.uv.reshape(-1, 2, 3, 2)
    np.testing.assert_array_equal(np.unique(uv.reshape(-1, 2), axis=0), [[0, 0], [0, 1], [1, 0], [1, 1]])
    tri = leaves.triangles.reshape(-1, 2, 3, 3)
    base = tri[:, 0, 0]                                  # uv (0, 0)
    tip = tri[:, 0, 2]                                   # uv (1, 1)
    assert np.all(uv[:, 0, 0] == [0, 0]) and np.all(uv[:, 0, 2] == [1, 1])
    assert np.all(tip[:, 1] > base[:, 1])                # leaves rise from their base
    assert np.all(leaves.vertices[:, 1] > 0.5)           # above the pots' rims (0.5 m)


# --------------------------------------------------------------------------------------
# determinism, level of detail, triangle counts
# --------------------------------------------------------------------------------------

def test_seed_determines_the_plants_only(scene):
    again = atrium(seed=0)
    np.testing.assert_array_equal(again.triangles, scene.triangles)
    other = atrium(seed=1)
    for name in scene.meshes:
        same = np.array_equal(other.meshes[name].vertices, scene.meshes[name].vertices)
        assert same == (name != "leaves"), name
    gen = atrium(seed=np.random.default_rng(1))
    np.testing.assert_array_equal(gen.meshes["leaves"].vertices, other.meshes["leaves"].vertices)
    assert gen.metadata["parameters"]["seed"] == "Generator" and other.metadata["parameters"]["seed"] == 1


def test_triangle_counts(scene):
    n = len(scene.triangles)
    assert 20_000 <= n <= 60_000
    assert scene.metadata["n_triangles"] == {k: len(m.faces) for k, m in scene.meshes.items()}
    # counted by hand: a column is two boxes (12 + 12) and a shaft of s sides (4 s); a link
    # is 2 x segments x 6 triangles; a pot 4 s; a card 2; a banner 2 x 6 x 12
    small = atrium(column_segments=6, link_segments=5, arch_segments=4, leaves_per_plant=3)
    counts = small.metadata["n_triangles"]
    assert counts["columns"] == 52 * (24 + 4 * 6)
    assert counts["chains"] == 160 * 2 * 5 * 6
    assert counts["pots"] == 8 * 4 * 6
    assert counts["leaves"] == 8 * 3 * 2
    assert counts["banners"] == 10 * 2 * 6 * 12
    # an arcade wall: a profile of 2 m vertices (m on the bottom polyline: the two ends and
    # arch_segments + 1 per bay) gives 2 (m - 1) triangles per cap and 4 m on the sides;
    # one wall per side and storey: four of 8 bays, four of 5
    walls = sorted(len(p.faces) for p in small.meshes["arches"].split(only_watertight=False))
    m_x, m_z = 2 + 8 * (4 + 1), 2 + 5 * (4 + 1)
    assert walls == [4 * (m_z - 1) + 4 * m_z] * 4 + [4 * (m_x - 1) + 4 * m_x] * 4
    assert len(small.triangles) < n


def test_registered_and_exported():
    assert "atrium" in names()
    assert get("atrium", leaves_per_plant=2).metadata["parameters"]["leaves_per_plant"] == 2
    assert "atrium" in vo.scenes.__all__ and vo.scenes.atrium is atrium


# --------------------------------------------------------------------------------------
# bad input
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, match", [
    ({"size": (20.0,)}, "size must be a pair"),
    ({"size": "20x12"}, "size must be a pair"),
    ({"size": (20.0, -12.0)}, "size must be a positive"),
    ({"size": (20.0, float("nan"))}, "size must be a positive"),
    ({"bays": (1, 5)}, "bays must be an integer >= 2"),
    ({"bays": (8, 2.5)}, "bays must be an integer"),
    ({"bays": (30, 5)}, r"size and bays leave bays of 0.667 m along x \(30 bays\)"),
    ({"storey_height": 3.0}, r"storey_height 3 m is too low .* need storey_height >= 3.3"),
    ({"storey_height": 0.0}, "storey_height must be a positive"),
    ({"arcade_depth": 0.5}, "arcade_depth must be at least 1 m"),
    ({"arch_segments": 1}, "arch_segments must be an integer >= 2"),
    ({"column_segments": 2}, "column_segments must be an integer >= 3"),
    ({"link_segments": 3}, "link_segments must be an integer >= 4"),
    ({"chain_length": 3.0}, "chain_length 3 m is too long"),
    ({"chain_length": -1.0}, "chain_length must be a positive"),
    ({"leaves_per_plant": 0}, "leaves_per_plant must be an integer >= 1"),
    ({"seed": -1}, "seed must be"),
])
def test_bad_arguments_name_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        atrium(**kwargs)


def test_bad_keyword_through_the_registry():
    with pytest.raises(ValueError, match="atrium"):
        get("atrium", radius=1.0)


def test_scene_is_a_trimesh_scene_of_its_meshes(scene):
    # the concatenated mesh keeps every triangle (no vertex merging across parts)
    assert isinstance(scene.mesh, trimesh.Trimesh)
    assert len(scene.mesh.faces) == len(scene.triangles)


def test_docs_pictures_script_runs(tmp_path):
    """docs/scenes_pictures.py (the pictures of docs/scenes.md) runs in its quick mode and
    records every built-in scene and both atrium views."""
    import importlib.util
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "scenes_pictures.py"
    spec = importlib.util.spec_from_file_location("scenes_pictures", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    written = module.make(tmp_path, quick=True)
    assert [p.name for p in written] == ["builtin.png", "atrium.png", "provenance.json"]
    record = json.loads((tmp_path / "provenance.json").read_text())
    assert set(record["scenes"]) == set(names()) | {"atrium/arcade", "atrium/gallery"}
    assert record["scenes"]["atrium/arcade"]["coverage"] >= MIN_COVERAGE


def test_the_leaf_cards_are_traced_with_their_holes(scene):
    """With the alpha test, rays pass the leaf cards' holes: removing material can only move a
    pixel's first hit farther, and on the leaves' pixels many do move (the texture is mostly
    holes); without it the cards are solid quads. The AO reference sees the holes too."""
    solid = vo.Scene(scene.meshes, view=scene.view, smooth_angle=scene.smooth_angle)   # no alpha
    plant = scene.meshes["leaves"].triangles[0].mean(axis=0)          # one plant, seen from 1.5 m
    cam = vo.Camera.look_at(plant + (1.2, 0.6, 0.8), plant, size=(64, 48), fov_y=50)
    gb_alpha, gb_solid = vo.render_gbuffer(scene, cam), vo.render_gbuffer(solid, cam)
    leaves = scene.mesh_index == list(scene.meshes).index("leaves")
    on_leaf = gb_solid.valid & leaves[np.where(gb_solid.valid, gb_solid.primitive, 0)]
    assert on_leaf.sum() >= 50, "the camera must see plants"
    finite = gb_solid.valid
    assert np.all(gb_alpha.depth[finite] >= gb_solid.depth[finite] * (1 - 1e-6))
    through = gb_alpha.depth[on_leaf] > gb_solid.depth[on_leaf] * (1 + 1e-6)
    assert through.mean() > 0.2, through.mean()
    assert np.all(gb_alpha.depth[~on_leaf & finite] == gb_solid.depth[~on_leaf & finite])
