"""VBAO (Therrien et al. 2023): planes (a level camera among them), the orthographic crease, the
GTAO limit, solid intervals, extremes, float32 (the Cornell box among them) and argument
errors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import GBuffer
from vobscure.layers import SolidIntervals
from vobscure.screenspace.gtao import gtao
from vobscure.screenspace.vbao import EEVEE_WEIGHTS, sector_weights, vbao

from analytic import crease_cosine_ao, crease_uniform_ao
from conftest import one_slice_z

#: Planes at 9 slices, cosine weighting: the slice integral is exact only on average over
#: slices, as GTAO's (tests/test_gtao.py, PLANE_TOL); no tap on a plane marks a sector (its
#: angle is the hemisphere's edge, half a sector from the nearest centre).
PLANE_TOL = 1e-3
#: The uniform and bit-count weightings give every slice of an open hemisphere exactly 1 (sum
#: of the sector weights: 1 up to rounding).
EXACT_TOL = 1e-12
#: Orthographic crease at 32 slices x 32 steps x 32 sectors: GTAO's discretization (measured
#: RMSE 8.9e-3, tests/test_gtao.py) plus the sector quantization, an error uniform over half a
#: sector (pi / 64) at each of the two horizon ends, std (pi / 32) / sqrt(12) = 2.8e-2 per end,
#: averaged over 32 slices: 2.8e-2 sqrt(2 / 32) = 7e-3 in quadrature, 1.1e-2 in all.
CREASE_TOL = 1.2e-2
#: VBAO's arccos (Abramowitz & Stegun 4.4.46) is within 2.2e-8 rad of the exact one: a horizon
#: that close to a sector's centre may flip it (the integrand is at most 1 per radian).
ACOS_TOL = 1e-7
#: The same at 12 slices x 12 steps: GTAO's discretization measured 1.3e-2 at 16 x 16 and
#: 2.2e-2 at 8 x 8 (about 1 / n), so about 1.7e-2 at 12 x 12; the quantization
#: 2.8e-2 sqrt(2 / 12) = 1.1e-2 in quadrature: 2.0e-2.
CREASE_TOL_12 = 2.2e-2
#: A thickness far larger than the crease scene (its walls are a few units across).
THICK = 1e3
#: float32 against float64: the taps' angles move by ~1e-7 rad; a sector whose centre lies
#: that close to an angle flips, changing a slice by one sector's weight (at most pi / sectors
#: for the cosine weighting) divided by the slices. Otherwise equal to ~1e-6.
FLOAT32_TOL = 1e-5
#: The fraction of pixels where such a flip may happen (angles within ~1e-7 rad of one of 32
#: sector centres of a slice: of the order of 1e-5 per tap; a few in 1e3 allowed).
FLOAT32_FLIP_FRACTION = 5e-3
#: Grazing views of a plane at 9 slices, as GTAO's (tests/test_gtao.py, GRAZING_PLANE_TOL):
#: the slice integrand is clipped near the hemisphere's edge; a level camera's far floor is
#: grazing (measured worst pixel 0.9929).
GRAZING_PLANE_TOL = 1e-2
#: The probe's slab (its edges in view) from a level camera and from one tilted by 0.02 degrees:
#: the two images differ by the tilt's 0.02-pixel shift; measured difference of the means 1.4e-5
#: (3 slices). 1e-3 is 70x that and 70x below what a level floor read as occluded would show.
TILT_MEAN_TOL = 1e-3

#: A camera 1 unit above the slab's top (y = 0) looking level (view-space n_z = 0 at every
#: floor pixel), and the same camera tilted down by atan(0.001 / 3) = 0.02 degrees.
LEVEL_EYE = (0.0, 1.0, 3.0)
LEVEL_TARGETS = {"level": (0.0, 1.0, 0.0), "tilted": (0.0, 0.999, 0.0)}


def _interior(gb, radius):
    from conftest import interior
    return interior(gb, radius)


# --------------------------------------------------------------------------- closed forms
VIEWS = {
    "persp-oblique": dict(eye=(1, 2, 1.5), fov_y=40.0),
    "ortho-oblique": dict(eye=(1, 2, 1.5), ortho_height=2.0),
    "persp-top": dict(eye=(0.01, 3, 0.0), fov_y=60.0),
}


@pytest.mark.parametrize("view", sorted(VIEWS))
def test_plane_reads_open(big_slab, view):
    kw = VIEWS[view]
    cam = vo.Camera.look_at(kw["eye"], (0, 0, 0), size=(24, 20), **{k: v for k, v in kw.items() if k != "eye"})
    gb = vo.render_gbuffer(big_slab, cam)
    inside = _interior(gb, 0.3)
    assert inside.sum() > 50
    for thickness in (0.1, np.inf):
        v = vbao(gb, radius=0.3, slices=9, thickness=thickness)
        assert np.max(np.abs(v[inside] - 1.0)) < PLANE_TOL, (view, thickness)
        for weighting in ("uniform", "bitcount", "eevee"):
            w = vbao(gb, radius=0.3, slices=3, thickness=thickness, weighting=weighting)
            assert np.max(np.abs(w[inside] - 1.0)) < (EXACT_TOL if weighting != "eevee" else 1e-5), weighting


@pytest.mark.parametrize("weighting, closed_form", [("cosine", crease_cosine_ao), ("uniform", crease_uniform_ao)])
def test_tends_to_closed_form_on_orthographic_crease(crease_view, weighting, closed_form):
    """The fast version of the next test: 4 and 12 slices x steps."""
    gb, floor, c = crease_view
    exact = closed_form(c)
    rmse = [np.sqrt(np.mean((vbao(gb, radius=1.0, slices=n, steps=n, thickness=THICK, weighting=weighting,
                                  randomize=False)[floor] - exact) ** 2)) for n in (4, 12)]
    assert rmse[1] < rmse[0] / 2 and rmse[1] < CREASE_TOL_12, rmse


@pytest.mark.slow
@pytest.mark.parametrize("weighting, closed_form", [("cosine", crease_cosine_ao), ("uniform", crease_uniform_ao)])
def test_converges_to_closed_form_on_orthographic_crease(crease_view, weighting, closed_form):
    """A thickness larger than the scene: every occluder is solid to the end, as the crease's."""
    gb, floor, c = crease_view
    exact = closed_form(c)
    rmse = [np.sqrt(np.mean((vbao(gb, radius=1.0, slices=n, steps=n, thickness=THICK, weighting=weighting,
                                  randomize=False)[floor] - exact) ** 2)) for n in (4, 16, 32)]
    assert rmse[2] < rmse[1] < rmse[0], rmse
    assert rmse[2] < CREASE_TOL, rmse


