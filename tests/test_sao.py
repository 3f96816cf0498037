"""Alchemy AO and SAO (McGuire et al. 2011, 2012; vobscure.screenspace.sao): planes, the
orthographic crease, extremes. The properties every obscurance estimator of this family shares
(planes, extremes, float32, scale, arguments) are tested here for HBAO too; HBAO's own
convergence is in test_hbao.py."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import GBuffer
from vobscure.screenspace.hbao import hbao, hbao_taps
from vobscure.screenspace.sao import GOLDEN_ANGLE, alchemy, alchemy_taps, sao, sao_taps

from conftest import CREASE_EYE, CREASE_RADIUS, CREASE_SIZE, CREASE_TARGET

#: Planes with the default bias beta: every tap has v . n below the bias, so exactly 1.
#: Without the bias (beta = 0) float32 depth noise gives v . n of either sign; measured
#: largest 1 - A over the slab views below and the intrinsics camera: 1.7e-5 (Alchemy),
#: 3.0e-5 (SAO), 1.3e-5 (HBAO, angle_bias = 0); 1e-4 is 3x the largest.
PLANE_NOISE_TOL = 1e-4
#: The estimators against their own converged value on the orthographic crease (the disk
#: (Alchemy) or spiral (SAO) integral of the same summand, computed here by ray-plane
#: geometry on a 200 x 200 quadrature, independent of the depth buffer). What remains at
#: many taps is the snapping of taps to pixel centres (radius 32 px here) and the
#: quadrature's own error (2e-3 max between 200^2 and 400^2 points): measured RMSE over
#: 451 floor pixels 3.1e-3 (Alchemy, 1024 taps) and 2.7e-3 (SAO, 1024 taps, randomize=False).
#: 1e-2 is 3x the larger; sigma = 1.1 instead of 1 (a wrong constant) measures 3.8e-2.
LIMIT_TOL = 1e-2
#: float32 against float64 (and scaled scenes, Embree's float32 hits) per pixel: the taps'
#: points come from float32 depths (relative error u = 6e-8) in v . n / v . v, where |v| can
#: be a few pixels while z is large, amplifying u by z / |v| ~ 100. Measured max on the
#: oblique crease: float32 1.1e-6 (Alchemy), 2.4e-6 (SAO); scales 1e-3 and 1e3 2.0e-6 and
#: 4.7e-6; HBAO 1.0e-6 and 1.4e-6. 2e-5 is 4x the largest.
FLOAT32_TOL = 2e-5

R_CREASE = CREASE_RADIUS
SIZE = CREASE_SIZE
ESTIMATORS = [alchemy, sao, hbao]
NO_BIAS = {alchemy: dict(beta=0.0), sao: dict(beta=0.0), hbao: dict(angle_bias=0.0)}


@pytest.mark.parametrize("fn", ESTIMATORS)
@pytest.mark.parametrize("view", [dict(eye=(1, 2, 1.5), fov_y=40.0), dict(eye=(3, 0.6, 0.4), fov_y=30.0),
                                  dict(eye=(1, 2, 1.5), ortho_height=2.0)], ids=["oblique", "grazing", "ortho"])
def test_planes_open_by_the_bias(big_slab, fn, view):
    """The bias term (Alchemy's z_C beta, SAO's beta, HBAO's angle bias) makes a plane read
    exactly 1."""
    kw = dict(view)
    cam = vo.Camera.look_at(kw.pop("eye"), (0, 0, 0), size=(64, 48), **kw)
    gb = vo.render_gbuffer(big_slab, cam)
    for radius in (0.02, 0.3):
        v = fn(gb, radius=radius)
        assert np.all(v[gb.valid] == 1.0)
        v0 = fn(gb, radius=radius, **NO_BIAS[fn])
        assert np.min(v0[gb.valid]) > 1.0 - PLANE_NOISE_TOL


def _limit(gb, floor, eye, target, *, pattern, beta, epsilon, sigma=1.0, tau=7, m=200):
    """The converged estimator on the orthographic crease floor, by ray-plane geometry.

    Each disk offset r (ux, uy) in the view plane through C, pushed along the view
    direction to where it leaves the free quadrant x > 0, y > 0, is the surface point Q.
    ``pattern="disk"``: the area-uniform disk (Alchemy's sunflower as s grows);
    ``"spiral"``: SAO's spiral with phi = 0, alpha uniform on [0, 1].
    """
    f = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(f, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    Cw = gb.world_position[floor]                   # (k, 3)
    zC = gb.depth[floor]
    r = R_CREASE
    if pattern == "disk":
        rho, th = np.meshgrid(np.sqrt((np.arange(m) + 0.5) / m), 2 * np.pi * (np.arange(m) + 0.5) / m)
        ux, uy = (rho * np.cos(th)).ravel(), (rho * np.sin(th)).ravel()
    else:
        alpha = (np.arange(m * m) + 0.5) / (m * m)
        th = 2 * np.pi * alpha * tau
        ux, uy = alpha * np.cos(th), alpha * np.sin(th)
    total = np.zeros(len(Cw))
    for a in range(0, len(ux), 2000):
        off = r * (ux[a:a + 2000, None] * right + uy[a:a + 2000, None] * up)     # (m, 3)
        P0 = Cw[:, None, :] + off[None]                                          # (k, m, 3)
        t = np.minimum(-P0[..., 0] / f[0], -P0[..., 1] / f[1])
        v = P0 + t[..., None] * f - Cw[:, None, :]
        vv = np.sum(v * v, axis=-1)
        vn = v[..., 1]                                                          # n = +y
        if pattern == "disk":
            term = np.where(vv < r * r, np.maximum(0, vn - zC[:, None] * beta) / (vv + epsilon * r * r), 0)
        else:
            term = np.maximum(0, r * r - vv) ** 3 * np.maximum(0, (vn - beta * r) / (vv + epsilon * r * r))
        total += term.sum(axis=1)
    mean = total / len(ux)
    if pattern == "disk":
        return np.maximum(0, 1 - 2 * sigma * r * mean)
    return np.maximum(0, 1 - 5 * sigma / r ** 5 * mean)


def test_crease_converges_to_own_limit(crease_view):
    """As taps grow, each estimator tends to its own converged value (not to a ray-cast
    obscurance, see test_closest_obscurance)."""
    gb, floor, _ = crease_view
    eye, target = np.asarray(CREASE_EYE), np.asarray(CREASE_TARGET)
    floor = floor & (np.arange(floor.size).reshape(floor.shape) % 3 == 0)   # every third pixel
    assert floor.sum() > 300
    lim_a = _limit(gb, floor, eye, target, pattern="disk", beta=1e-4, epsilon=1e-4)
    lim_s = _limit(gb, floor, eye, target, pattern="spiral", beta=0.01, epsilon=0.01)
    rmse = {}
    for n in (4, 64, 1024):
        rmse[n] = (np.sqrt(np.mean((alchemy(gb, radius=R_CREASE, samples=n)[floor] - lim_a) ** 2)),
                   np.sqrt(np.mean((sao(gb, radius=R_CREASE, samples=n, randomize=False)[floor] - lim_s) ** 2)))
    assert rmse[1024][0] < rmse[64][0] < rmse[4][0], rmse
    assert rmse[1024][1] < rmse[4][1], rmse
    assert rmse[1024][0] < LIMIT_TOL and rmse[1024][1] < LIMIT_TOL, rmse


def test_sunflower_is_uniform_by_area():
    """Alchemy's disk: the fraction of taps within radius rho is rho^2 (to 1 / s)."""
    s = 1000
    rho = np.sqrt((np.arange(s) + 0.5) / s)
    for q in (0.25, 0.5, 0.9):
        assert abs(np.mean(rho < q) - q * q) <= 1.0 / s
    assert 0 < GOLDEN_ANGLE < np.pi


#: Measured RMSE over the 1353 interior crease-floor pixels (radius 1, 1024 taps, defaults)
#: against the ray-cast obscurance (1024 cosine rays, stderr 3.5e-3) with each of
#: groundtruth.OBSCURANCE_FALLOFFS (docs/screenspace.md): Alchemy step 0.141, linear 0.260,
#: smooth 0.259; SAO step 0.187, linear 0.227, smooth 0.219. Neither estimates any of them
#: (the margins, > 0.03, are 10x the reference noise); "step" (AO within r) is the closest.
CLOSEST_FALLOFF = "step"


def test_closest_obscurance(crease, crease_view):
    scene = crease
    gb, floor, _ = crease_view
    pts, nrm = gb.world_position[floor][::7], gb.world_normal[floor][::7]
    for fn in (alchemy, sao):
        est = fn(gb, radius=R_CREASE, samples=256)[floor][::7]
        rmse = {}
        for falloff in vo.groundtruth.OBSCURANCE_FALLOFFS:
            ref = vo.obscurance(scene, pts, nrm, radius=R_CREASE, falloff=falloff, rays=512, seed=1).value
            rmse[falloff] = np.sqrt(np.mean((est - ref) ** 2))
        assert min(rmse, key=rmse.get) == CLOSEST_FALLOFF, (fn.__name__, rmse)


@pytest.mark.parametrize("fn", ESTIMATORS)
def test_extremes(fn, crease, crease_view):
    scene = crease
    gb, _, _ = crease_view
    for radius in (1e-7, 1e-3):   # below a pixel: every tap is the centre pixel, v = 0
        v = fn(gb, radius=radius)
        assert np.all(v[gb.valid] == 1.0) and np.all(np.isnan(v[~gb.valid]))
    v = fn(gb, radius=1e3)        # larger than the scene
    assert np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1)) and np.all(np.isnan(v[~gb.valid]))
    # grazing view of steps: discontinuities, off-screen taps
    steps = vo.scenes.steps()
    g2 = vo.render_gbuffer(steps, vo.Camera.look_at((3.0, 0.3, 0.2), (0, 0.3, 0), size=(40, 30), fov_y=60))
    for offscreen in ("clamp", "open"):
        with np.errstate(all="raise"):
            v = fn(g2, radius=0.4, offscreen=offscreen)
        assert np.all(np.isfinite(v[g2.valid])) and np.all((v[g2.valid] >= 0) & (v[g2.valid] <= 1))
    # all background, one pixel, NaN depth (treated as background)
    sky = vo.render_gbuffer(scene, vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(6, 5)))
    assert np.all(np.isnan(fn(sky, radius=0.5)))
    one = vo.render_gbuffer(scene, vo.Camera.look_at((2, 2, 2), (0.5, 0, 0), size=(1, 1)))
    v1 = fn(one, radius=0.5)
    assert v1.shape == (1, 1) and v1[0, 0] == 1.0
    depth = np.array(gb.depth)
    depth[10:20, 10:20] = np.nan
    holed = GBuffer(gb.camera, depth=depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive, hits=gb.hits)
    vh = fn(holed, radius=0.5)
    assert np.all(np.isnan(vh[10:20, 10:20]))
    assert np.all(np.isfinite(vh[gb.valid & ~np.isnan(depth)]))


