"""The method registry (vobscure.methods): names and errors, configuration parsing, the cost
model checked against the taps the estimators really make (counted by instrumenting the
depth fetch), the quantity -> reference mapping, and registering a new method that then runs
in a sweep and in `compare`."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure import methods, references
from vobscure.screenspace import _common, area

#: Slab seen from above at an angle: every pixel covered, no tap off screen.
CAM = vo.Camera.look_at((0.4, 2.0, 1.2), (0.0, 0.0, 0.0), size=(12, 10), fov_y=40.0)


@pytest.fixture(scope="module")
def gb():
    return vo.render_gbuffer(vo.scenes.slab(), CAM)


def test_names_and_unknown_name_lists_them():
    vegetation = ("hegeman", "hegeman_ellipsoid", "hegeman_multishell", "reeves_blau", "poisson")
    baselines = ("gtao", "vbao", "vbao_uniform", "hbao", "alchemy", "sao")
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


#: On a plane the ball's VO is 1/2 and every other quantity (the half-ball's VO, AO and
#: obscurance within the radius) is 1: the hand-made case of the quantity -> reference mapping.
PLANE_VALUE = {"ball VO": 0.5}
#: Median over the pixels of an estimate on the plane against the closed form: the estimators
#: with their default (few) samples are unbiased on a plane up to the depth buffer's
#: quantization; their per-pixel noise (up to 0.1 at 9-12 samples) averages out in the median.
PLANE_MEDIAN_TOL = 0.02


@pytest.mark.parametrize("name", ["point", "line", "area", "gtao", "hbao", "alchemy", "sao"])
@pytest.mark.parametrize("normal_clamp", [False, True])
def test_own_reference_measures_what_the_method_estimates_on_a_plane(gb, name, normal_clamp):
    m = methods.get(name)
    quantity = m.quantity(normal_clamp)
    want = PLANE_VALUE.get(quantity, 1.0)
    estimate = m.run(gb, radius=0.2, normal_clamp=normal_clamp)
    assert abs(np.nanmedian(estimate) - want) < PLANE_MEDIAN_TOL
    # the reference named for the quantity, computed from its registry entry, is that value
    ref = references.get(m.reference(normal_clamp))
    assert ref.quantity(normal_clamp) == quantity
    args = ref.arguments(radius=0.2, seed=0, rays=16, volume_samples=64, normal_clamp=normal_clamp,
                         falloff="constant", allow_open=False)
    truth = vo.ground_truth(vo.scenes.slab(), gb, **args)
    np.testing.assert_allclose(truth.value, want, atol=4 * np.nanmax(truth.stderr) + 1e-12)


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
    np.testing.assert_array_equal(area_trilinear, vo.vo_area(gb, radius=0.2, fetch="trilinear"))


def test_vo_area_reconstruction_is_a_deprecated_name_of_fetch(gb):
    with pytest.warns(DeprecationWarning, match="fetch="):
        old = vo.vo_area(gb, radius=0.2, reconstruction="trilinear")
    np.testing.assert_array_equal(old, vo.vo_area(gb, radius=0.2, fetch="trilinear"))
    assert not np.array_equal(old, vo.vo_area(gb, radius=0.2))      # the B-spline differs
    with pytest.raises(ValueError, match="fetch must be one of"):
        vo.vo_area(gb, radius=0.2, fetch="bicubic")


# --------------------------------------------------------------------------- run: one return type, options
def test_run_returns_the_image_and_estimate_the_standard_error(gb):
    ref = methods.Config("reference", 64)
    image = ref.run(gb, radius=0.2, seed=1)
    est = ref.estimate(gb, radius=0.2, seed=1)
    direct = vo.vo_reference(gb, radius=0.2, samples=64, seed=1)
    assert isinstance(image, np.ndarray) and image.shape == gb.valid.shape
    np.testing.assert_array_equal(image, direct.value)
    np.testing.assert_array_equal(est.stderr, direct.stderr)
    with pytest.raises(ValueError, match="gives no standard error"):
        methods.Config("line", 5).estimate(gb, radius=0.2)


def test_run_passes_each_method_the_options_it_takes(gb):
    common = dict(radius=0.2, normal_clamp=True, thickness=0.1, falloff="quadratic", seed=2)
    # GTAO takes none of the VO options: it runs as without them
    np.testing.assert_array_equal(methods.Config("gtao", 2).run(gb, **common),
                                  vo.gtao(gb, radius=0.2, slices=2, seed=2))
    # lines take them all: the thickness and falloff change the image
    np.testing.assert_array_equal(methods.Config("line", 5).run(gb, **common),
                                  vo.vo_line(gb, samples=5, **common))
    # an option of another method (SAO's beta) is not the line's: left out
    np.testing.assert_array_equal(methods.Config("line", 5).run(gb, beta=0.5, **common),
                                  vo.vo_line(gb, samples=5, **common))
    with pytest.raises(ValueError, match="no registered method takes the option.*'thicknes'"):
        methods.Config("line", 5).run(gb, radius=0.2, thicknes=0.1)
    with pytest.raises(ValueError, match="give its sample count as samples=, not slices="):
        methods.get("gtao").run(gb, radius=0.2, slices=4)


def test_a_function_taking_any_keyword_gets_every_option(gb):
    seen = {}

    def open_everywhere(gbuffer, *, radius, samples=1, **options):
        seen.update(options, radius=radius, samples=samples)
        return np.ones(gbuffer.valid.shape)

    m = methods.Method("anything", open_everywhere, default_samples=1, fetch="nearest", fetch_parameter=None)
    m.run(gb, 3, radius=0.2, normal_clamp=True, beta=0.5)
    assert seen == dict(radius=0.2, samples=3, normal_clamp=True, beta=0.5)
    bad = methods.Method("bad", lambda gbuffer, *, radius, samples: np.ones(3), default_samples=1, fetch="nearest")
    with pytest.raises(ValueError, match=r"must return an \(H, W\) array"):
        bad.run(gb, radius=0.2)


def test_every_registered_function_is_reachable_from_vo():
    """Every estimator of the registry is a public name reachable by attributes from ``vo``
    (its module's path with no private part), and the engines' estimators, the bent normals
    and ``io`` are top-level names."""
    import functools

    for name in methods.names():
        fn = methods.get(name).function
        fn = fn.func if isinstance(fn, functools.partial) else fn     # some keywords fixed
        parts = fn.__module__.split(".")[1:]
        assert not any(p.startswith("_") for p in parts + [fn.__name__]), (name, fn.__module__)
        owners = [vo]                 # vo and the packages and module on the way to the function
        for part in parts:
            owners.append(getattr(owners[-1], part, None))
        assert any(getattr(o, fn.__name__, None) is fn for o in owners), name
    for name in ("gtao", "gtao_bent_normals", "hbao", "sao", "alchemy"):
        assert name in vo.__all__ and getattr(vo, name) is getattr(vo.screenspace, name)
    assert "io" in vo.__all__ and vo.io.read_buffers is not None


# --------------------------------------------------------------------------- the reference registry
def test_a_reference_is_one_registry_entry(monkeypatch):
    """A new reference (here the uniformly weighted obscurance) is one entry: the sweep then
    computes it from the entry alone, the same numbers as ground_truth called by hand."""
    from vobscure.experiments import InlineExecutor, SweepConfig, sweep

    entry = references.Reference("obscurance_uniform", "uniform obscurance", "obscurance", "rays",
                                 weighting="uniform")
    monkeypatch.setitem(references.REFERENCES, entry.name, entry)
    config = SweepConfig("crease", "line", 5, size=(10, 8), radius=0.3, rays=16,
                         references=("obscurance", "obscurance_uniform"))
    (res,) = sweep([config], executor=InlineExecutor(), keep_images=True)
    want = vo.ground_truth(vo.scenes.crease(), res.gbuffer, quantity="obscurance", radius=0.3,
                           weighting="uniform", rays=16, seed=0)
    np.testing.assert_array_equal(res.references["obscurance_uniform"].value, want.value)
    assert not np.array_equal(want.value, res.references["obscurance"].value)
    row = res.as_row()
    assert row["rmse_obscurance_uniform"] == vo.error(res.image, want.value).rmse


def test_reference_registry_errors():
    with pytest.raises(ValueError, match="unknown reference 'fog'; expected one of screen, volumetric"):
        references.get("fog")
    with pytest.raises(ValueError, match="ground_truth must be None or one of ao, obscurance, volumetric"):
        references.Reference("x", "x", "fog", "rays")
    with pytest.raises(ValueError, match="samples must be one of"):
        references.Reference("x", "x", "ao", "points")
    with pytest.raises(ValueError, match="needs rays"):
        references.get("ao").arguments(radius=1.0, seed=0)


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
    # open leaves: the shell VO stands in for the solid world-space VO, and the verdict says why
    assert res.provenance["references"] == ["screen", "shell", "ao", "sky"]
    assert res.provenance["missing_references"] == {"volumetric": "shell"}
    note = next(t for t in res.summary["text"] if t.startswith("No 'volumetric' reference"))
    assert "(leaves)" in note
    rows = {r["label"]: r for r in res.rows}
    assert rows["hegeman"]["own_reference"] == "sky" and rows["hegeman"]["taps_per_pixel"] == 0
    assert rows["line:9"]["own_reference"] == "shell"
    refs = {(g["reference"], g["error"]) for g in res.summary["groups"]}
    assert ("sky", "own_rmse") in refs and ("shell", "own_rmse") in refs and ("screen", "screen_rmse") in refs
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
    if name in ("alchemy", "sao"):     # the registry's cost is the estimator's own count
        assert {"alchemy": screenspace.alchemy_taps, "sao": screenspace.sao_taps}[name](n) == taps


@pytest.mark.parametrize("name, n", [("gtao", 2), ("hbao", 3)])
def test_horizon_taps_are_the_fetches_they_make(gb, monkeypatch, name, n):
    calls = _count(monkeypatch, _common, "fetch_depth", lambda a, k: np.size(a[1]))
    methods.Config(name, n).run(gb, radius=0.2)
    assert sum(calls) / gb.valid.sum() == methods.get(name).taps(n)


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


# --------------------------------------------------------------------------- the thickness kinds
def test_the_registry_declares_which_methods_read_layers():
    """Written out by hand from docs/screenspace.md ("Thickness from layers", "VBAO"): the VO
    point and line estimators, GTAO and VBAO read layers; area sampling and the converged
    reference take only a constant thickness; GTAO no constant; the obscurance and HBAO
    baselines none."""
    expected = {"point": ("constant", "layers"), "line": ("constant", "layers"), "area": ("constant",),
                "reference": ("constant",), "gtao": ("layers",), "vbao": ("constant", "layers"),
                "vbao_uniform": ("constant", "layers"), "hbao": (), "alchemy": (), "sao": ()}
    for name, kinds in expected.items():
        m = methods.get(name)
        assert m.thickness_kinds == kinds, name
        assert m.takes_thickness("layers") == ("layers" in kinds)
        assert m.takes_thickness(0.3) == ("constant" in kinds)


def test_run_passes_a_thickness_only_of_a_kind_the_method_takes():
    scene = vo.scenes.thin_occluders()
    layered = vo.render_gbuffer(scene, scene.camera((12, 12)), layers=2)
    kw = dict(radius=0.5, seed=1)
    np.testing.assert_array_equal(methods.Config("line", 5).run(layered, thickness="layers", **kw),
                                  vo.vo_line(layered, samples=5, thickness="layers", **kw))
    np.testing.assert_array_equal(methods.Config("vbao", 2).run(layered, thickness="layers", **kw),
                                  vo.vbao(layered, slices=2, steps=methods.VBAO_STEPS, thickness="layers", **kw))
    # area sampling takes no layers: it runs as without a thickness (vo_area itself refuses "layers")
    np.testing.assert_array_equal(methods.Config("area", 1).run(layered, thickness="layers", **kw),
                                  vo.vo_area(layered, samples=1, **kw))
    with pytest.raises(ValueError, match="thickness"):
        vo.vo_area(layered, thickness="layers", **kw)
    # GTAO takes the layers, and no number (vo.gtao itself refuses one)
    np.testing.assert_array_equal(methods.Config("gtao", 2).run(layered, thickness="layers", **kw),
                                  vo.gtao(layered, slices=2, thickness="layers", **kw))
    np.testing.assert_array_equal(methods.Config("gtao", 2).run(layered, thickness=0.2, **kw),
                                  vo.gtao(layered, slices=2, **kw))


def test_thickness_kinds_are_validated_and_default_to_the_signature():
    def with_thickness(gbuffer, *, radius, samples=1, thickness=None):
        return np.ones(gbuffer.valid.shape)

    def without(gbuffer, *, radius, samples=1):
        return np.ones(gbuffer.valid.shape)

    assert methods.Method("t", with_thickness, default_samples=1, fetch="nearest").thickness_kinds == ("constant",)
    assert methods.Method("n", without, default_samples=1, fetch="nearest").thickness_kinds == ()
    assert methods.Method("l", with_thickness, default_samples=1, fetch="nearest",
                          thickness_kinds="layers").thickness_kinds == ("layers",)
    with pytest.raises(ValueError, match="thickness_kinds must be some of constant, layers, got 'fat'"):
        methods.Method("f", with_thickness, default_samples=1, fetch="nearest", thickness_kinds=("fat",))
    with pytest.raises(ValueError, match="needs a function that takes the keyword thickness"):
        methods.Method("w", without, default_samples=1, fetch="nearest", thickness_kinds=("layers",))