@pytest.mark.parametrize("camera", ["ortho", "persp"])
def test_infinite_thickness_is_gtao_up_to_the_sectors(crease, camera):
    """thickness=inf: the unmarked sectors are GTAO's visible arc between its two horizons,
    each end quantized to the nearest sector boundary by the centre rule: at most half a
    sector (pi / (2 S)) at each end, where the cosine-weighted integrand |n_p| cos(theta -
    gamma) |sin theta| is at most 1: |vbao - gtao| <= pi / S (plus VBAO's arccos error,
    ACOS_TOL), and the error shrinks with S."""
    size = (40, 32)
    cam = (vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=size, fov_y=50.0) if camera == "persp"
           else vo.Camera.look_at((1.5, 2.0, 2.5), (0.5, 0.3, 0.0), size=size, ortho_height=3.0))
    gb = vo.render_gbuffer(crease, cam)
    worst = {}
    for kw in (dict(seed=1), dict(seed=2, fetch="nearest", step_jitter="r1", slices=4, steps=5)):
        g = gtao(gb, radius=0.6, **kw)
        for S in (8, 64):
            v = vbao(gb, radius=0.6, thickness=np.inf, sectors=S, **kw)
            assert np.array_equal(np.isnan(v), ~gb.valid)
            d = np.abs(v - g)[gb.valid]
            assert d.max() <= np.pi / S + ACOS_TOL, (kw, S, d.max())
            worst[S] = max(worst.get(S, 0.0), d.max())
    assert worst[64] < worst[8] / 2, worst