@pytest.mark.parametrize("fn", ESTIMATORS)
def test_float32_scale_and_seed(fn):
    scene = vo.scenes.crease()
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(48, 40), fov_y=50.0)
    gb = vo.render_gbuffer(scene, cam)
    v64 = fn(gb, radius=0.5, seed=2)
    v32 = fn(gb.astype(np.float32), radius=0.5, seed=2)
    assert v64.dtype == np.float64 and v32.dtype == np.float32
    assert np.array_equal(np.isnan(v32), ~gb.valid)
    np.testing.assert_allclose(v32[gb.valid], v64[gb.valid], rtol=0, atol=FLOAT32_TOL)
    # scene, camera and radius scaled together: the same image (sigma, beta, epsilon are
    # relative to the radius)
    for k in (1e-3, 1e3):
        vk = fn(vo.render_gbuffer(scene.scaled(k), cam.scaled(k)), radius=0.5 * k, seed=2)
        np.testing.assert_allclose(vk[gb.valid], v64[gb.valid], rtol=0, atol=FLOAT32_TOL)
    assert np.array_equal(fn(gb, radius=0.5, seed=2), v64, equal_nan=True)
    assert not np.array_equal(fn(gb, radius=0.5, seed=3), v64, equal_nan=True)
    # the tiled texture is the only randomness: randomize=False ignores the seed
    assert np.array_equal(fn(gb, radius=0.5, randomize=False, seed=2), fn(gb, radius=0.5, randomize=False, seed=9),
                          equal_nan=True)


