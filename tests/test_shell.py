"""The shell reference (world-space VO of surfaces of a stated thickness, for open scenes) against
closed forms and an independent Monte Carlo, and its place in ``vobscure compare``."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.experiments import compare as cmp

from analytic import slab_shell_vo
from conftest import assert_unbiased, t_threshold

R = 0.5
GROUPS = 16
DF = GROUPS - 1
SAMPLES = 4096


def _ortho(forward, size=(8, 8)):
    eye = -5.0 * np.asarray(forward, float)
    up = (0, 0, -1) if abs(forward[1]) > 0.99 else (0, 1, 0)
    return vo.Camera.look_at(eye, (0, 0, 0), up, size=size, ortho_height=2.0)


@pytest.mark.parametrize("thickness", [0.1, 0.3, 5.0])
def test_a_plane_seen_from_above_is_solid_only_a_thickness_deep(slab, thickness):
    # orthographic, looking straight down: the layer below the plane that is solid is `thickness` deep
    e = vo.volumetric_obscurance(slab, [[0, 0, 0]], radius=R, samples=SAMPLES, thickness=thickness,
                                 camera=_ortho((0, -1, 0)), groups=GROUPS, seed=3)
    assert_unbiased(e, [slab_shell_vo(thickness, R)], df=DF)


def test_the_layer_is_as_thick_from_any_direction(slab):
    # the thickness is measured along the surface's normal: a view at 50 degrees to it sees the
    # same layer as the view straight down (a thickness along the view ray would thin it by cos)
    forward = np.array([0.0, -np.cos(np.radians(50)), -np.sin(np.radians(50))])
    t = 0.3
    e = vo.volumetric_obscurance(slab, [[0, 0, 0]], radius=R, samples=SAMPLES, thickness=t,
                                 camera=_ortho(forward), groups=GROUPS, seed=4)
    assert_unbiased(e, [slab_shell_vo(t, R)], df=DF)


def test_perspective_agrees_with_an_independent_monte_carlo(slab):
    """A point of the plane y = 0 far off the optical axis, seen by a perspective camera: the
    occupancy is written here in closed form per sample, and the two means are compared by a
    z-test."""
    # far off the optical axis and every point of its ball in front of the eye
    cam = vo.Camera.look_at((0, 1.0, 0), (0, 1.0, -5), size=(8, 8), fov_y=60)
    p = np.array([1.0, 0.0, -0.8])
    t = 0.35
    e = vo.volumetric_obscurance(slab, [p], radius=R, samples=SAMPLES, thickness=t, camera=cam,
                                 groups=GROUPS, seed=5)
    rng = np.random.default_rng(11)
    n = 400_000
    x = rng.normal(size=(n, 3))
    x *= (R * rng.random(n) ** (1 / 3) / np.linalg.norm(x, axis=1))[:, None]
    x += p
    eye, fwd = np.asarray(cam.eye), np.asarray(cam.forward)
    # the ray from a point below the plane y = 0 to the eye (above it) meets the plane first (the
    # slab's bottom face is 1 below, out of the ball); the point's distance from the plane
    # along its normal is -y: occupied when below the plane by at most t
    occupied = (x[:, 1] < 0) & (-x[:, 1] <= t)
    assert np.all(x[:, 1] > -1.0) and eye[1] > 0
    mc = 1.0 - occupied.mean()
    mc_se = occupied.std() / np.sqrt(n)
    z = (e.value[0] - mc) / np.hypot(e.stderr[0], mc_se)
    assert abs(z) < t_threshold(DF), (e.value, e.stderr, mc, mc_se)


def test_on_a_closed_slab_seen_from_above_a_deep_shell_is_the_solid(slab):
    cam = vo.Camera.look_at((0, 5, 0.0), (0, 0, 0), (0, 0, -1), size=(6, 6), ortho_height=4.0)
    gb = vo.render_gbuffer(slab, cam)
    solid = vo.ground_truth(slab, gb, quantity="volumetric", radius=R, samples=512, seed=2)
    shell = vo.ground_truth(slab, gb, quantity="volumetric", radius=R, samples=512, seed=2, thickness=100.0)
    v = gb.valid
    diff = shell.value[v] - solid.value[v]
    se = np.hypot(shell.stderr[v], solid.stderr[v])
    assert np.all(np.abs(diff) <= t_threshold(DF, tests=v.sum()) * np.maximum(se, 1e-12))
    assert abs(np.mean(solid.value[v]) - 0.5) < 0.02       # the ball is half solid on the slab


def test_open_scene_needs_the_shell_and_says_so():
    quad = trimesh.Trimesh([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    sc = vo.Scene({"floor": quad})
    gb = vo.render_gbuffer(sc, vo.Camera.look_at((0, 2, 2), (0, 0, 0), size=(8, 8), fov_y=40))
    with pytest.raises(ValueError, match="shell"):
        vo.ground_truth(sc, gb, quantity="volumetric", radius=0.2, samples=64)
    e = vo.ground_truth(sc, gb, quantity="volumetric", radius=0.2, samples=64, thickness=0.2)
    assert np.all(np.isfinite(e.value[gb.valid]))


def test_bad_shell_arguments_are_named(slab):
    gb = vo.render_gbuffer(slab, vo.Camera.look_at((0, 2, 2), (0, 0, 0), size=(4, 4), fov_y=40))
    with pytest.raises(ValueError, match="thickness"):
        vo.ground_truth(slab, gb, quantity="ao", radius=0.2, rays=8, thickness=0.1)
    with pytest.raises(ValueError, match="thickness"):
        vo.ground_truth(slab, gb, quantity="volumetric", radius=0.2, samples=8, thickness=-1.0)
    with pytest.raises(ValueError, match="camera"):
        vo.volumetric_obscurance(slab, [[0, 0, 0]], radius=0.2, samples=8, thickness=0.1)


def test_shell_reference_takes_the_estimates_thickness_or_the_radius():
    shell = vo.references.get("shell")
    common = dict(radius=0.5, seed=0, volume_samples=64, falloff="constant", normal_clamp=False)
    assert shell.arguments(thickness=None, **common)["thickness"] == 0.5 * vo.references.SHELL_THICKNESS
    assert shell.arguments(thickness=0.2, **common)["thickness"] == 0.2
    assert vo.references.usable("volumetric", vo.scenes.slab()) == "volumetric"
    assert vo.references.usable("volumetric", vo.scenes.leaf_cloud()) == "shell"
    assert vo.references.usable("ao", vo.scenes.leaf_cloud()) == "ao"


def test_compare_on_an_open_scene_scores_vo_against_the_shell_and_names_the_open_meshes(tmp_path):
    quad = trimesh.Trimesh([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], [[0, 2, 1], [0, 3, 2]])
    box = trimesh.creation.box(extents=(0.6, 0.6, 0.6))
    box.apply_translation((0, 0.3, 0))
    sc = vo.Scene({"floor": quad, "box": box}, view=dict(eye=(1.5, 1.5, 2), target=(0, 0, 0), fov_y=50))
    res = cmp.compare(sc, size=(24, 24), methods="line:5,gtao:2", quick=True, cache=False, out=tmp_path,
                      suggest=False, radii=0.3)
    rows = {r["label"]: r for r in res.rows}
    assert rows["line:5"]["own_reference"] == "shell" and rows["gtao:2"]["own_reference"] == "ao"
    assert "volumetric" not in res.provenance["references"]
    assert res.provenance["missing_references"] == {"volumetric": "shell"}
    assert res.provenance["shell_thickness"] == {"0.3": 0.3}
    note = next(t for t in res.summary["text"] if t.startswith("No 'volumetric' reference"))
    assert "1 of 2 mesh(es) are open or alpha-tested with holes (floor)" in note and "'shell'" in note
    assert res.summary["missing_references"]["volumetric"]["open_meshes"] == ["floor"]
    # the decomposition runs through the shell
    assert np.isfinite(rows["line:5"]["screen_error_rmse"])
    assert (tmp_path / "gallery.png").exists()
    with pytest.raises(ValueError, match=r"open \(floor\).*'shell'.*--allow-open"):
        cmp.compare(sc, size=(8, 8), methods="line:5", quick=True, cache=False, write=False,
                    references=("volumetric",), radii=0.3)
    forced = cmp.compare(sc, size=(8, 8), methods="line:5", quick=True, cache=False, write=False,
                         radii=0.3, allow_open=True, suggest=False)
    assert "volumetric" in forced.provenance["references"] and forced.rows[0]["own_reference"] == "volumetric"


def test_gallery_panels_use_the_verdicts_reference():
    available = {"screen": 0, "shell": 0, "ao": 0}
    assert cmp.panel_reference({"own_reference": "shell"}, available) == ("shell", True)
    assert cmp.panel_reference({"own_reference": "ao"}, available) == ("ao", True)
    assert cmp.panel_reference({"own_reference": None}, available) == ("screen", False)