def test_thickness_between_zero_and_infinity(crease_view):
    """Thinner occluders occlude less: the visibility grows as the thickness falls, and a
    thickness of zero with Blender's far angle of zero marks nothing on the crease's floor
    (every tap's interval is a single angle)."""
    gb, floor, c = crease_view
    runs = [vbao(gb, radius=1.0, slices=6, steps=6, thickness=t, randomize=False)[floor]
            for t in (np.inf, 0.5, 0.1, 0.0)]
    for a, b in zip(runs, runs[1:]):
        assert np.all(b >= a - 1e-12)
    assert np.mean(runs[1]) > np.mean(runs[0])
    # zero thickness marks nothing: the same as no tap within the radius
    nothing = vbao(gb, radius=1e-7, slices=6, steps=6, randomize=False)[floor]
    np.testing.assert_allclose(runs[3], nothing, rtol=0, atol=1e-12)
    # Blender's far angle: the back horizon at least that far past the front one
    far = vbao(gb, radius=1.0, slices=6, steps=6, thickness=0.0, thickness_far=np.pi / 4, randomize=False)[floor]
    assert np.mean(far) < np.mean(runs[3])


def test_sector_rules_and_weightings(crease_view):
    """Bevy's and SSRT3's touch rule marks every sector an interval touches: darker than the
    centre rule on average; the weights of the cosine weighting sum to GTAO's open slice."""
    gb, floor, c = crease_view
    centre = vbao(gb, radius=1.0, slices=8, steps=8, thickness=THICK, randomize=False)[floor]
    touch = vbao(gb, radius=1.0, slices=8, steps=8, thickness=THICK, randomize=False, sector_rule="touch")[floor]
    assert np.mean(touch) < np.mean(centre)
    gamma = np.linspace(-1.4, 1.4, 7)
    w = sector_weights(gamma, 32, "cosine")
    # a(gamma - pi/2) + a(gamma + pi/2) with a(h) = (-cos(2h - gamma) + cos gamma + 2 h sin gamma) / 4:
    # cos gamma / 2 + (pi / 2) |sin gamma| ... computed from GTAO's own formula
    from vobscure.screenspace.gtao import _inner_integral
    s, co = np.sin(gamma), np.cos(gamma)
    open_slice = _inner_integral(gamma - np.pi / 2, gamma, s, co) + _inner_integral(gamma + np.pi / 2, gamma, s, co)
    np.testing.assert_allclose(w.sum(axis=1), open_slice, rtol=0, atol=1e-12)
    assert np.all(w >= 0)
    # Blender's grouped weights are within 0.2 % of its reference loop, cos(centre) pi / 64
    centre_angle = ((np.arange(32) + 0.5) / 32 - 0.5) * np.pi
    loop = (np.cos(centre_angle) * np.pi / 64)[:16].reshape(4, 4).mean(axis=1)
    np.testing.assert_allclose(EEVEE_WEIGHTS, loop, rtol=2e-3)


# --------------------------------------------------------------------------- solid intervals
def _plate(thickness=0.05):
    """An orthographic view straight down on a floor at depth 5 with a plate at depth 4 over
    columns 20-27 (every row), ``thickness`` thick: the floor and the plate face the camera."""
    H, W = 24, 48
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(W, H), ortho_height=2.0)
    depth = np.full((H, W), 5.0)
    depth[:, 20:28] = 4.0
    normal = np.zeros((H, W, 3))
    normal[..., 2] = -1.0
    gb = GBuffer.from_arrays(depth, normal, camera=cam)
    front = np.full((2, H, W), np.inf)
    back = np.full((2, H, W), np.inf)
    front[0] = depth
    back[0, :, 20:28] = 4.0 + thickness
    front[1, :, 20:28] = 5.0
    return gb, gb.with_intervals(SolidIntervals(front, back))