def test_fx_fy_cx_cy_honoured():
    """A camera with fx != fy and an off-centre principal point: the taps' points are
    reconstructed with it, so they lie on the plane (v . n = 0 up to float32 noise); a wrong
    fx, fy, cx or cy tilts the reconstructed plane and darkens it."""
    scene = vo.scenes.slab(size=200.0)
    base = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(64, 48), fov_y=40)
    cam = vo.Camera.from_intrinsics(70.0, 45.0, 20.0, 30.0, (64, 48), pose=base.pose)
    gb = vo.render_gbuffer(scene, cam)
    for fn in ESTIMATORS:
        assert np.all(fn(gb, radius=0.3)[gb.valid] == 1.0)
        assert np.min(fn(gb, radius=0.3, **NO_BIAS[fn])[gb.valid]) > 1.0 - PLANE_NOISE_TOL


@pytest.mark.parametrize("fn", ESTIMATORS)
def test_bad_arguments(fn, crease_view):
    gb, _, _ = crease_view
    cases = [(dict(radius=0), "radius"), (dict(radius=-1), "radius"), (dict(radius=np.nan), "radius"),
             (dict(radius=1, offscreen="wrap"), "offscreen"), (dict(radius=1, noise_size=0), "noise_size"),
             (dict(radius=1, seed="x"), "seed")]
    if fn is not hbao:
        cases += [(dict(radius=1, samples=0), "samples"), (dict(radius=1, samples=2.5), "samples"),
                  (dict(radius=1, beta=-1), "beta"), (dict(radius=1, sigma=-1), "sigma"),
                  (dict(radius=1, k=0), "k"), (dict(radius=1, epsilon=0), "epsilon")]
    if fn is sao:
        cases.append((dict(radius=1, turns=0), "turns"))
    for kw, name in cases:
        with pytest.raises(ValueError, match=name):
            fn(gb, **kw)
    if fn is hbao:
        for kw, name in ((dict(directions=0), "directions"), (dict(steps=1.5), "steps"),
                         (dict(angle_bias=-0.1), "angle_bias"), (dict(angle_bias=np.pi / 2), "angle_bias")):
            with pytest.raises(ValueError, match=name):
                fn(gb, radius=1, **kw)
    with pytest.raises(ValueError, match="gbuffer"):
        fn(gb.depth, radius=1)


def test_taps():
    assert alchemy_taps(12) == 12 and sao_taps(9) == 9 and hbao_taps(8, 4) == 32
    with pytest.raises(ValueError, match="directions"):
        hbao_taps(0, 4)
