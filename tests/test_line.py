"""Screen-space VO by line sampling (Loos & Sloan 2010; vobscure.screenspace.line): planes,
the closed forms of the orthographic crease, the kernel against a pixel-by-pixel version.
The properties line and point sampling share (scale invariance, float32, seeds, thickness,
extremes, arguments) are tested here for both; point sampling and the converged reference
on their own: test_point.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import GBuffer

from analytic import SLAB_VO, SLAB_VO_CLAMPED, crease_vo, crease_vo_clamped
from conftest import CREASE_RADIUS, interior

#: Flat surfaces: the depth buffer holds Embree's float32 hits, so planes are exact to ~1e-5.
PLANE_TOL = 1e-3
#: Deterministic quadrature of line sampling on the orthographic crease with 129 symmetric
#: disk samples (measured RMSE 4e-4 against the closed form; 9 samples: 1e-2).
LINE_QUADRATURE_TOL = 2e-3
#: float32 against float64, per pixel. float32's unit roundoff is u = 2**-24 = 6e-8: the
#: pixel's and the tap's depths round by u z each; over the chord 2 R z_s of a line that is
#: 2 u z / (2 R z_s) <= 1.1e-6 here (z <= 7.1, R = 0.5, z_s >= 0.77 for the 9-sample disk),
#: and the result rounds by u / 2 on output. Measured max over the valid pixels of the
#: oblique crease (commit d9d8b0b): float32 G-buffer 2.0e-7 (line), 4.6e-7 (line, quadratic,
#: clamped), 2.9e-8 (point); scaled scenes (Embree's float32 hits) 3.9e-7 (line), 0 (point).
#: 2e-6: 4x the largest; a value stored at half precision anywhere (~2e-4) fails.
FLOAT32_TOL = 2e-6
#: Two float64 evaluations of the same sums in a different order.
KERNEL_TOL = 1e-12

R_CREASE = CREASE_RADIUS


CAMERAS = {
    "persp-oblique": dict(eye=(1, 2, 1.5), fov_y=40.0),
    "persp-grazing": dict(eye=(3, 0.6, 0.4), fov_y=30.0),
    "persp-top": dict(eye=(0.01, 3, 0.0), fov_y=60.0),
    "ortho-oblique": dict(eye=(1, 2, 1.5), ortho_height=2.0),
    "ortho-grazing": dict(eye=(3, 0.8, 0.4), ortho_height=1.5),
}


@pytest.mark.parametrize("view", CAMERAS, ids=list(CAMERAS))
@pytest.mark.parametrize("radius", [0.02, 0.3])
def test_line_exact_on_planes(big_slab, view, radius):
    kw = dict(CAMERAS[view])
    cam = vo.Camera.look_at(kw.pop("eye"), (0, 0, 0), size=(64, 48), **kw)
    gb = vo.render_gbuffer(big_slab, cam)
    inside = interior(gb, radius)
    assert inside.sum() > 50
    for samples in (5, 9, 16):
        for fetch in ("nearest", "bilinear"):
            v = vo.vo_line(gb, radius=radius, samples=samples, fetch=fetch, seed=1)
            vc = vo.vo_line(gb, radius=radius, samples=samples, fetch=fetch, normal_clamp=True, seed=1)
            assert np.max(np.abs(v[inside] - SLAB_VO)) < PLANE_TOL, (samples, fetch)
            assert np.max(np.abs(vc[inside] - SLAB_VO_CLAMPED)) < PLANE_TOL, (samples, fetch)


def test_line_converges_to_closed_forms_orthographic(crease_view):
    """Orthographic: the depth buffer describes the solids exactly; line sampling is a
    deterministic quadrature over the disk and converges to the closed forms."""
    gb, floor, c = crease_view
    assert floor.sum() > 500
    rmse = {}
    for n in (9, 33, 129):
        v = vo.vo_line(gb, radius=R_CREASE, samples=n, randomize=False)
        vh = vo.vo_line(gb, radius=R_CREASE, samples=n, randomize=False, normal_clamp=True)
        rmse[n] = (np.sqrt(np.mean((v[floor] - crease_vo(c)) ** 2)),
                   np.sqrt(np.mean((vh[floor] - crease_vo_clamped(c)) ** 2)))
    assert rmse[129][0] < rmse[33][0] < rmse[9][0]
    assert rmse[129][1] < rmse[33][1] < rmse[9][1]
    assert rmse[129][0] < LINE_QUADRATURE_TOL and rmse[129][1] < LINE_QUADRATURE_TOL


def test_perspective_line_approximation_is_measured(big_slab):
    """Under perspective, line sampling reads each line's depth along an oblique line of
    sight (the paper's approximation, docs/screenspace.md): its converged value differs from
    the reference. On this scene the mean difference is smaller at the smaller radius."""
    scene = vo.scenes.sphere_on_plane(subdivisions=4)
    errs = []
    for radius in (0.4, 0.1):
        cam = vo.Camera.look_at((0, 1.6, 4.0), (0, 0.6, 0), size=(96, 72), fov_y=40)
        gb = vo.render_gbuffer(scene, cam)
        inside = interior(gb, radius)
        line = vo.vo_line(gb, radius=radius, samples=129, randomize=False)
        ref = vo.vo_reference(gb, radius=radius, samples=2048, seed=3).value
        errs.append(np.mean(np.abs(line - ref)[inside]))
    assert errs[1] < errs[0]


@pytest.fixture(scope="module")
def oblique_crease():
    """The crease seen in perspective from an oblique eye (48 x 40): floor, wall and edge."""
    scene = vo.scenes.crease()
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(48, 40), fov_y=50.0)
    return scene, cam, vo.render_gbuffer(scene, cam)


@pytest.mark.parametrize("fn, samples", [(vo.vo_line, 9), (vo.vo_point, 12)])
def test_scale_invariance(oblique_crease, fn, samples):
    """Scene, camera and radius scaled together: the same visibility at every pixel."""
    scene, cam, gb = oblique_crease
    base = fn(gb, radius=0.5, samples=samples, seed=2)
    for k in (1e-3, 1e3):
        gbk = vo.render_gbuffer(scene.scaled(k), cam.scaled(k))
        vk = fn(gbk, radius=0.5 * k, samples=samples, seed=2)
        assert np.array_equal(np.isnan(vk), np.isnan(base))
        # per pixel: Embree's float32 hits differ by ~1e-7 relative between the scales
        np.testing.assert_allclose(vk[gb.valid], base[gb.valid], rtol=0, atol=FLOAT32_TOL,
                                   err_msg=f"{fn.__name__}, scale {k}")


@pytest.mark.parametrize("fn, kwargs", [
    (vo.vo_line, dict(samples=9)),
    (vo.vo_line, dict(samples=9, falloff="quadratic", normal_clamp=True)),
    (vo.vo_point, dict(samples=12)),
    (vo.vo_point, dict(samples=12, falloff="quadratic", normal_clamp=True)),
], ids=["line", "line-quadratic-clamped", "point", "point-quadratic-clamped"])
def test_float32_agrees_with_float64(oblique_crease, fn, kwargs):
    """float32 in, float32 out, and the same values as the float64 G-buffer at every pixel
    (the accumulation is float64: only the inputs' and the output's rounding remain)."""
    _, _, gb = oblique_crease
    v64 = fn(gb, radius=0.5, seed=2, **kwargs)
    v32 = fn(gb.astype(np.float32), radius=0.5, seed=2, **kwargs)
    assert v64.dtype == np.float64 and v32.dtype == np.float32
    assert np.array_equal(np.isnan(v32), ~gb.valid)
    np.testing.assert_allclose(v32[gb.valid].astype(np.float64), v64[gb.valid], rtol=0, atol=FLOAT32_TOL)


def test_determinism_by_seed(crease_view):
    gb, floor, _ = crease_view
    for fn in (vo.vo_line, vo.vo_point):
        a = fn(gb, radius=0.5, samples=9, seed=4)
        b = fn(gb, radius=0.5, samples=9, seed=4)
        c = fn(gb, radius=0.5, samples=9, seed=5)
        assert np.array_equal(a, b, equal_nan=True)
        assert not np.array_equal(a, c, equal_nan=True)


def test_thickness(crease_view):
    gb, floor, _ = crease_view
    for fn in (vo.vo_line, vo.vo_point):
        base = fn(gb, radius=0.5, samples=9, seed=1)
        thick = fn(gb, radius=0.5, samples=9, seed=1, thickness=1.0)   # >= 2 R: no change
        np.testing.assert_allclose(thick[gb.valid], base[gb.valid], atol=1e-12)
        thin = fn(gb, radius=0.5, samples=9, seed=1, thickness=0.05)   # thin shells: more open
        assert np.all(thin[gb.valid] >= base[gb.valid] - 1e-12)
        assert np.mean(thin[gb.valid]) > np.mean(base[gb.valid])


def test_quadratic_falloff_on_planes(big_slab):
    cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(48, 40), fov_y=40)
    gb = vo.render_gbuffer(big_slab, cam)
    inside = interior(gb, 0.3)
    v = vo.vo_line(gb, radius=0.3, samples=9, falloff="quadratic")
    vc = vo.vo_line(gb, radius=0.3, samples=9, falloff="quadratic", normal_clamp=True)
    assert np.max(np.abs(v[inside] - SLAB_VO)) < PLANE_TOL
    assert np.max(np.abs(vc[inside] - SLAB_VO_CLAMPED)) < PLANE_TOL


def _silent(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            return fn(*args, **kw)


def _reference_value(gbuffer, **kw):
    return vo.vo_reference(gbuffer, **kw).value


@pytest.mark.parametrize("fn", [vo.vo_line, vo.vo_point, _reference_value])
def test_extremes(fn, crease_view):
    gb, _, _ = crease_view
    scene = vo.scenes.crease()
    kw = dict(samples=64) if fn is _reference_value else {}
    for radius in (1e-7, 1e-3, 1e3):   # below a pixel ... larger than the scene
        for clamp in (False, True):
            v = fn(gb, radius=radius, normal_clamp=clamp, **kw)
            assert np.all(np.isfinite(v[gb.valid])) and np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1))
            assert np.all(np.isnan(v[~gb.valid]))
    # grazing normals, depth discontinuities, off-screen taps: a grazing view of steps
    steps = vo.scenes.steps()
    g2 = vo.render_gbuffer(steps, vo.Camera.look_at((3.0, 0.3, 0.2), (0, 0.3, 0), size=(40, 30), fov_y=60))
    for offscreen in ("clamp", "open"):
        v = fn(g2, radius=0.4, offscreen=offscreen, **kw)
        assert np.all(np.isfinite(v[g2.valid]))
    # all background, one pixel, NaN depth
    sky = vo.render_gbuffer(scene, vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(6, 5)))
    assert np.all(np.isnan(fn(sky, radius=0.5, **kw)))
    one = vo.render_gbuffer(scene, vo.Camera.look_at((2, 2, 2), (0.5, 0, 0), size=(1, 1)))
    v1 = fn(one, radius=0.5, **kw)
    assert v1.shape == (1, 1) and np.isfinite(v1[0, 0])
    depth = np.array(gb.depth)
    depth[10:20, 10:20] = np.nan
    holed = GBuffer(gb.camera, depth=depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive, hits=gb.hits)
    vh = fn(holed, radius=0.5, **kw)
    assert np.all(np.isnan(vh[10:20, 10:20]))
    ok = gb.valid & ~np.isnan(depth)
    assert np.all(np.isfinite(vh[ok]))


def test_zero_depth_variance_plane_facing_camera():
    """An orthographic camera looking straight down at the slab: constant depth."""
    scene = vo.scenes.slab(size=50.0)
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(32, 32), ortho_height=2.0)
    gb = vo.render_gbuffer(scene, cam)
    assert np.ptp(gb.depth) == 0
    inside = interior(gb, 0.2)
    for fn in (vo.vo_line, vo.vo_point):
        assert np.max(np.abs(fn(gb, radius=0.2)[inside] - SLAB_VO)) < PLANE_TOL


def test_bad_arguments(crease_view):
    gb, _, _ = crease_view
    cases = [
        (dict(radius=0), "radius"), (dict(radius=-1), "radius"), (dict(radius=np.nan), "radius"),
        (dict(radius=1, samples=0), "samples"), (dict(radius=1, samples=2.5), "samples"),
        (dict(radius=1, fetch="cubic"), "fetch"), (dict(radius=1, offscreen="wrap"), "offscreen"),
        (dict(radius=1, falloff="cubic"), "falloff"), (dict(radius=1, thickness=0), "thickness"),
        (dict(radius=1, seed=-1), "seed"), (dict(radius=1, noise_size=0), "noise_size"),
    ]
    for fn in (vo.vo_line, vo.vo_point):
        for kw, match in cases:
            with pytest.raises(ValueError, match=match):
                fn(gb, **kw)
    with pytest.raises(ValueError, match="samples"):
        vo.vo_line(gb, radius=1, samples=vo.patterns.ball(5))
    with pytest.raises(ValueError, match="samples"):
        vo.vo_point(gb, radius=1, samples=vo.patterns.disk(5))
    with pytest.raises(ValueError, match="gbuffer"):
        vo.vo_line(np.zeros((4, 4)), radius=1)


def _line_by_hand(gb, radius, pattern, texture, offscreen, clamp):
    """vo_line written pixel by pixel and sample by sample, straight from the definitions
    (an independent implementation of the vectorized kernel; perspective and orthographic)."""
    cam = gb.camera
    H, W = gb.depth.shape
    out = np.full((H, W), np.nan)
    for i, j in zip(*np.nonzero(gb.valid)):
        z = float(gb.depth[i, j])
        r = radius * float(cam.pixels_per_unit(z))
        v = texture[i % texture.shape[0], j % texture.shape[1]]
        n = gb.normal[i, j] / np.linalg.norm(gb.normal[i, j])
        if cam.is_perspective:
            f = cam.focal_length_px
            p = np.array([(j + 0.5 - W / 2) * z / f, (H / 2 - i - 0.5) * z / f, z])
        num = den = 0.0
        for s, w in zip(pattern.points, pattern.weights):
            x, y = 2 * np.dot(s, v) * v - s                      # reflection (Sec. 4.5)
            z_s = np.sqrt(1 - x * x - y * y)
            di, dj = -np.rint(r * y), np.rint(r * x)
            ti, tj = int(i + di), int(j + dj)
            if 0 <= ti < H and 0 <= tj < W:
                d = float(gb.depth[ti, tj]) if gb.valid[ti, tj] else np.inf
            else:
                d = float(gb.depth[min(max(ti, 0), H - 1), min(max(tj, 0), W - 1)]) if offscreen == "clamp" else np.inf
                if offscreen == "clamp" and not np.isfinite(d):
                    d = np.inf
            d_r = (z / radius) * (1 - z / d) if cam.is_perspective else (d - z) / radius
            hi = z_s
            if clamp:
                xs, ys = dj / r, -di / r                        # the tapped pixel's offset
                if cam.is_perspective:
                    plane = -z * (n[0] * xs + n[1] * ys) / min(np.dot(n, p), -1e-12 * z)
                else:
                    plane = -(n[0] * xs + n[1] * ys) / min(n[2], -1e-12)
                hi = min(max(plane, -z_s), z_s)
            num += w / (2 * z_s) * (min(max(d_r, -z_s), hi) + z_s)
            den += w / (2 * z_s) * (hi + z_s)
        out[i, j] = num / den if den > 0 else 1.0
    return out


@pytest.mark.parametrize("ortho", [False, True])
def test_line_kernel_matches_a_pixel_by_pixel_implementation(ortho, monkeypatch):
    """The vectorized nearest-fetch kernel (padded fast path and clipped fallback) against a
    scalar implementation of the same definitions, with off-screen taps and background."""
    from vobscure.screenspace import _common as C
    scene = vo.scenes.steps()
    kw = dict(ortho_height=2.5) if ortho else dict(fov_y=55)
    gb = vo.render_gbuffer(scene, vo.Camera.look_at((2.5, 1.6, 2.0), (0, 0.3, 0), size=(24, 18), **kw))
    assert 0 < gb.valid.sum() < gb.valid.size
    pattern = vo.patterns.disk(7)
    texture = C.noise_texture(4, 5, 2, True)
    for offscreen in ("clamp", "open"):
        for clamp in (False, True):
            expected = _line_by_hand(gb, 0.35, pattern, texture, offscreen, clamp)
            fast = vo.vo_line(gb, radius=0.35, samples=pattern, seed=5, offscreen=offscreen, normal_clamp=clamp)
            with monkeypatch.context() as m:
                m.setattr(C, "MAX_PAD", 0)        # no padded buffer: the clipping fallback
                slow = vo.vo_line(gb, radius=0.35, samples=pattern, seed=5, offscreen=offscreen,
                                  normal_clamp=clamp)
            np.testing.assert_array_equal(np.isnan(fast), ~gb.valid)
            np.testing.assert_allclose(fast[gb.valid], expected[gb.valid], rtol=0, atol=KERNEL_TOL)
            np.testing.assert_allclose(slow[gb.valid], fast[gb.valid], rtol=0, atol=KERNEL_TOL)


@pytest.mark.parametrize("samples", [5, 9, 16])
def test_clamped_line_constant_denominator_for_antipodal_patterns(samples, monkeypatch):
    """For an exactly antipodal pattern the clamped denominator is not accumulated (the
    pairs' tangent-plane terms cancel); accumulating it anyway gives the same image."""
    from vobscure.screenspace import line as L

    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((48, 40)))
    pattern = vo.patterns.disk(samples)
    assert L._exactly_antipodal(pattern)
    assert not L._exactly_antipodal(vo.patterns.disk(samples, symmetric=False, method="random", seed=3))
    fast = vo.vo_line(gb, radius=0.3, samples=pattern, normal_clamp=True)
    monkeypatch.setattr(L, "_exactly_antipodal", lambda p: False)
    full = vo.vo_line(gb, radius=0.3, samples=pattern, normal_clamp=True)
    valid = gb.valid
    assert np.isnan(fast[~valid]).all() and np.isfinite(fast[valid]).all()
    np.testing.assert_allclose(fast[valid], full[valid], rtol=0, atol=1e-12)