def test_layers_let_light_pass_behind_a_thin_plate():
    gb, layered = _plate(0.05)
    receivers = np.zeros(gb.depth.shape, dtype=bool)
    receivers[4:20, 28:36] = True                           # the floor beside the plate
    kw = dict(radius=1.5, slices=8, steps=8, randomize=False, fetch="nearest")
    solid = vbao(layered, thickness=np.inf, **kw)
    layers = vbao(layered, thickness="layers", **kw)
    known = vbao(layered, thickness=0.05, **kw)
    # the depth buffer's model fills the space under the plate; the layers know it is empty
    assert np.all(layers[receivers] >= solid[receivers] - 1e-12)
    assert np.mean(layers[receivers] - solid[receivers]) > 0.05
    # orthographic: the back of the plate's interval on the tap's ray is the tap moved back
    # by the plate's thickness along v, the constant model with the true thickness
    np.testing.assert_allclose(layers[gb.valid], known[gb.valid], rtol=0, atol=1e-9)
    # SSRT3's linear thickness: per unit of the tap's depth; the taps that mark sectors lie on
    # the plate (depth 4), the floor's taps lie on the floor's own tangent plane
    linear = vbao(layered, thickness=0.05 / 4.0, thickness_scale="linear", **kw)
    np.testing.assert_allclose(linear[gb.valid], known[gb.valid], rtol=0, atol=1e-9)


def test_layers_need_intervals():
    gb, _ = _plate()
    with pytest.raises(ValueError, match="intervals"):
        vbao(gb, radius=1.0, thickness="layers")
    with pytest.raises(ValueError, match="thickness"):
        vbao(gb, radius=1.0, thickness="layer")


# --------------------------------------------------------------------------- extremes
def _silent(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            return fn(*args, **kw)


def test_extremes(crease_view, crease):
    gb, _, _ = crease_view
    # below a pixel: no tap within the radius, nothing marked (open, up to the slice quadrature)
    small = _silent(vbao, gb, radius=1e-7, slices=9)
    np.testing.assert_allclose(small[gb.valid], 1.0, atol=PLANE_TOL)
    for radius in (1e-3, 1e3):
        v = _silent(vbao, gb, radius=radius)
        assert np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1)) and np.all(np.isnan(v[~gb.valid]))
    steps = vo.scenes.steps()
    g2 = vo.render_gbuffer(steps, vo.Camera.look_at((3.0, 0.3, 0.2), (0, 0.3, 0), size=(40, 30), fov_y=60))
    for offscreen in ("clamp", "open"):
        for fetch in ("bilinear", "nearest"):
            for weighting in ("cosine", "uniform", "bitcount", "eevee"):
                v = _silent(vbao, g2, radius=0.4, offscreen=offscreen, fetch=fetch, weighting=weighting,
                            thickness_far=0.3, sector_rule="touch", step_power=1.0)
                assert np.all(np.isfinite(v[g2.valid])) and np.all((v[g2.valid] >= 0) & (v[g2.valid] <= 1))
                assert np.all(np.isnan(v[~g2.valid]))
    # a level camera: the floor's view-space normal has n_z = 0
    level = vo.render_gbuffer(crease, vo.Camera.look_at((2.5, 0.4, 2.5), (0.0, 0.4, 0.0), size=(24, 20), fov_y=60))
    flat = level.valid & (np.abs(level.normal[..., 2]) < 1e-9)
    assert flat.any()
    v = _silent(vbao, level, radius=0.5)
    assert np.all(np.isfinite(v[level.valid])) and np.all((v[level.valid] >= 0) & (v[level.valid] <= 1))
    sky = vo.render_gbuffer(crease, vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(6, 5)))
    assert np.all(np.isnan(_silent(vbao, sky, radius=0.5)))
    one = vo.render_gbuffer(crease, vo.Camera.look_at((2, 2, 2), (0.5, 0, 0), size=(1, 1)))
    v1 = _silent(vbao, one, radius=0.5)
    assert v1.shape == (1, 1) and np.isfinite(v1[0, 0])
    for sectors in (1, 8, 64):
        vs = _silent(vbao, gb, radius=0.5, sectors=sectors)
        assert np.all((vs[gb.valid] >= 0) & (vs[gb.valid] <= 1))


