"""GTAO (Jimenez et al. 2016): planes (a level camera among them), the orthographic crease, the
ray-cast AO, float32 (the Cornell box among them), extremes."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import GBuffer
from vobscure.screenspace.gtao import PRESETS, gtao, gtao_bent_normals

from analytic import crease_bent_normal, crease_cosine_ao
from conftest import interior, one_slice_z

#: Planes at 9 slices (not grazing): the slice integral |n_p| (cos g + g sin g) is exact only
#: on average over slices; the midpoint rule over 9 slices leaves at most 1.4e-6 (measured,
#: perspective oblique), 3e-9 (orthographic oblique).
PLANE_TOL = 1e-3
#: Grazing views of a plane at 9 slices: the slice integrand is clipped near gamma = +-pi/2,
#: so the slice quadrature converges slower; measured worst pixel 0.9936 (perspective),
#: 0.9997 (orthographic).
GRAZING_PLANE_TOL = 1e-2
#: Orthographic crease, 32 slices x 32 steps, no randomization: measured RMSE 8.9e-3 against
#: the closed form (4 x 4: 4.4e-2, 16 x 16: 1.3e-2); what remains is the horizon missed
#: between steps (always low, so the estimate reads too open) and the bilinear chamfer at
#: the crease.
CREASE_TOL = 1.2e-2
#: Perspective oblique crease, 16 x 16 against ground_truth("ao", 1024 rays, its own noise
#: 1.6e-3 RMS): measured RMSE 1.8e-2 (3 x 3: 3.9e-2).
PERSPECTIVE_TOL = 2.5e-2
#: Bent normals on a plane, degrees from the normal (interior pixels), 2 slices or more:
#: measured max 1.2e-6 degrees (3 and 9 slices).
BENT_PLANE_TOL_DEG = 1e-2
#: Bent normals on the orthographic crease against the closed form (tests/analytic.py)
#: (the wall blocks omega_x < -c), 16 x 16 without randomization: measured RMS angle 0.88
#: degrees (3 x 3: 4.5, 32 x 32: 0.61).
BENT_CREASE_TOL_DEG = 1.2
#: float32 against float64 G-buffer, per pixel: the inputs round at 6e-8 relative (computed
#: in float64 after that). Measured max 9e-7 (orthographic crease), 4e-7 (perspective);
#: acos near 1 amplifies a rounding of the horizon cosine, hence 10x the measured.
FLOAT32_TOL = 1e-5
#: Bent normals, float32 against float64 per component (the cosine of their angle is too close
#: to 1 for acos to resolve it): measured max 1.1e-6 on the Cornell box; 10x as FLOAT32_TOL.
BENT_FLOAT32_TOL = 1e-5
#: The probe's slab (its edges in view) from a level camera and from one tilted by 0.02 degrees:
#: the two images differ by the tilt's 0.02-pixel shift; measured difference of the means 1.4e-5
#: (3 slices). 1e-3 is 70x that and 70x below what a level floor read as occluded would show.
TILT_MEAN_TOL = 1e-3

#: A camera 1 unit above the slab's top (y = 0) looking level (view-space n_z = 0 at every
#: floor pixel), and the same camera tilted down by atan(0.001 / 3) = 0.02 degrees.
LEVEL_EYE = (0.0, 1.0, 3.0)
LEVEL_TARGETS = {"level": (0.0, 1.0, 0.0), "tilted": (0.0, 0.999, 0.0)}


VIEWS = {
    "persp-oblique": (dict(eye=(1, 2, 1.5), fov_y=40.0), PLANE_TOL),
    "persp-top": (dict(eye=(0.01, 3, 0.0), fov_y=60.0), PLANE_TOL),
    "ortho-oblique": (dict(eye=(1, 2, 1.5), ortho_height=2.0), PLANE_TOL),
    "persp-grazing": (dict(eye=(3, 0.6, 0.4), fov_y=30.0), GRAZING_PLANE_TOL),
    "ortho-grazing": (dict(eye=(3, 0.8, 0.4), ortho_height=1.5), GRAZING_PLANE_TOL),
}


@pytest.mark.parametrize("view", VIEWS, ids=list(VIEWS))
@pytest.mark.parametrize("fetch", ["bilinear", "nearest"])
def test_plane_reads_open(big_slab, view, fetch):
    kw, tol = VIEWS[view]
    kw = dict(kw)
    gb = vo.render_gbuffer(big_slab, vo.Camera.look_at(kw.pop("eye"), (0, 0, 0), size=(64, 48), **kw))
    inside = interior(gb, 0.3)
    assert inside.sum() > 500
    v = gtao(gb, radius=0.3, slices=9, steps=3, fetch=fetch)
    if fetch == "bilinear":
        assert np.max(np.abs(v[inside] - 1.0)) < tol
    else:
        # snapped taps leave the slice plane and can rise above its horizon (documented)
        assert np.mean(v[inside]) > 0.98


def test_plane_facing_the_camera_is_exact_with_one_slice():
    """n = v: gamma = 0 and |n_p| = 1 in every slice, so one slice is already exact."""
    scene = vo.scenes.slab(size=50.0)
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(32, 32), ortho_height=2.0)
    gb = vo.render_gbuffer(scene, cam)
    inside = interior(gb, 0.2)
    for slices, steps in PRESETS.values():
        v = gtao(gb, radius=0.2, slices=slices, steps=steps, seed=3)
        assert np.max(np.abs(v[inside] - 1.0)) < PLANE_TOL


def test_converges_to_closed_form_on_orthographic_crease(crease_view):
    gb, floor, c = crease_view
    assert floor.sum() > 500
    exact = crease_cosine_ao(c)
    rmse = [np.sqrt(np.mean((gtao(gb, radius=1.0, slices=n, steps=n, randomize=False)[floor] - exact) ** 2))
            for n in (4, 16, 32)]
    assert rmse[2] < rmse[1] < rmse[0], rmse
    assert rmse[2] < CREASE_TOL, rmse


def test_against_ray_cast_ao_in_perspective():
    scene = vo.scenes.crease()
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(48, 40), fov_y=50.0)
    gb = vo.render_gbuffer(scene, cam)
    ref = vo.ground_truth(scene, gb, quantity="ao", radius=0.5, rays=1024, seed=1)
    valid = gb.valid
    rmse = {}
    for s, st in ((3, 3), (16, 16)):
        v = gtao(gb, radius=0.5, slices=s, steps=st)
        assert np.array_equal(np.isnan(v), ~valid)
        rmse[s] = np.sqrt(np.mean((v - ref.value)[valid] ** 2))
    assert rmse[16] < rmse[3]
    assert rmse[16] < PERSPECTIVE_TOL, rmse


def test_options_move_away_from_the_reference(crease_view):
    """power and falloff_range bias the estimate (docs/screenspace.md, "GTAO")."""
    gb, floor, c = crease_view
    exact = crease_cosine_ao(c)
    base = gtao(gb, radius=1.0, slices=8, steps=8, randomize=False)
    dark = gtao(gb, radius=1.0, slices=8, steps=8, randomize=False, power=2.2)
    np.testing.assert_allclose(dark[floor], base[floor] ** 2.2, rtol=1e-12)
    soft = gtao(gb, radius=1.0, slices=8, steps=8, randomize=False, falloff_range=0.615)
    assert np.all(soft[floor] >= base[floor] - 1e-12)          # the falloff only opens
    fudge = gtao(gb, radius=1.0, slices=8, steps=8, randomize=False, normal_fudge=0.05)
    assert np.all(fudge[gb.valid] >= base[gb.valid] - 1e-12)    # |n_p| only grows
    err = lambda v: np.sqrt(np.mean((v[floor] - exact) ** 2))   # noqa: E731
    assert err(dark) > err(base) and err(soft) > err(base)


def test_taps_per_pixel(crease_view, monkeypatch):
    """2 x slices x steps depth reads per pixel (the lead's cost model)."""
    from vobscure.screenspace import _common as C
    gb, _, _ = crease_view
    count = [0]
    real = C.fetch_depth

    def counting(depth, x, y, **kw):
        count[0] += np.size(x)
        return real(depth, x, y, **kw)
    monkeypatch.setattr(C, "fetch_depth", counting)
    for slices, steps in PRESETS.values():
        count[0] = 0
        gtao(gb, radius=0.5, slices=slices, steps=steps)
        assert count[0] == 2 * slices * steps * gb.valid.sum()


def test_float32_and_determinism(crease_view):
    gb, _, _ = crease_view
    v64 = gtao(gb, radius=0.5, seed=2)
    v32 = gtao(gb.astype(np.float32), radius=0.5, seed=2)
    assert v64.dtype == np.float64 and v32.dtype == np.float32
    assert np.array_equal(np.isnan(v32), ~gb.valid)
    np.testing.assert_allclose(v32[gb.valid].astype(np.float64), v64[gb.valid], rtol=0, atol=FLOAT32_TOL)
    a = gtao(gb, radius=0.5, seed=4)
    b = gtao(gb, radius=0.5, seed=4)
    c = gtao(gb, radius=0.5, seed=5)
    assert a.tobytes() == b.tobytes()
    assert not np.array_equal(a, c, equal_nan=True)
    d = gtao(gb, radius=0.5, randomize=False, seed=4)
    assert d.tobytes() == gtao(gb, radius=0.5, randomize=False, seed=5).tobytes()


def _silent(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            return fn(*args, **kw)


def test_extremes(crease_view):
    gb, _, _ = crease_view
    scene = vo.scenes.crease()
    # below a pixel: every tap lies beyond the radius, the horizons stay at the tangent
    # plane (an open surface: 1 up to the slice quadrature, PLANE_TOL at 9 slices)
    small = _silent(gtao, gb, radius=1e-7, slices=9)
    np.testing.assert_allclose(small[gb.valid], 1.0, atol=PLANE_TOL)
    for radius in (1e-3, 1e3):                             # ... larger than the scene
        v = _silent(gtao, gb, radius=radius)
        assert np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1)) and np.all(np.isnan(v[~gb.valid]))
    steps = vo.scenes.steps()          # grazing view, depth discontinuities, off-screen taps
    g2 = vo.render_gbuffer(steps, vo.Camera.look_at((3.0, 0.3, 0.2), (0, 0.3, 0), size=(40, 30), fov_y=60))
    for offscreen in ("clamp", "open"):
        for fetch in ("bilinear", "nearest"):
            v = _silent(gtao, g2, radius=0.4, offscreen=offscreen, fetch=fetch, falloff_range=0.5,
                        thin_occluder=1.0, normal_fudge=0.05, power=2.2)
            assert np.all(np.isfinite(v[g2.valid])) and np.all((v[g2.valid] >= 0) & (v[g2.valid] <= 1))
            assert np.all(np.isnan(v[~g2.valid]))
    sky = vo.render_gbuffer(scene, vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(6, 5)))
    assert np.all(np.isnan(_silent(gtao, sky, radius=0.5)))
    one = vo.render_gbuffer(scene, vo.Camera.look_at((2, 2, 2), (0.5, 0, 0), size=(1, 1)))
    v1 = _silent(gtao, one, radius=0.5)
    assert v1.shape == (1, 1) and np.isfinite(v1[0, 0])
    depth = np.array(gb.depth)
    depth[10:20, 10:20] = np.nan
    holed = GBuffer(gb.camera, depth=depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive, hits=gb.hits)
    vh = _silent(gtao, holed, radius=0.5)
    assert np.all(np.isnan(vh[10:20, 10:20]))
    assert np.all(np.isfinite(vh[gb.valid & ~np.isnan(depth)]))


