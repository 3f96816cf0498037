"""HBAO (Bavoil et al. 2008; vobscure.screenspace.hbao) on the orthographic crease: the horizon
integral converges to the closed form and to the ray-cast obscurance; a level camera (view-space
n_z = 0) reads an open plane open; float32 agrees on the Cornell box. More planes, extremes,
float32 and arguments: test_sao.py, which tests HBAO with Alchemy and SAO."""

from __future__ import annotations

import numpy as np

import vobscure as vo
from vobscure.screenspace.hbao import hbao

from analytic import crease_uniform_ao
from conftest import CREASE_RADIUS as R_CREASE

#: HBAO on the orthographic crease, 32 directions x 16 steps, angle_bias = 0, against what it
#: estimates: unattenuated, the uniformly weighted AO within R, (1 + c) / 2; attenuated by
#: W = 1 - r^2 / R^2, the uniformly weighted obscurance with rho(t) = t^2 (ray-cast, 1024
#: rays, noise 1.5e-3 RMS). Measured RMSE over 451 floor pixels 0.0080 and 0.0083 (0.0042
#: and 0.0041 at 64 x 32: the march's discretization, the horizon between taps missed, a
#: positive bias halving with N_s). 0.02 is 2.4x; the step falloff instead of t^2 gives 0.10.
HBAO_TOL = 0.02
#: Planes without the angle bias: a tap on the plane lies on the tangent plane up to the depth
#: buffer's rounding (Embree's float32 hits, relative 6e-8, amplified by z / |D| ~ 100), so its
#: rise is of either sign and tiny. Measured largest 1 - V on the level and tilted views of the
#: slab: 5e-6; 1e-4, test_sao.py's bound for planes, is 20x that. With the default bias of
#: 10 degrees every such rise is far below it and a plane reads exactly 1.
PLANE_NOISE_TOL = 1e-4
#: float32 against float64 per pixel, as in test_sao.py: the taps' points come from float32
#: depths (relative 6e-8) amplified by z / |D| ~ 100 in sin h and sin t. Measured max on the
#: Cornell box, 64 x 64, R = 0.5: 1.6e-6; 2e-5 (test_sao.py's bound) is 12x that.
FLOAT32_TOL = 2e-5

#: A camera 1 unit above the slab's top (y = 0) looking level, and the same camera tilted down
#: by atan(0.001 / 3) = 0.02 degrees: the level one sees the plane with view-space n_z = 0 at
#: every pixel, the tilted one with n_z = -3.3e-4.
LEVEL_EYE = (0.0, 1.0, 3.0)
LEVEL_TARGETS = {"level": (0.0, 1.0, 0.0), "tilted": (0.0, 0.999, 0.0)}


def test_hbao_converges_on_the_crease(crease, crease_view):
    """Unattenuated, HBAO's horizon integral is the uniformly weighted AO within R, exact on
    the orthographic crease as directions and steps grow; attenuated, the uniformly weighted
    obscurance with rho(t) = t^2 (a callable falloff of vobscure.obscurance)."""
    scene = crease
    gb, floor, _ = crease_view
    floor = floor & (np.arange(floor.size).reshape(floor.shape) % 3 == 0)
    c = gb.world_position[floor][:, 0] / R_CREASE
    rmse = []
    for nd, ns in ((4, 2), (8, 4), (32, 16)):
        u = hbao(gb, radius=R_CREASE, directions=nd, steps=ns, angle_bias=0.0, attenuation=False)[floor]
        rmse.append(np.sqrt(np.mean((u - crease_uniform_ao(c)) ** 2)))
    assert rmse[2] < rmse[1] < rmse[0] and rmse[2] < HBAO_TOL, rmse
    ref = vo.obscurance(scene, gb.world_position[floor], gb.world_normal[floor], radius=R_CREASE,
                        falloff=lambda t: t * t, weighting="uniform", rays=1024, seed=1).value
    v = hbao(gb, radius=R_CREASE, directions=32, steps=16, angle_bias=0.0)[floor]
    assert np.sqrt(np.mean((v - ref) ** 2)) < HBAO_TOL



def test_level_camera_reads_an_open_plane_open():
    """A floor seen by a level camera has n_z = 0 in view space: the tangent of a tap's slice
    must not divide by n_z (its sign would then follow rounding noise and flip t between
    -pi/2 and pi/2). The tangent from the tap's view ray and the tangent plane reads the plane
    open, exactly as from a camera tilted by 0.02 degrees."""
    scene = vo.scenes.slab()
    means = {}
    for name, target in LEVEL_TARGETS.items():
        gb = vo.render_gbuffer(scene, vo.Camera.look_at(LEVEL_EYE, target, size=(64, 64), fov_y=60))
        nz = gb.normal[..., 2][gb.valid]
        assert gb.valid.sum() > 1000
        assert np.all(nz == 0.0) if name == "level" else np.all(nz < -1e-4)
        v = hbao(gb, radius=0.3)
        assert np.all(v[gb.valid] == 1.0), (name, np.nanmean(v), np.nanmin(v))
        for kw in (dict(), dict(directions=16, steps=8, randomize=False), dict(offscreen="open")):
            v0 = hbao(gb, radius=0.3, angle_bias=0.0, **kw)[gb.valid]
            assert np.min(v0) > 1.0 - PLANE_NOISE_TOL, (name, kw, np.min(v0))
        means[name] = np.mean(v0)
    assert abs(means["level"] - means["tilted"]) < PLANE_NOISE_TOL


def test_float32_agrees_on_the_cornell_box():
    """The Cornell box seen head-on: its walls, floor and ceiling have n_z = 0 in view space
    (rounding decides the sign of the tangent's slope there unless the tangent is built without
    dividing by n_z); float32 and float64 G-buffers give the same image within float32's
    rounding."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((64, 64)))
    assert np.sum(gb.normal[..., 2][gb.valid] == 0.0) > 1000
    for radius in (0.1, 0.5):
        v64 = hbao(gb, radius=radius)
        v32 = hbao(gb.astype(np.float32), radius=radius)
        assert v64.dtype == np.float64 and v32.dtype == np.float32
        assert np.array_equal(np.isnan(v32), ~gb.valid)
        np.testing.assert_allclose(v32[gb.valid].astype(np.float64), v64[gb.valid], rtol=0, atol=FLOAT32_TOL)
        # the walls meet the floor and the boxes stand on it: not a trivially open image
        assert np.mean(v64[gb.valid]) < 0.995