def test_float32_and_determinism(crease_view):
    gb, _, _ = crease_view
    v64 = vbao(gb, radius=0.5, seed=2)
    v32 = vbao(gb.astype(np.float32), radius=0.5, seed=2)
    assert v64.dtype == np.float64 and v32.dtype == np.float32
    assert np.array_equal(np.isnan(v32), ~gb.valid)
    d = np.abs(v32[gb.valid].astype(np.float64) - v64[gb.valid])
    # a sector flip: one sector's weight, at most pi / 32, over 3 slices
    assert d.max() <= np.pi / 32 / 3 + FLOAT32_TOL
    assert np.mean(d > FLOAT32_TOL) <= FLOAT32_FLIP_FRACTION
    a = vbao(gb, radius=0.5, seed=4)
    assert a.tobytes() == vbao(gb, radius=0.5, seed=4).tobytes()
    assert not np.array_equal(a, vbao(gb, radius=0.5, seed=5), equal_nan=True)


def test_bad_arguments(crease_view):
    gb, _, _ = crease_view
    cases = [
        (dict(radius=0), "radius"), (dict(slices=0), "slices"), (dict(steps=2.5), "steps"),
        (dict(thickness=-1), "thickness"), (dict(thickness=np.nan), "thickness"),
        (dict(thickness_scale="log"), "thickness_scale"), (dict(thickness_far=-0.1), "thickness_far"),
        (dict(weighting="cos"), "weighting"), (dict(sectors=0), "sectors"), (dict(sectors=65), "sectors"),
        (dict(sectors=16, weighting="eevee"), "sectors"), (dict(sector_rule="floor"), "sector_rule"),
        (dict(step_power=0), "step_power"), (dict(randomize="yes"), "randomize"), (dict(seed=-1), "seed"),
        (dict(fetch="cubic"), "fetch"), (dict(offscreen="wrap"), "offscreen"), (dict(noise_size=0), "noise_size"),
        (dict(step_jitter="r2"), "step_jitter"),
    ]
    for kw, match in cases:
        with pytest.raises(ValueError, match=match):
            vbao(gb, **{"radius": 0.5, **kw})
    with pytest.raises(ValueError, match="gbuffer"):
        vbao(np.zeros((4, 4)), radius=1)


def test_registered_against_its_own_references(crease_view):
    gb, _, _ = crease_view
    m, u = vo.methods.get("vbao"), vo.methods.get("vbao_uniform")
    assert (m.reference(), u.reference()) == ("ao", "ao_uniform")
    assert m.taps(3) == 2 * 3 * 3 == u.taps(3)
    np.testing.assert_array_equal(m.run(gb, 2, radius=0.5, seed=3), vbao(gb, radius=0.5, slices=2, steps=3, seed=3))
    np.testing.assert_array_equal(u.run(gb, 2, radius=0.5, seed=3),
                                  vbao(gb, radius=0.5, slices=2, steps=3, seed=3, weighting="uniform"))
    assert vo.vbao is vbao


