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
    assert methods.names() == ("point", "line", "area", "reference")
    assert methods.names(include_references=False) == ("point", "line", "area")
    with pytest.raises(ValueError, match="unknown method 'gtao'; expected one of point, line, area, reference"):
        methods.get("gtao")


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
    for name in methods.names():
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
    calls = _count(monkeypatch, area._Pyramid, "lookup", lambda a, k: np.size(a[1]))
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
