"""The thin-occluder scene: closed parts, dimensions, the default view and ray-cast sanity."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.scenes import thin as T

PARTS = ["chair", "floor", "railing", "sheet", "stand", "table", "wall"]
#: The default view covers at least this fraction of the image (the wall and floor fill it).
MIN_COVERAGE = 0.95
#: Every part is seen by at least this many pixels of a 320 x 240 render.
MIN_PART_PIXELS = 100


@pytest.fixture(scope="module")
def scene():
    return vo.scenes.thin_occluders()


@pytest.fixture(scope="module")
def view(scene):
    return vo.render_gbuffer(scene, scene.camera((320, 240)))


def _mesh_of_pixel(scene, gb):
    """(H, W) index into ``list(scene.meshes)`` of the mesh each pixel sees, -1 on background."""
    ends = np.cumsum([len(m.faces) for m in scene.meshes.values()])
    return np.where(gb.valid, np.searchsorted(ends, gb.primitive, side="right"), -1)


def test_registered_closed_and_in_metres(scene):
    assert "thin_occluders" in vo.scenes.names()
    assert vo.scenes.get("thin_occluders").name == "thin_occluders"
    assert sorted(scene.meshes) == PARTS
    assert scene.open_meshes == [] and scene.is_watertight
    for name, mesh in scene.meshes.items():
        assert mesh.is_winding_consistent and mesh.volume > 0, name
    assert scene.metadata["units"] == "m"


def test_parts_do_not_overlap_in_volume(scene):
    # every part is a union of axis-aligned boxes (each a closed component): no two boxes of
    # the whole scene may share a volume, though they may touch along faces
    boxes = [c.bounds for m in scene.meshes.values() for c in m.split(only_watertight=True)]
    assert len(boxes) == sum(len(m.faces) for m in scene.meshes.values()) // 12
    for c in (c for m in scene.meshes.values() for c in m.split(only_watertight=True)):
        assert c.volume == pytest.approx(np.prod(np.ptp(c.vertices, axis=0)), rel=1e-12)  # a box
    b = np.array(boxes)
    lo = np.maximum(b[:, None, 0], b[None, :, 0])
    hi = np.minimum(b[:, None, 1], b[None, :, 1])
    overlap = np.prod(np.clip(hi - lo, 0.0, None), axis=-1)
    np.fill_diagonal(overlap, 0.0)
    assert overlap.max() == 0.0


def test_extents_and_thin_dimensions(scene):
    lo, hi = scene.bounds
    np.testing.assert_allclose(lo, [-T.FLOOR_HALF_X, -T.SLAB, T.WALL_Z - T.SLAB])
    np.testing.assert_allclose(hi, [T.FLOOR_HALF_X, T.WALL_HEIGHT, T.FLOOR_FRONT_Z])
    sheet = scene.meshes["sheet"].bounds
    assert sheet[1, 2] - sheet[0, 2] == pytest.approx(T.SHEET_THICKNESS, abs=1e-12)
    # everything but the floor stands on it: the lowest point of each part is y = 0
    for name in ("wall", "table", "chair", "railing", "stand"):
        assert scene.meshes[name].bounds[0, 1] == 0.0, name
    # the sheet hangs: it touches the stand's bar from below and nothing else
    assert sheet[0, 1] > 0.3
    # the table top at 0.75 m, the railing's bars 1.2 cm across
    assert scene.meshes["table"].bounds[1, 1] == pytest.approx(0.75)
    widths = [np.ptp(m.vertices[:, 0]) for m in scene.meshes["railing"].split(only_watertight=True)]
    assert min(widths) == pytest.approx(T.RAIL_BAR)


def test_default_view_covers_the_image_and_sees_every_part(scene, view):
    assert view.valid.mean() >= MIN_COVERAGE
    seen = _mesh_of_pixel(scene, view)
    counts = {name: int(np.sum(seen == k)) for k, name in enumerate(scene.meshes)}
    assert all(c >= MIN_PART_PIXELS for c in counts.values()), counts


def test_default_radius_is_half_a_metre(scene, view):
    from vobscure.experiments.common import choose_radius

    choice = choose_radius(scene, view)
    assert choice.rule == "metres" and choice.radius == 0.5


def test_ray_cast_sanity(scene):
    # a ray down onto the floor in the open hits y = 0 at distance 2; one toward the wall
    # through the sheet hits its 1 cm thick front face first
    hits = scene.tracer.intersect(np.array([[1.0, 2.0, 1.5], [-1.2, 1.0, 3.0]], np.float32),
                                  np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0]], np.float32))
    assert hits.distance[0] == pytest.approx(2.0, rel=1e-6)
    sheet_front = scene.meshes["sheet"].bounds[1, 2]
    assert hits.distance[1] == pytest.approx(3.0 - sheet_front, rel=1e-6)


def test_thin_parts_give_a_thin_feature_band(scene, view):
    band = vo.metrics.thin_feature_mask(view, radius=0.5)
    seen = _mesh_of_pixel(scene, view)
    names = list(scene.meshes)
    # the band lies on the floor and the wall behind the thin parts, never on a thin part in front
    behind = np.isin(seen[band], [names.index("floor"), names.index("wall")])
    assert behind.mean() > 0.95
    # and behind every thin part: each has band pixels within its own silhouette's reach
    from scipy.ndimage import binary_dilation

    for part in scene.metadata["thin_parts"]:
        near_part = binary_dilation(seen == names.index(part), iterations=3)
        assert np.any(band & near_part), part
    assert 0.05 < band.mean() < 0.6


def test_picture_script_runs(tmp_path):
    """docs/scenes_pictures.py's make_thin (the picture of docs/scenes.md) in its quick mode."""
    import importlib.util
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "scenes_pictures.py"
    spec = importlib.util.spec_from_file_location("scenes_pictures", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    written = module.make_thin(tmp_path, quick=True)
    assert [p.name for p in written] == ["thin_occluders.png", "thin_occluders.json"]
    record = json.loads(written[1].read_text())
    assert record["coverage"] >= MIN_COVERAGE and record["radius"] == 0.5