def test_bad_arguments(crease_view):
    gb, _, _ = crease_view
    cases = [
        (dict(radius=0), "radius"), (dict(radius=np.nan), "radius"),
        (dict(slices=0), "slices"), (dict(slices=2.5), "slices"), (dict(steps=0), "steps"),
        (dict(falloff_range=-0.1), "falloff_range"), (dict(falloff_range=1.5), "falloff_range"),
        (dict(thin_occluder=-1), "thin_occluder"), (dict(power=0), "power"),
        (dict(normal_fudge=2), "normal_fudge"), (dict(randomize="yes"), "randomize"),
        (dict(seed=-1), "seed"), (dict(fetch="cubic"), "fetch"), (dict(offscreen="wrap"), "offscreen"),
        (dict(noise_size=0), "noise_size"),
    ]
    for kw, match in cases:
        with pytest.raises(ValueError, match=match):
            gtao(gb, **{"radius": 0.5, **kw})
    with pytest.raises(ValueError, match="gbuffer"):
        gtao(np.zeros((4, 4)), radius=1)


def test_presets_are_xegtao():
    assert PRESETS == {"low": (1, 2), "medium": (2, 2), "high": (3, 3), "ultra": (9, 3)}


def _angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


@pytest.mark.parametrize("view", ["persp-oblique", "ortho-oblique", "persp-grazing"])
def test_bent_normals_on_planes_are_the_normal(big_slab, view):
    kw = dict(VIEWS[view][0])
    gb = vo.render_gbuffer(big_slab, vo.Camera.look_at(kw.pop("eye"), (0, 0, 0), size=(64, 48), **kw))
    inside = interior(gb, 0.3)
    n = np.where(gb.valid[..., None], gb.normal, 1.0)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    for slices in (2, 3, 9):       # one slice: the bent normal lies in its plane
        b = gtao_bent_normals(gb, radius=0.3, slices=slices, seed=1)
        assert np.all(np.isnan(b[~gb.valid]))
        np.testing.assert_allclose(np.linalg.norm(b[gb.valid], axis=-1), 1.0, atol=1e-12)
        assert np.max(_angle_deg(b, n)[inside]) < BENT_PLANE_TOL_DEG, slices


