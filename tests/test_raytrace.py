"""The Embree layer: queries, barycentrics, and the self-intersection offset across scales."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.raytrace import OFFSET_RELATIVE, Tracer
from vobscure.sampling import square_to_cosine_hemisphere, square_to_uniform_hemisphere, to_world

SCALES = [1e-3, 1e-1, 1.0, 1e2, 1e4]


def _rotation(axis, angle_deg):
    return trimesh.transformations.rotation_matrix(np.radians(angle_deg), axis)


def _plate(scale, tilt_deg, shift):
    """A closed, finely triangulated slab (top face y = 0 before the transform)."""
    box = trimesh.creation.box(extents=(4.0, 1.0, 4.0))
    box.apply_translation((0, -0.5, 0))
    box = box.subdivide().subdivide().subdivide()  # many coplanar triangles and shared edges
    box.apply_transform(_rotation((1, 0, 1), tilt_deg))
    box.apply_scale(scale)
    box.apply_translation(np.asarray(shift) * scale)
    return box


def _top_samples(mesh, normal, count, rng):
    """Random points on the triangles whose normal is ``normal``, some on edges and corners."""
    faces = np.flatnonzero(mesh.face_normals @ normal > 1 - 1e-9)
    tri = mesh.triangles[rng.choice(faces, count)]
    u = rng.random((count, 2))
    flip = u.sum(axis=1) > 1
    u[flip] = 1 - u[flip]
    # a quarter of the points exactly on an edge, a tenth exactly on a vertex
    u[: count // 4, 1] = 0.0
    u[: count // 10] = 0.0
    return tri[:, 0] + u[:, :1] * (tri[:, 1] - tri[:, 0]) + u[:, 1:] * (tri[:, 2] - tri[:, 0])


@pytest.mark.parametrize("scale", SCALES)
@pytest.mark.parametrize("tilt", [0.0, 27.0])
@pytest.mark.parametrize("shift", [(0, 0, 0), (30, -20, 10)])
def test_no_false_self_hits(scale, tilt, shift):
    """Rays leaving a convex solid can never hit it: every hit would be a self-intersection."""
    mesh = _plate(scale, tilt, shift)
    tracer = vo.Scene(mesh, smooth_angle=0).tracer
    normal = _rotation((1, 0, 1), tilt)[:3, :3] @ np.array([0.0, 1.0, 0.0])
    rng = np.random.default_rng(0)
    pts = _top_samples(mesh, normal, 400, rng)
    n = np.tile(normal, (len(pts), 1))
    u = rng.random((len(pts), 64, 2))
    u[:, :8, 0] = 1.0 - 1e-7  # grazing: cosine-warp u0 -> 1 is theta -> 90 degrees
    for warp in (square_to_cosine_hemisphere, square_to_uniform_hemisphere):
        d = to_world(warp(u), n).reshape(-1, 3)
        o = np.repeat(tracer.offset_origins(pts, n), 64, axis=0)
        blocked = tracer.occluded(o, d)
        assert blocked.sum() == 0, f"{blocked.sum()} false self-hits at scale {scale}"
    assert tracer.offset == pytest.approx(OFFSET_RELATIVE * tracer.scale)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e4])
def test_offset_keeps_real_occluders_in_narrow_groove(scale):
    """A ceiling about 1e-3 of the extent above the floor must block every upward ray."""
    floor = trimesh.creation.box(extents=(4.0, 1.0, 4.0))
    floor.apply_translation((0, -0.5, 0))
    gap = 0.01  # the scene's extent is about 11.4
    ceiling = trimesh.creation.box(extents=(8.0, 0.5, 8.0))
    ceiling.apply_translation((0, gap + 0.25, 0))
    scene = vo.Scene({"floor": floor, "ceiling": ceiling}, smooth_angle=0).scaled(scale)
    tracer = scene.tracer
    assert gap * scale / scene.extent < 1e-3
    assert tracer.offset < 0.05 * gap * scale
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(-1.5, 1.5, 300), np.zeros(300), rng.uniform(-1.5, 1.5, 300)]) * scale
    n = np.tile([0.0, 1.0, 0.0], (300, 1))
    u = rng.random((300, 32, 2)) * [0.99, 1.0]  # up to ~84 degrees: reaches the big ceiling
    d = to_world(square_to_cosine_hemisphere(u), n).reshape(-1, 3)
    o = np.repeat(tracer.offset_origins(pts, n), 32, axis=0)
    assert tracer.occluded(o, d).all()
    hits = tracer.intersect(o, d)
    assert hits.hit.all()
    # every hit is on the ceiling's underside, at height gap
    np.testing.assert_allclose(tracer.hit_points(hits)[:, 1], gap * scale, rtol=1e-5)


def test_max_distance_per_ray():
    tri = np.array([[[-1, 0, -1], [1, 0, -1], [0, 0, 1]]], float)
    tracer = Tracer(tri, threads=1)
    o = np.array([[0, 1, 0]] * 3, float)
    d = np.array([[0, -1, 0]] * 3, float)
    assert tracer.occluded(o, d, [0.5, 1.5, np.inf]).tolist() == [False, True, True]
    hits = tracer.intersect(o, d, [0.5, 1.5, np.inf])
    assert hits.hit.tolist() == [False, True, True]
    assert np.isinf(hits.distance[0]) and hits.primitive[0] == -1
    with pytest.raises(ValueError, match="max_distance"):
        tracer.occluded(o, d, [1.0, 2.0])
    with pytest.raises(ValueError, match="max_distance"):
        tracer.occluded(o, d, -1.0)


def test_barycentric_hit_points_and_primitives():
    rng = np.random.default_rng(2)
    mesh = trimesh.creation.icosphere(subdivisions=3)
    tracer = vo.Scene(mesh).tracer
    d = rng.normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hits = tracer.intersect(np.zeros((500, 3)), d)
    assert hits.hit.all()
    p = tracer.hit_points(hits)
    # the rebuilt point lies on the reported triangle's plane and along the ray
    tri = tracer.triangles[hits.primitive]
    plane = np.einsum("ij,ij->i", p - tri[:, 0], tracer.face_normals[hits.primitive])
    np.testing.assert_allclose(plane, 0.0, atol=1e-12)
    np.testing.assert_allclose(p, d * hits.distance[:, None], atol=1e-6)


def test_threads_give_identical_results():
    mesh = trimesh.creation.icosphere(subdivisions=3)
    tracer = vo.Scene(mesh).tracer
    rng = np.random.default_rng(3)
    o = rng.uniform(-2, 2, (100_000, 3))
    d = rng.normal(size=(100_000, 3))
    a = tracer.occluded(o, d, 1.0, threads=1)
    b = tracer.occluded(o, d, 1.0, threads=2)
    np.testing.assert_array_equal(a, b)
    assert 0 < a.mean() < 1


def test_bad_tracer_inputs():
    with pytest.raises(ValueError, match="triangles"):
        Tracer(np.zeros((0, 3, 3)))
    with pytest.raises(ValueError, match="triangles"):
        Tracer(np.zeros((2, 3)))
    tracer = Tracer(np.array([[[-1, 0, -1], [1, 0, -1], [0, 0, 1]]], float))
    with pytest.raises(ValueError, match="origins and directions"):
        tracer.occluded(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="threads"):
        tracer.occluded(np.zeros((2, 3)), np.ones((2, 3)), threads=0)
