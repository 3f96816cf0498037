"""The method registry (vobscure.methods): names and errors, configuration parsing, the cost
model checked against the taps the estimators really make (counted by instrumenting the
depth fetch), the quantity -> reference mapping, and registering a new method that then runs
in a sweep and in `compare`."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure import methods
from vobscure.screenspace import _common, area

#: Slab seen from above at an angle: every pixel covered, no tap off screen.
CAM = vo.Camera.look_at((0.4, 2.0, 1.2), (0.0, 0.0, 0.0), size=(12, 10), fov_y=40.0)


@pytest.fixture(scope="module")
def gb():
    return vo.render_gbuffer(vo.scenes.slab(), CAM)


def test_names_and_unknown_name_lists_them():
    vegetation = ("hegeman", "hegeman_ellipsoid", "hegeman_multishell", "reeves_blau", "poisson")
    baselines = ("gtao", "hbao", "alchemy", "sao")
    object_space = ("bunnell", "ren")
    assert methods.names() == ("point", "line", "area", "reference") + baselines + vegetation + object_space
    assert methods.names(include_references=False) == ("point", "line", "area") + baselines + vegetation + \
        object_space
    with pytest.raises(ValueError, match="unknown method 'ssao'; expected one of point, line, area, reference, gtao"):
        methods.get("ssao")


@pytest.mark.parametrize("spec, labels", [
    ("line:9", ["line:9"]),
    ("point:12, line:5 ,area:1", ["point:12", "line:5", "area:1"]),
    ("line,point", ["line:9", "point:12"]),                       # default sample counts
    ("point:12:nearest,point:12:bilinear", ["point:12:nearest", "point:12"]),
])
def test_parse(spec, labels):
    assert [c.label for c in methods.parse(spec)] == labels


@pytest.mark.parametrize("spec, match", [
    ("", "at least one"), ("line:x", "NAME\\[:SAMPLES"), ("cone:3", "unknown method 'cone'"),
    ("line:0", "samples"), ("line:5,line:5", "twice"), ("point:12:cubic", "fetch"),
])
def test_parse_errors(spec, match):
    with pytest.raises(ValueError, match=match):
        methods.parse(spec)


def test_quantity_and_reference():
    for name in ("point", "line", "area", "reference"):
        m = methods.get(name)
        assert m.quantity(False) == "ball VO" and m.quantity(True) == "half-ball VO"
        assert m.reference(False) == m.reference(True) == "volumetric"
    assert methods.QUANTITIES["cosine AO"].reference == "ao"
    assert methods.QUANTITIES["half-ball VO"].normal_clamp is True


def _count(monkeypatch, owner, name, size_of):
    """Wrap owner.name so that every call adds size_of(args, kwargs) to the returned list."""
    calls = []
    real = getattr(owner, name)

    def counting(*args, **kwargs):
        calls.append(size_of(args, kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, counting)
    return calls


@pytest.mark.parametrize("samples", [6, 12, 13, 33])
def test_point_taps_are_the_fetches_vo_point_makes(gb, monkeypatch, samples):
    calls = _count(monkeypatch, _common, "fetch_depth", lambda a, k: np.size(a[1]))
    vo.vo_point(gb, radius=0.2, samples=samples)
    assert sum(calls) / gb.valid.sum() == methods.get("point").taps(samples)


@pytest.mark.parametrize("samples", [3, 5, 9])
def test_line_taps_are_the_fetches_vo_line_makes(gb, monkeypatch, samples):
    calls = _count(monkeypatch, _common, "nearest_taps", lambda a, k: len(a[1]))
    vo.vo_line(gb, radius=0.2, samples=samples)
    assert sum(calls) / gb.valid.sum() == methods.get("line").taps(samples) == samples


@pytest.mark.parametrize("samples", [1, 3])
def test_area_taps_are_the_lookups_vo_area_makes(gb, monkeypatch, samples):
    calls = _count(monkeypatch, area.MomentPyramid, "lookup", lambda a, k: np.size(a[1]))
    vo.vo_area(gb, radius=0.2, samples=samples)
    assert sum(calls) / gb.valid.sum() == methods.get("area").taps(samples) == samples


def test_texels_follow_the_fetch():
    point, line, ar = (methods.get(n) for n in ("point", "line", "area"))
    assert point.texels(33) == 4 * 32 and point.texels(33, "nearest") == 32
    assert line.texels(9) == 9 and line.texels(9, "bilinear") == 36
    assert ar.texels(1) == 18 and ar.texels(1, "trilinear") == 8
    assert methods.Config("point", 12, fetch="nearest").texels == 12


def test_config_runs_the_function_with_its_fetch(gb):
    got = methods.Config("point", 12, fetch="nearest").run(gb, radius=0.2, seed=3)
    want = vo.vo_point(gb, radius=0.2, samples=12, fetch="nearest", seed=3)
    np.testing.assert_array_equal(got, want)
    area_trilinear = methods.Config("area", 1, fetch="trilinear").run(gb, radius=0.2)
    np.testing.assert_array_equal(area_trilinear, vo.vo_area(gb, radius=0.2, reconstruction="trilinear"))


def test_register_validates_and_refuses_duplicates():
    with pytest.raises(ValueError, match="already registered"):
        methods.register(methods.Method("line", vo.vo_line, default_samples=9, fetch="nearest"))
    with pytest.raises(ValueError, match="fetch must be one of"):
        methods.Method("x", vo.vo_line, default_samples=9, fetch="cubic")
    with pytest.raises(ValueError, match="callable"):
        methods.Method("x", None, default_samples=9, fetch="nearest")
    with pytest.raises(ValueError, match="takes a vobscure.methods.Method"):
        methods.register("line")


def test_a_registered_method_runs_in_compare():
    calls = []

    def vo_twice_as_open(gbuffer, *, radius, samples=4, **options):
        calls.append(samples)
        v = vo.vo_line(gbuffer, radius=radius, samples=5, **options)
        return np.minimum(1.0, 2.0 * v)

    methods.register(methods.Method("twice", vo_twice_as_open, default_samples=4, fetch="nearest",
                                    taps=lambda n: 5, summary="test method"))
    try:
        res = vo.experiments.compare.compare("slab", size=(12, 12), methods="twice:4,line:5",
                                             references=("screen",), quick=True, cache=False,
                                             progress=False, write=False, suggest=False)
    finally:
        methods.unregister("twice")
    assert "twice" not in methods.names()
    rows = {r["label"]: r for r in res.rows}
    assert calls and set(calls) == {4}
    assert rows["twice:4"]["taps_per_pixel"] == 5 and rows["twice:4"]["texels_per_pixel"] == 5
    # its row measures its own image: min(1, 2 x lines 5), against the same reference
    radius = rows["line:5"]["radius"]
    line, twice = res.images[(radius, "line:5")], res.images[(radius, "twice:4")]
    np.testing.assert_array_equal(twice, np.minimum(1.0, 2.0 * line))
    assert rows["twice:4"]["screen_bias"] - rows["line:5"]["screen_bias"] == pytest.approx(
        float(np.nanmean(twice - line)), abs=1e-12)
    assert np.nanmean(twice - line) > 0.3
    for name in ("hegeman", "hegeman_ellipsoid", "hegeman_multishell", "reeves_blau"):
        m = methods.get(name)
        assert m.quantity(True) == "sky visibility" and m.reference() == "sky"
        assert m.taps(1) == 0 and m.texels(1) == 0 and m.needs_scene


# --------------------------------------------------------------------------- vegetation models
def test_hegeman_per_pixel_is_the_canopy_model_at_the_pixels():
    from vobscure import trees
    from vobscure.trees.pixels import canopy_shell, scene_density

    scene = vo.scenes.get("leaf_cloud")
    gb = vo.render_gbuffer(scene, scene.camera((24, 24)))
    got = methods.Config("hegeman", 1).run(gb, radius=0.1, scene=scene)
    shell = canopy_shell(scene)
    v = trees.canopy_visibility(gb.world_position[gb.valid], gb.world_normal[gb.valid], shell,
                                density=scene_density(scene, shell))
    np.testing.assert_array_equal(got[gb.valid], v)
    assert np.isnan(got[~gb.valid]).all() and (~gb.valid).any()


def test_hegeman_ground_pixels_use_the_occluder_model():
    from vobscure.trees.pixels import hegeman_gbuffer

    scene = vo.scenes.get("tree")
    gb = vo.render_gbuffer(scene, scene.camera((32, 32)))
    names = list(scene.meshes)
    ground = gb.valid.copy()
    ground[gb.valid] = scene.mesh_index[gb.primitive[gb.valid]] == names.index("ground")
    assert ground.any() and (gb.valid & ~ground).any()
    eqs78 = hegeman_gbuffer(gb, scene=scene)
    porous = hegeman_gbuffer(gb, scene=scene, ground="porous")
    # the tree's own pixels do not depend on the ground model; the ground's do
    np.testing.assert_array_equal(eqs78[gb.valid & ~ground], porous[gb.valid & ~ground])
    assert not np.array_equal(eqs78[ground], porous[ground])
    # Eq. 8 never darkens below 1/2 (a hemisphere's solid angle at most), and is < 1 under the tree
    assert eqs78[ground].min() >= 0.5 and eqs78[ground].min() < 1.0


def test_compare_on_a_vegetation_scene_runs_the_models_against_the_sky():
    res = vo.experiments.compare.compare("leaf_cloud", size=(16, 16), quick=True, cache=False,
                                         write=False, suggest=False)
    assert res.provenance["references"] == ["screen", "ao", "sky"]     # open leaves: no world VO
    rows = {r["label"]: r for r in res.rows}
    assert rows["hegeman"]["own_reference"] == "sky" and rows["hegeman"]["taps_per_pixel"] == 0
    assert rows["line:9"]["own_reference"] == "screen"                # no world-space VO here
    refs = {(g["reference"], g["error"]) for g in res.summary["groups"]}
    assert ("sky", "own_rmse") in refs and ("screen", "own_rmse") in refs
    # the canopy model is not ranked against the screen-space VO, a different quantity
    screen = next(g for g in res.summary["groups"] if g["reference"] == "screen")
    assert not any(label.startswith("hegeman") for label in screen["front_time"] + screen["front_taps"])
    with pytest.raises(ValueError, match="no canopy"):
        vo.experiments.compare.compare("slab", size=(8, 8), methods="hegeman", references=("sky",),
                                       quick=True, cache=False, write=False)


def test_reeves_blau_per_pixel_uses_the_leaves_extinction():
    from vobscure import trees
    from vobscure.trees.pixels import canopy_shell, scene_extinction

    scene = vo.scenes.get("tree")
    gb = vo.render_gbuffer(scene, scene.camera((24, 24)))
    got = methods.Config("reeves_blau", 1).run(gb, radius=0.1, scene=scene)
    shell = canopy_shell(scene)
    sigma = scene_extinction(scene, shell)
    meta = scene.metadata
    assert sigma == pytest.approx(meta["n_leaves"] / shell.volume * meta["leaf_area"] / 2, rel=1e-12)
    want = trees.reeves_blau(gb.world_position[gb.valid], shell, k=sigma)
    np.testing.assert_array_equal(got[gb.valid], want)
    outside = ~shell.contains(gb.world_position[gb.valid])
    assert outside.any() and np.all(got[gb.valid][outside] == 1.0)     # the ground: no interaction
    assert np.nanmin(got) < 0.9                                        # deep in the crown: attenuated


# --------------------------------------------------------------------------- the engines' baselines
@pytest.mark.parametrize("name, n, taps, quantity, reference", [
    ("gtao", 3, 18, "cosine AO", "ao"), ("gtao", 9, 54, "cosine AO", "ao"),
    ("hbao", 8, 32, "uniform AO", "ao_uniform"),
    ("alchemy", 12, 12, "obscurance", "obscurance"), ("sao", 12, 12, "obscurance", "obscurance"),
])
def test_baselines_in_the_registry(name, n, taps, quantity, reference):
    from vobscure import screenspace

    m = methods.get(name)
    assert m.taps(n) == taps and m.quantity(True) == quantity and m.reference() == reference
    # the registry's cost is the estimator's own count
    own = {"gtao": lambda k: 2 * k * methods.GTAO_STEPS, "hbao": lambda k: screenspace.hbao_taps(k, methods.HBAO_STEPS),
           "alchemy": screenspace.alchemy_taps, "sao": screenspace.sao_taps}[name]
    assert own(n) == taps


def test_gtao_taps_are_the_fetches_it_makes(gb, monkeypatch):
    calls = _count(monkeypatch, _common, "fetch_depth", lambda a, k: np.size(a[1]))
    methods.Config("gtao", 2).run(gb, radius=0.2)
    assert sum(calls) / gb.valid.sum() == methods.get("gtao").taps(2)


def test_compare_runs_the_baselines_against_their_own_references():
    res = vo.experiments.compare.compare("crease", size=(16, 12), methods="gtao:2,hbao:4,sao:8,line:5",
                                         quick=True, cache=False, write=False, suggest=False)
    # sao's own reference, the obscurance, is added to the defaults (which keep cosine AO,
    # the AO a renderer would use)
    assert set(res.provenance["references"]) == {"screen", "volumetric", "ao", "ao_uniform", "obscurance"}
    rows = {r["label"]: r for r in res.rows}
    assert rows["gtao:2"]["own_reference"] == "ao" and rows["hbao:4"]["own_reference"] == "ao_uniform"
    assert rows["sao:8"]["own_reference"] == "obscurance"
    assert rows["line:5"]["own_reference"] == "volumetric"
    for r in rows.values():
        assert np.isfinite(r["own_rmse"])
    groups = {g["reference"] for g in res.summary["groups"]}
    assert {"ao", "ao_uniform", "volumetric", "screen", "obscurance"} <= groups