def test_bent_normals_converge_on_the_crease(crease_view):
    gb, floor, c = crease_view
    exact = crease_bent_normal(c)
    exact /= np.linalg.norm(exact, axis=-1, keepdims=True)
    rms = []
    for n in (3, 16):
        b = gtao_bent_normals(gb, radius=1.0, slices=n, steps=n, randomize=False)
        world = b[floor] @ gb.camera.rotation          # view -> world: rotation.T @ b
        rms.append(np.sqrt(np.mean(_angle_deg(world, exact) ** 2)))
    assert rms[1] < rms[0] and rms[1] < BENT_CREASE_TOL_DEG, rms
    # float32 in, float32 out; the same seed, the same image
    b32 = gtao_bent_normals(gb.astype(np.float32), radius=0.5, seed=3)
    assert b32.dtype == np.float32 and b32.shape == gb.shape + (3,)
    assert b32.tobytes() == gtao_bent_normals(gb.astype(np.float32), radius=0.5, seed=3).tobytes()
    with pytest.raises(ValueError, match="slices"):
        gtao_bent_normals(gb, radius=0.5, slices=0)
    with pytest.raises(ValueError, match="radius"):
        gtao_bent_normals(gb, radius=-1.0)


def test_step_jitter_r1_is_xegtaos_and_optional(crease_view):
    gb, _, _ = crease_view
    pixel = gtao(gb, radius=0.5, seed=3)
    assert pixel.tobytes() == gtao(gb, radius=0.5, seed=3, step_jitter="pixel").tobytes()
    r1 = gtao(gb, radius=0.5, seed=3, step_jitter="r1")
    valid = gb.valid
    assert not np.array_equal(r1[valid], pixel[valid])          # the slices sample other radii
    assert np.all((r1[valid] >= 0) & (r1[valid] <= 1))
    # without randomization there is no jitter to advance: both are the midpoint rule
    assert gtao(gb, radius=0.5, randomize=False, step_jitter="r1").tobytes() == \
        gtao(gb, radius=0.5, randomize=False).tobytes()
    with pytest.raises(ValueError, match="step_jitter"):
        gtao(gb, radius=0.5, step_jitter="golden")
    with pytest.raises(ValueError, match="step_jitter"):
        gtao_bent_normals(gb, radius=0.5, step_jitter="R1")


