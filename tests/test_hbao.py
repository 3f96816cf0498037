"""HBAO (Bavoil et al. 2008; vobscure.screenspace.hbao) on the orthographic crease: the horizon
integral converges to the closed form and to the ray-cast obscurance. Planes, extremes, float32
and arguments: test_sao.py, which tests HBAO with Alchemy and SAO."""

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