def test_sector_weights_against_quadrature_and_the_byte_tables():
    """The sector weights against a midpoint quadrature of their integrands, and the byte
    tables that sum the open sectors of a mask against the explicit sum of those weights."""
    from types import SimpleNamespace

    from vobscure.screenspace.vbao import _LOW, _Weights

    rng = np.random.default_rng(0)
    gamma = np.concatenate([rng.uniform(-1.5, 1.5, 20), [0.0, 1e-17, -np.pi / 2, np.pi / 2]])
    S, n = 16, 4000                                   # n midpoints per sector: error ~ (pi/S/n)^2
    u = (np.arange(n) + 0.5) / n
    for weighting, f in (("cosine", lambda th, g: np.cos(th - g) * np.abs(np.sin(th))),
                         ("uniform", lambda th, g: 0.5 * np.abs(np.sin(th)))):
        w = sector_weights(gamma, S, weighting)
        for k, g in enumerate(gamma):
            edges = g - np.pi / 2 + np.pi * np.arange(S + 1) / S
            th = edges[:-1, None] + (np.pi / S) * u[None, :]
            quad = f(th, g).mean(axis=1) * (np.pi / S)
            # the midpoint rule's error on the kink of |sin| at 0: (pi / S / n)^2 x O(1)
            np.testing.assert_allclose(w[k], quad, rtol=0, atol=1e-8)
    for S in (1, 7, 32, 64):
        for weighting in ("cosine", "uniform", "bitcount") + (("eevee",) if S == 32 else ()):
            open_ = rng.random((len(gamma), S)) < 0.5
            mask = np.zeros(len(gamma), dtype=np.uint64)
            for i in range(S):
                mask |= np.where(open_[:, i], np.uint64(0), np.uint64(1) << np.uint64(i))
            assert np.all(mask <= _LOW[S])
            sl = SimpleNamespace(gamma=gamma, sin_g=np.sin(gamma), cos_g=np.cos(gamma))
            got = _Weights(S, weighting).open_weight(mask, sl)
            want = (open_ * sector_weights(gamma, S, weighting)).sum(axis=1)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)


def test_level_camera_reads_an_open_plane_open(big_slab):
    """A floor seen by a level camera has n_z = 0 in view space at every pixel; VBAO's slices
    go through the view vector, so nothing divides by n_z: the plane reads open within the
    grazing-view tolerance at 9 slices, exactly 1 under the uniform and bit-count weightings
    (no tap on a plane marks a sector), and the probe's slab reads as from a camera tilted by
    0.02 degrees."""
    means = {}
    for name, target in LEVEL_TARGETS.items():
        cam = vo.Camera.look_at(LEVEL_EYE, target, size=(64, 64), fov_y=60)
        gb = vo.render_gbuffer(big_slab, cam)
        if name == "level":
            assert np.all(gb.normal[..., 2][gb.valid] == 0.0)
        inside = _interior(gb, 0.3)
        assert inside.sum() > 1000
        for thickness in (0.1, np.inf):
            v = vbao(gb, radius=0.3, slices=9, thickness=thickness)
            assert np.max(np.abs(v[inside] - 1.0)) < GRAZING_PLANE_TOL, (name, thickness)
        for weighting in ("uniform", "bitcount"):
            w = vbao(gb, radius=0.3, weighting=weighting)
            assert np.max(np.abs(w[inside] - 1.0)) < EXACT_TOL, (name, weighting)
        small = vo.render_gbuffer(vo.scenes.slab(), cam)
        means[name] = np.nanmean(vbao(small, radius=0.3))
    assert abs(means["level"] - means["tilted"]) < TILT_MEAN_TOL


def test_float32_agrees_on_the_cornell_box():
    """The Cornell box seen head-on: walls, floor and ceiling with n_z = 0 in view space;
    float32 and float64 G-buffers agree but for sector flips (see FLOAT32_TOL)."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((64, 64)))
    g32 = gb.astype(np.float32)
    assert np.sum(gb.normal[..., 2][gb.valid] == 0.0) > 1000
    for kw in (dict(), dict(thickness=0.1), dict(weighting="uniform")):
        v64, v32 = vbao(gb, radius=0.5, **kw), vbao(g32, radius=0.5, **kw)
        assert v32.dtype == np.float32
        d = np.abs(v32[gb.valid].astype(np.float64) - v64[gb.valid])
        assert d.max() <= np.pi / 32 / 3 + FLOAT32_TOL, kw
        assert np.mean(d > FLOAT32_TOL) <= FLOAT32_FLIP_FRACTION, kw


def test_unclipped_one_slice_frames_average_to_the_integral():
    # An open plane seen obliquely is open (1). One slice per frame at a random angle is unbiased
    # only unclipped (a slice's estimate can exceed 1); clipped frames average darker.
    assert abs(one_slice_z(vo.vbao, clip=False)) < 3.29     # two-sided, false-failure rate 1e-3
    assert one_slice_z(vo.vbao, clip=True) < -5.0
