"""Clear errors, and no silent wrong results, at the public API's edges.

Every test here is a hostile call: an argument of the wrong kind, an input at the limits of
float64, or data that do not belong together. Each must end in an error that names the
argument the caller passed, a warning that says what went wrong, or the right answer.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure import trees
from vobscure.convert import NormalsRenormalizedWarning
from vobscure.groundtruth import SmallRadiusWarning
from vobscure.objectspace import disks as D, sh
from vobscure.objectspace.spheres import sphere_set, sphere_set_ao
from vobscure.trees.poisson import MAX_QUADRATURE

#: Relative agreement of two algebraically different forms of one closed form in float64.
CLOSED_FORM_RTOL = 1e-12
#: The tree's cost estimate is a fit over icospheres; it must stay within this factor of the
#: terms the traversal really evaluates, or the warning's minutes mean nothing.
COST_ESTIMATE_FACTOR = 2.0


def _camera(n=8):
    return vo.Camera.look_at((0, 1, 3.5), (0, 1, 0), size=(n, n), fov_y=45.0)


@pytest.fixture(scope="module")
def cornell():
    scene = vo.scenes.cornell_box()
    return scene, vo.render_gbuffer(scene, _camera())


# ----------------------------------------------------------------------------- booleans
def _bool_calls(cornell):
    scene, gb = cornell
    p, n = np.zeros((1, 3)), np.array([[0.0, 1.0, 0.0]])
    slab = vo.scenes.slab()
    return {
        "repair_normals": lambda v: vo.GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera, repair_normals=v),
        "normal_clamp (vo_point)": lambda v: vo.vo_point(gb, radius=0.3, normal_clamp=v),
        "normal_clamp (vo_line)": lambda v: vo.vo_line(gb, radius=0.3, normal_clamp=v),
        "normal_clamp (vo_area)": lambda v: vo.vo_area(gb, radius=0.3, normal_clamp=v),
        "normal_clamp (vo_reference)": lambda v: vo.vo_reference(gb, radius=0.3, samples=16, normal_clamp=v),
        "randomize (vo_point)": lambda v: vo.vo_point(gb, radius=0.3, randomize=v),
        "randomize (gtao)": lambda v: vo.gtao(gb, radius=0.3, randomize=v),
        "clip (gtao)": lambda v: vo.gtao(gb, radius=0.3, clip=v),
        "attenuation (hbao)": lambda v: vo.hbao(gb, radius=0.3, attenuation=v),
        "prefilter (vo_area)": lambda v: vo.vo_area(gb, radius=0.3, prefilter=v),
        "normal_clamp (ground_truth)": lambda v: vo.ground_truth(scene, gb, quantity="volumetric", radius=0.3,
                                                                 samples=8, normal_clamp=v),
        "progress (ground_truth)": lambda v: vo.ground_truth(scene, gb, rays=8, progress=v),
        "allow_open (volumetric_obscurance)": lambda v: vo.volumetric_obscurance(slab, p, radius=0.3, samples=8,
                                                                                 allow_open=v),
        "bent_normals (ambient_occlusion)": lambda v: vo.ambient_occlusion(slab, p, n, rays=8, bent_normals=v),
        "average (bunnell)": lambda v: D.bunnell(vo.scenes.get("crease"), average=v),
        "progress (bunnell_gbuffer)": lambda v: D.bunnell_gbuffer(gb, scene=scene, progress=v),
        "clip (sphere_set_ao)": lambda v: sphere_set_ao(p, n, [[0.0, 2.0, 0.0]], [1.0], clip=v),
    }


BOOL_CASES = ["repair_normals", "normal_clamp (vo_point)", "normal_clamp (vo_line)", "normal_clamp (vo_area)",
              "normal_clamp (vo_reference)", "randomize (vo_point)", "randomize (gtao)", "clip (gtao)",
              "attenuation (hbao)", "prefilter (vo_area)", "normal_clamp (ground_truth)", "progress (ground_truth)",
              "allow_open (volumetric_obscurance)", "bent_normals (ambient_occlusion)", "average (bunnell)",
              "progress (bunnell_gbuffer)", "clip (sphere_set_ao)"]


@pytest.mark.parametrize("case", BOOL_CASES)
def test_truthy_strings_are_not_booleans(cornell, case):
    """A string such as "no" is truthy: taken as a bool it would silently mean True."""
    call = _bool_calls(cornell)[case]
    name = case.split(" ")[0]
    with pytest.raises(ValueError, match=rf"{name} must be True or False, got 'no'"):
        call("no")


def test_check_bool_accepts_numpy_bools():
    assert vo._validate.check_bool(np.bool_(True), "x") is True
    for bad in ("False", 0, 1, None, 1.0):
        with pytest.raises(ValueError, match="x must be True or False"):
            vo._validate.check_bool(bad, "x")


# ----------------------------------------------------------------------------- trees
def test_grass_of_empty_inputs_is_empty_like_the_other_models():
    assert trees.grass_visibility([], 1.0, []).shape == (0,)
    assert trees.grass_visibility(np.zeros((0, 3)), 1.0, np.zeros((0, 3))).shape == (0, 3)
    empty = trees.canopy_visibility(np.zeros((0, 3)), np.zeros((0, 3)), trees.Sphere((0, 0, 0), 1.0), density=1.0)
    assert empty.shape == (0,)


@pytest.mark.parametrize("h", [1.0, 1e300, 1e308, np.finfo(np.float64).max])
def test_grass_at_the_tip_is_open_at_any_scale(h):
    """Eq. 9 at P_z = h, facing up: V = 1 whatever h (h / h, never 2 h, which overflows)."""
    assert trees.grass_visibility([h], h, [1.0])[0] == 1.0
    assert trees.grass_visibility([h / 2], h, [0.0])[0] == 0.25


def test_shell_volume_must_fit_float64():
    with pytest.raises(ValueError, match=r"radius 1e\+300 gives a volume of inf"):
        trees.Sphere((0, 0, 0), 1e300)
    with pytest.raises(ValueError, match="radius .* gives a volume of 0"):
        trees.Sphere((0, 0, 0), 1e-200)
    with pytest.raises(ValueError, match="radii .* gives a volume of inf"):
        trees.Ellipsoid((0, 0, 0), (1e200, 1e200, 1.0))
    trees.Sphere((0, 0, 0), 1e100)                          # large but representable: accepted


@pytest.mark.parametrize("L", [1e3, 1e50, 1e150, 1e155, 1e200, 1e300])
def test_canopy_far_sideways_point_against_closed_form(L):
    """Unit sphere, x = (L, 0, 0), n = (-1, 1, 0)/sqrt 2: the whole sphere is on the normal's
    side (h = 2R), d^2 = L^2 / 2, so f = h^2 / (d^2 + h^2) = 8 / (L^2 + 8), V_cap = 4 pi / 3.
    Here f is written as (8 / L) / L / (1 + (8 / L) / L), which never squares L."""
    density = 1.0
    q = 8.0 / L / L
    expected = math.exp(-density * (q / (1.0 + q)) * 4.0 * math.pi / 3.0)   # Hegeman 2006, Eqs. 4-6
    n = np.array([[-1.0, 1.0, 0.0]]) / math.sqrt(2.0)
    V = trees.canopy_visibility([[L, 0.0, 0.0]], n, trees.Sphere((0, 0, 0), 1.0), density=density)
    np.testing.assert_allclose(V[0], expected, rtol=CLOSED_FORM_RTOL)


def test_canopy_points_whose_unit_coordinates_overflow_are_an_error():
    with pytest.raises(ValueError, match="unit frame overflow"):
        trees.canopy_visibility([[1e308, 0, 0]], [[0, 1, 0]], trees.Sphere((-1e308, 0, 0), 1.0), density=1.0)


def test_fit_references_must_be_visibilities():
    rng = np.random.default_rng(0)
    x, n = rng.uniform(-0.5, 0.5, (20, 3)), rng.normal(size=(20, 3))
    s = trees.Sphere((0, 0, 0), 1.0)
    with pytest.raises(ValueError, match=r"reference must be visibilities in \[0, 1\].*20 value"):
        trees.fit_density(x, n, s, -np.ones(20))
    with pytest.raises(ValueError, match=r"reference must be visibilities in \[0, 1\].*1 value"):
        trees.fit_reeves_blau(x, s, np.r_[np.full(19, 0.5), 1.5])
    # noise of a few hundredths past 0 or 1 is a noisy visibility, not an error
    V = trees.canopy_visibility(x, n, s, density=0.8)
    trees.fit_density(x, n, s, np.clip(V, 0, 1) + np.where(np.arange(20) % 2, 0.05, -0.05))


def test_quadrature_beyond_the_stated_limit_is_an_error():
    s = trees.Sphere((0, 2, 0), 1.0)
    with pytest.raises(ValueError, match=r"quadrature must be at most MAX_QUADRATURE = 1024.*74.5 GiB"):
        trees.occluder_visibility([[0, 0, 0]], [[0, 1, 0]], [s], model="porous", sigma=1.0, quadrature=10 ** 5)
    with pytest.raises(ValueError, match="quadrature must be at most"):
        trees.sphere_transmittance([0, 0, 0], [0, 1, 0], s, extinction=1.0, quadrature=MAX_QUADRATURE + 1)
    with pytest.raises(ValueError, match="nodes must be at most"):
        trees.poisson_quadrature([0, 0, 0], [0, 1, 0], s, extinction=1.0, nodes=MAX_QUADRATURE + 1)


# ----------------------------------------------------------------------------- spherical harmonics
def test_sh_index_covers_each_band_once():
    indices = [sh.sh_index(l, m) for l in range(5) for m in range(-l, l + 1)]
    assert indices == list(range(25))
    with pytest.raises(ValueError, match=r"\|m\| <= l = 2, got 3"):
        sh.sh_index(2, 3)
    with pytest.raises(ValueError, match="l must be an integer >= 0"):
        sh.sh_index(-1, 0)


@pytest.mark.parametrize("d", [[0.0, 0.0, 0.0], [np.nan, 0.0, 1.0], [0.0, 0.0, 2.0]])
def test_sh_directions_must_be_unit(d):
    with pytest.raises(ValueError, match="directions must be unit vectors"):
        sh.sh_basis(d)
    with pytest.raises(ValueError, match="direction must be unit vectors"):
        sh.rotate_zonal(sh.cap_zonal(0.3, order=3), d)


def test_sh_log_outside_its_domain_is_an_error():
    with pytest.raises(ValueError, match="sh_log needs g positive somewhere"):
        sh.sh_log(np.zeros(16))
    g = np.zeros(16)
    g[0] = -1.0                                             # a negative constant
    with pytest.raises(ValueError, match="sh_log needs g positive somewhere"):
        sh.sh_log(g)


@pytest.mark.parametrize("method", ["hybrid", "ol", "taylor", "exact"])
def test_sh_exp_overflow_is_an_error_and_deep_shadow_is_zero(method):
    f = np.zeros(16)
    f[0] = 1e4                                              # exp(1e4 / sqrt(4 pi)) overflows
    with pytest.raises(ValueError, match="overflows float64"):
        sh.sh_exp(f, method=method)
    f[0] = -1e4                                             # a log-visibility: exp underflows to 0
    out = sh.sh_exp(f, method=method)
    assert np.all(out == 0.0)


# ----------------------------------------------------------------------------- methods, io
@pytest.mark.parametrize("samples", ["²", "٣", "1_0", "+3"])
def test_methods_samples_are_ascii_digits(samples):
    with pytest.raises(ValueError, match=re.escape(f"--methods entry 'line:{samples}'") + ".*ASCII digits"):
        vo.methods.parse(f"line:{samples}")


def test_reader_arguments_are_named(tmp_path):
    from PIL import Image

    cam = vo.Camera.look_at((0, 1, 3), (0, 0, 0), size=(4, 4), fov_y=45.0)
    npz = tmp_path / "g.npz"
    np.savez(npz, depth=np.ones((4, 4)), normal=np.tile([0, 0, -1.0], (4, 4, 1)))
    with pytest.raises(ValueError, match="normal_channels must be None .* got 5"):
        vo.io.read_gbuffer(npz, camera=cam, normal_channels=5)
    png = tmp_path / "d.png"
    Image.fromarray(np.full((4, 4), 100, np.uint16)).save(png)
    with pytest.raises(ValueError, match="depth_scale must be a finite number > 0.*got 'x'"):
        vo.io.read_gbuffer(png, camera=cam, depth_scale="x")
    pfm = tmp_path / "bad.pfm"
    pfm.write_bytes(b"Pf\n2 1\ne-.\n" + bytes(8))
    with pytest.raises(ValueError, match=r"bad\.pfm: the PFM scale line must be a number"):
        vo.io.read_pfm(pfm)


@pytest.mark.parametrize("suffix", [".png", ".exr", ".npy", ".pfm"])
def test_write_image_of_no_pixels_is_an_error(tmp_path, suffix):
    with pytest.raises(ValueError, match="empty 0 x 0 image"):
        vo.io.write_image(tmp_path / f"e{suffix}", np.zeros((0, 0)))
    assert not (tmp_path / f"e{suffix}").exists()


def test_sphere_set_names_k_not_samples():
    with pytest.raises(ValueError, match="k = 1000000 spheres .* samples = 20000"):
        sphere_set(vo.scenes.cornell_box(), 10 ** 6, meshes=["tall_box"])


# ----------------------------------------------------------------------------- G-buffers, ground truth
def test_astype_refuses_depths_beyond_float32(cornell):
    _, gb = cornell
    far = vo.GBuffer.from_arrays(np.where(gb.valid, 1e39, np.inf), gb.normal, camera=gb.camera)
    with pytest.raises(ValueError, match=r"largest depth of a covered pixel, 1e\+39, exceeds float32"):
        far.astype(np.float32)
    assert far.astype(np.float64).dtype == np.float64
    with pytest.raises(ValueError, match="dtype must be a float dtype"):
        gb.astype(np.int32)
    assert np.array_equal(gb.astype(np.float32).valid, gb.valid)


def test_from_arrays_long_normals_are_renormalized_not_called_zero(cornell):
    _, gb = cornell
    with pytest.warns(NormalsRenormalizedWarning, match="largest difference 1e\\+200"):
        long = vo.GBuffer.from_arrays(gb.depth, gb.normal * 1e200, camera=gb.camera)
    np.testing.assert_allclose(long.normal[gb.valid], gb.normal[gb.valid], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match=r"\d+ of length <= 1e-06, 0 with a NaN or inf"):
        vo.GBuffer.from_arrays(gb.depth, gb.normal * 1e-200, camera=gb.camera)


def test_ground_truth_refuses_a_gbuffer_of_another_scene(cornell):
    _, gb = cornell
    with pytest.raises(ValueError, match="gbuffer does not belong to this scene.*primitive indices"):
        vo.ground_truth(vo.scenes.slab(), gb, rays=8)
    # the same triangle count, moved: the indices fit, the hit points do not
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    moved = box.copy()
    moved.apply_translation((0.0, 0.25, 0.0))
    cam = vo.Camera.look_at((1.5, 2.0, 2.5), (0, 0, 0), size=(8, 8), fov_y=45.0)
    gb_box = vo.render_gbuffer(vo.scenes.as_scene(box), cam)
    with pytest.raises(ValueError, match="gbuffer does not belong to this scene.*lie off their triangles"):
        vo.ground_truth(vo.scenes.as_scene(moved), gb_box, rays=8)
    vo.ground_truth(vo.scenes.as_scene(box), gb_box, rays=8)      # its own scene: accepted


def test_volumetric_radius_below_the_ray_offset_warns(cornell):
    scene, gb = cornell
    offset = scene.tracer.offset
    with pytest.warns(SmallRadiusWarning, match="below the tracer's ray offset"):
        vo.ground_truth(scene, gb, quantity="volumetric", radius=1e-9, samples=8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        vo.ground_truth(scene, gb, quantity="volumetric", radius=2 * offset, samples=8)


# ----------------------------------------------------------------------------- Bunnell's cost
def test_bunnell_cost_estimate_tracks_the_terms_evaluated():
    """The tree's estimate (terms per receiver) against the count of the real traversal."""
    for sub in (3, 4):
        mesh = trimesh.creation.icosphere(subdivisions=sub)
        k = len(mesh.vertices)
        counted = D.shadow_evaluations(mesh)
        estimated = D.estimated_seconds(k, 0, passes=2) / D.SECONDS_PER_TERM
        assert 1 / COST_ESTIMATE_FACTOR < estimated / counted < COST_ESTIMATE_FACTOR, (k, counted, estimated)
    assert D.estimated_seconds(100, 10, passes=3, hierarchy=False) == pytest.approx(
        (2 * 100 + 10) * 100 * D.SECONDS_PER_TERM)


def test_bunnell_warns_before_long_work_and_progress_changes_nothing(cornell, monkeypatch):
    scene, gb = cornell
    quiet = D.bunnell_gbuffer(gb, scene=vo.scenes.cornell_box())
    monkeypatch.setattr(D, "COST_WARN_SECONDS", 0.0)
    with pytest.warns(D.CostWarning, match=r"about .* minutes"):
        loud = D.bunnell_gbuffer(gb, scene=vo.scenes.cornell_box(), progress=True)
    assert np.array_equal(quiet, loud, equal_nan=True)