def test_unclipped_one_slice_frames_average_to_the_integral():
    # An open plane seen obliquely is open (1). One slice per frame at a random angle is unbiased
    # only unclipped (a slice's estimate can exceed 1); clipped frames average darker.
    assert abs(one_slice_z(gtao, clip=False)) < 3.29     # two-sided, false-failure rate 1e-3
    assert one_slice_z(gtao, clip=True) < -5.0

def test_level_camera_reads_an_open_plane_open(big_slab):
    """A floor seen by a level camera has n_z = 0 in view space at every pixel; GTAO's slices
    go through the view vector, so nothing divides by n_z: the plane reads open within the
    grazing-view tolerance at 9 slices (the floor is grazing far away), its bent normal is the
    normal, and the probe's slab reads as from a camera tilted by 0.02 degrees."""
    means = {}
    for name, target in LEVEL_TARGETS.items():
        cam = vo.Camera.look_at(LEVEL_EYE, target, size=(64, 64), fov_y=60)
        gb = vo.render_gbuffer(big_slab, cam)
        if name == "level":
            assert np.all(gb.normal[..., 2][gb.valid] == 0.0)
        inside = interior(gb, 0.3)
        assert inside.sum() > 1000
        v = gtao(gb, radius=0.3, slices=9, steps=3)
        assert np.max(np.abs(v[inside] - 1.0)) < GRAZING_PLANE_TOL, name
        b = gtao_bent_normals(gb, radius=0.3, seed=1)
        assert np.max(_angle_deg(b, gb.normal)[inside]) < BENT_PLANE_TOL_DEG, name
        small = vo.render_gbuffer(vo.scenes.slab(), cam)
        means[name] = np.nanmean(gtao(small, radius=0.3))
    assert abs(means["level"] - means["tilted"]) < TILT_MEAN_TOL


def test_float32_agrees_on_the_cornell_box():
    """The Cornell box seen head-on: walls, floor and ceiling with n_z = 0 in view space;
    float32 and float64 G-buffers agree within float32's rounding, visibility and bent
    normals."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((64, 64)))
    g32 = gb.astype(np.float32)
    assert np.sum(gb.normal[..., 2][gb.valid] == 0.0) > 1000
    v64, v32 = gtao(gb, radius=0.5), gtao(g32, radius=0.5)
    assert v32.dtype == np.float32
    np.testing.assert_allclose(v32[gb.valid].astype(np.float64), v64[gb.valid], rtol=0, atol=FLOAT32_TOL)
    b64, b32 = gtao_bent_normals(gb, radius=0.5), gtao_bent_normals(g32, radius=0.5)
    np.testing.assert_allclose(b32[gb.valid].astype(np.float64), b64[gb.valid], rtol=0, atol=BENT_FLOAT32_TOL)
