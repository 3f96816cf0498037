"""The registry of estimators: every method the experiments can run, in one place.

Each entry (:class:`Method`) says what a method is and what it costs:

- the function and the keyword that counts its samples (``samples`` for the VO estimators);
- its default depth fetch and how many depth texels one tap of that fetch reads;
- ``taps(n)``, the depth-buffer taps per pixel it makes with ``n`` samples, and
  ``texels(n)``, the texels those taps read (the cost model of DESIGN.md);
- the quantity it estimates (:data:`QUANTITIES`: ball VO, half-ball VO, cosine AO,
  obscurance) and so the reference it is compared with.

``vobscure compare``, :func:`vobscure.experiments.sweep`, the claims of Loos & Sloan, the
figures and the benchmarks read it; ``vobscure compare --help`` lists it. Adding an estimator
is one function plus one :func:`register` call (``docs/screenspace.md``, "Adding an
estimator"). A configuration -- a method with a sample count and, optionally, another fetch
-- is a :class:`Config`, written ``NAME:SAMPLES[:FETCH]`` (``line:9``, ``point:12:nearest``).

Examples
--------
>>> from vobscure import methods
>>> methods.names()
('point', 'line', 'area', 'reference', 'gtao', 'hbao', 'alchemy', 'sao', 'hegeman', 'hegeman_ellipsoid', 'hegeman_multishell', 'reeves_blau', 'poisson', 'bunnell', 'ren')
>>> m = methods.get("point")
>>> m.taps(33), m.texels(33), m.quantity(normal_clamp=True), m.reference(normal_clamp=True)
(32, 128, 'half-ball VO', 'volumetric')
>>> [c.label for c in methods.parse("line:9, point:12:nearest")]
['line:9', 'point:12:nearest']
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .estimate import DEFAULT_GROUPS
from .screenspace import alchemy, gtao, hbao, point_taps, sao, vo_area, vo_line, vo_point, vo_reference
from .trees.pixels import hegeman_gbuffer, reeves_blau_gbuffer

__all__ = ["Method", "Config", "Quantity", "QUANTITIES", "TEXELS_PER_TAP", "register", "get", "names",
           "parse", "unregister"]

#: Depth texels one tap reads with each fetch: a nearest fetch reads one texel, a bilinear
#: fetch 2 x 2; ``vo_area``'s mip-map lookup reads two levels of 2 x 2 (trilinear) or 3 x 3
#: (its default quadratic B-spline) texels; ``"none"``: an object-space model that reads no
#: depth buffer.
TEXELS_PER_TAP = {"nearest": 1, "bilinear": 4, "trilinear": 8, "bspline": 18, "none": 0}


@dataclass(frozen=True)
class Quantity:
    """A quantity an estimator estimates, and the reference (``ground_truth`` quantity) that
    measures it.

    Attributes
    ----------
    name : str
        Human-readable name, e.g. ``"half-ball VO"``.
    reference : str
        The reference of :mod:`vobscure.experiments.compare` that computes it exactly:
        ``"volumetric"`` (world-space VO, with ``normal_clamp`` as given), ``"ao"`` (cosine AO
        within the radius) or ``"obscurance"``.
    normal_clamp : bool or None
        The ``normal_clamp`` of the reference (None: not applicable).
    screen_limit : bool
        Whether :func:`vobscure.vo_reference` (the converged screen-space VO) is the
        estimator's limit with infinitely many samples, so that its error against it is the
        sampling error alone.
    """

    name: str
    reference: str
    normal_clamp: bool | None = None
    screen_limit: bool = False


#: The quantities, by name.
QUANTITIES = {
    "ball VO": Quantity("ball VO", "volumetric", normal_clamp=False, screen_limit=True),
    "half-ball VO": Quantity("half-ball VO", "volumetric", normal_clamp=True, screen_limit=True),
    "cosine AO": Quantity("cosine AO", "ao"),
    "uniform AO": Quantity("uniform AO", "ao_uniform"),
    "sky visibility": Quantity("sky visibility", "sky"),
    "uniform sky visibility": Quantity("uniform sky visibility", "sky_uniform"),
    "obscurance": Quantity("obscurance", "obscurance"),
}


def _vo_quantity(normal_clamp: bool = False) -> str:
    """The VO estimators estimate the ball's VO, or the half-ball's with the normal clamp."""
    return "half-ball VO" if normal_clamp else "ball VO"


def _one_tap_per_sample(n: int) -> int:
    return int(n)


def _reference_taps(n: int) -> int:
    """vo_reference rounds its samples up to DEFAULT_GROUPS randomizations of antithetic pairs."""
    per_group = 2 * DEFAULT_GROUPS
    return per_group * max(1, -(-int(n) // per_group))


@dataclass(frozen=True)
class Method:
    """One registered estimator.

    Parameters
    ----------
    name : str
        Registry key, as written in ``--methods`` (``"line"``).
    function : callable
        ``function(gbuffer, *, radius, <samples>=n, normal_clamp, thickness, seed, ...)``
        returning an (H, W) visibility image (or an :class:`~vobscure.Estimate`).
    default_samples : int
        The sample count of a configuration that gives none.
    fetch : str
        The default fetch (a key of :data:`TEXELS_PER_TAP`).
    taps : callable
        ``taps(n) -> int``: depth-buffer taps per pixel with ``n`` samples.
    quantity : callable
        ``quantity(normal_clamp) -> str``: a key of :data:`QUANTITIES`.
    samples : str or None
        The keyword of ``function`` that counts samples; None for a model without samples
        (the count of its configurations is then 1 and is not passed).
    fetch_parameter : str or None
        The keyword of ``function`` that selects the fetch (None: fixed).
    summary : str
        One line for ``--help`` and the docs.
    reference_only : bool
        A converged reference rather than an estimator one would ship (left out of the
        default comparisons and of the verdict's choices).
    needs_scene : bool
        The function also takes ``scene=`` (an object-space model that reads the scene's
        description, e.g. a tree's canopy shell), which the experiments pass.

    Examples
    --------
    >>> line = get("line")
    >>> line.taps(9), line.texels(9), line.fetch
    (9, 9, 'nearest')
    """

    name: str
    function: Callable
    default_samples: int
    fetch: str
    taps: Callable[[int], int] = _one_tap_per_sample
    quantity: Callable[..., str] = _vo_quantity
    samples: str | None = "samples"
    fetch_parameter: str | None = "fetch"
    summary: str = ""
    reference_only: bool = False
    needs_scene: bool = False

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ValueError(f"Method name must be an identifier such as 'line', got {self.name!r}")
        if not callable(self.function):
            raise ValueError(f"Method {self.name!r}: function must be callable, got {self.function!r}")
        if self.fetch not in TEXELS_PER_TAP:
            raise ValueError(f"Method {self.name!r}: fetch must be one of {', '.join(TEXELS_PER_TAP)}, "
                             f"got {self.fetch!r}")

    def texels(self, n: int, fetch: str | None = None) -> int:
        """Depth texels read per pixel with ``n`` samples: ``taps(n)`` x texels per tap of
        ``fetch`` (default the method's own)."""
        return self.taps(n) * TEXELS_PER_TAP[fetch or self.fetch]

    def reference(self, normal_clamp: bool = False) -> str:
        """The reference the method's estimate is scored against (its own quantity's)."""
        return QUANTITIES[self.quantity(normal_clamp)].reference

    def run(self, gbuffer, samples: int | None = None, *, fetch: str | None = None, **kwargs):
        """Call the function with ``samples`` (default :attr:`default_samples`) and, when
        given, another ``fetch``; other keywords are passed on."""
        if self.samples is not None:
            kwargs[self.samples] = self.default_samples if samples is None else samples
        if fetch is not None:
            if self.fetch_parameter is None:
                raise ValueError(f"method {self.name!r} has a fixed fetch; got fetch={fetch!r}")
            kwargs[self.fetch_parameter] = fetch
        return self.function(gbuffer, **kwargs)


_REGISTRY: dict[str, Method] = {}


def register(method: Method, *, replace: bool = False) -> Method:
    """Add ``method`` to the registry (``replace=True`` to redefine a name); returns it."""
    if not isinstance(method, Method):
        raise ValueError(f"register() takes a vobscure.methods.Method, got {type(method).__name__}")
    if method.name in _REGISTRY and not replace:
        raise ValueError(f"a method named {method.name!r} is already registered (pass replace=True)")
    _REGISTRY[method.name] = method
    return method


def unregister(name: str) -> None:
    """Remove a method (for tests and experiments that register their own)."""
    get(name)
    del _REGISTRY[name]


def names(*, include_references: bool = True) -> tuple[str, ...]:
    """The registered method names, in registration order."""
    return tuple(n for n, m in _REGISTRY.items() if include_references or not m.reference_only)


def get(name: str) -> Method:
    """The method registered as ``name``; the error lists the valid names."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown method {name!r}; expected one of {', '.join(_REGISTRY)}") from None


def describe() -> str:
    """One line per registered method, for ``--help`` and error messages."""
    lines = []
    for m in _REGISTRY.values():
        cost = ("object space, no samples" if m.samples is None
                else f"default {m.default_samples} samples, {m.fetch} fetch")
        lines.append(f"{m.name} ({cost}): {m.summary}")
    return "\n".join(lines)


@dataclass(frozen=True)
class Config:
    """A method with a sample count (and optionally another fetch): ``line:9``,
    ``point:12:nearest``.

    Examples
    --------
    >>> c = Config("point", 33, fetch="nearest")
    >>> c.label, c.taps, c.texels, c.quantity(False)
    ('point:33:nearest', 32, 32, 'ball VO')
    """

    method: str
    samples: int
    fetch: str | None = None

    def __post_init__(self):
        from ._validate import check_int

        m = get(self.method)
        object.__setattr__(self, "samples", check_int(self.samples, "samples"))
        if self.fetch is not None:
            if m.fetch_parameter is None or self.fetch not in TEXELS_PER_TAP:
                raise ValueError(f"fetch of {self.method!r} must be None or one of "
                                 f"{', '.join(TEXELS_PER_TAP)}, got {self.fetch!r}")
            if self.fetch == m.fetch:
                object.__setattr__(self, "fetch", None)

    @property
    def spec(self) -> Method:
        """The registry entry."""
        return get(self.method)

    @property
    def label(self) -> str:
        if self.spec.samples is None:
            return self.method
        base = f"{self.method}:{self.samples}"
        return base if self.fetch is None else f"{base}:{self.fetch}"

    @property
    def fetch_used(self) -> str:
        return self.fetch or self.spec.fetch

    @property
    def taps(self) -> int:
        return self.spec.taps(self.samples)

    @property
    def texels(self) -> int:
        return self.spec.texels(self.samples, self.fetch_used)

    def quantity(self, normal_clamp: bool = False) -> str:
        return self.spec.quantity(normal_clamp)

    def reference(self, normal_clamp: bool = False) -> str:
        return self.spec.reference(normal_clamp)

    def run(self, gbuffer, **kwargs):
        """Run the estimator on ``gbuffer`` with this configuration's samples and fetch."""
        return self.spec.run(gbuffer, self.samples, fetch=self.fetch, **kwargs)


def parse(spec) -> tuple[Config, ...]:
    """``"point:12,line:5"`` (or a sequence of such strings, Configs, or (name, samples)
    pairs) -> Configs. ``NAME`` alone takes the method's default sample count.

    Examples
    --------
    >>> [c.label for c in parse("point:12, line, area:1")]
    ['point:12', 'line:9', 'area:1']
    >>> parse("ray:3")
    Traceback (most recent call last):
    ...
    ValueError: --methods entry 'ray:3': unknown method 'ray'; expected one of point, line, area, reference, gtao, hbao, alchemy, sao, hegeman, hegeman_ellipsoid, hegeman_multishell, reeves_blau, poisson, bunnell, ren
    """
    items = [s.strip() for s in spec.split(",") if s.strip()] if isinstance(spec, str) else list(spec)
    if not items:
        raise ValueError(f"--methods must name at least one method, e.g. 'line:9,point:12'; "
                         f"methods: {', '.join(_REGISTRY)}")
    out = []
    for item in items:
        if isinstance(item, Config):
            out.append(item)
            continue
        if isinstance(item, tuple):
            out.append(Config(*item))
            continue
        name, _, rest = str(item).partition(":")
        name = name.strip()
        if name not in _REGISTRY:
            raise ValueError(f"--methods entry {item!r}: unknown method {name!r}; expected one of "
                             f"{', '.join(_REGISTRY)}")
        count, _, fetch = rest.partition(":")
        count = count.strip()
        if count and not count.isdigit():
            raise ValueError(f"--methods entry {item!r} must be NAME[:SAMPLES[:FETCH]] with SAMPLES a "
                             f"positive integer, e.g. 'line:9' or 'point:12:nearest'")
        samples = int(count) if count else _REGISTRY[name].default_samples
        out.append(Config(name, samples, fetch=fetch.strip() or None))
    if len(set(out)) != len(out):
        raise ValueError(f"--methods lists a configuration twice: {', '.join(c.label for c in out)}")
    return tuple(out)


# --------------------------------------------------------------------------- the registry
register(Method("point", vo_point, default_samples=12, fetch="bilinear", taps=point_taps,
                summary="point sampling of the ball (Loos & Sloan 2010, Sec. 4)"))
register(Method("line", vo_line, default_samples=9, fetch="nearest",
                summary="line sampling: exact chords through the ball (Sec. 4.1)"))
register(Method("area", vo_area, default_samples=1, fetch="bspline", fetch_parameter="reconstruction",
                summary="area sampling with mip-mapped depth moments (Sec. 4.2)"))
register(Method("reference", vo_reference, default_samples=4096, fetch="bilinear", taps=_reference_taps,
                summary="the converged screen-space VO (dense stratified points)", reference_only=True))



# --------------------------------------------------------------------------- the engines' baselines
def _cosine_ao(normal_clamp: bool = False) -> str:
    """GTAO estimates cosine-weighted AO within the radius."""
    return "cosine AO"


def _obscurance(normal_clamp: bool = False) -> str:
    """Alchemy and SAO are ambient *obscurance* estimators (their papers' titles): scored
    against the cosine-weighted obscurance; compare also shows them against cosine AO, which
    Alchemy is closer to on every scene measured (docs/results.md)."""
    return "obscurance"


def _uniform_ao(normal_clamp: bool = False) -> str:
    """HBAO estimates the uniformly weighted AO within the radius (with its attenuation, a
    t^2 obscurance of it: docs/screenspace.md)."""
    return "uniform AO"


def _gtao_taps(n: int) -> int:
    """GTAO with n slices of 3 steps a side: two taps a step."""
    return 2 * int(n) * GTAO_STEPS


def _hbao_taps(n: int) -> int:
    """HBAO with n directions of 4 steps."""
    return int(n) * HBAO_STEPS


#: Steps per side of the registered ``gtao`` (XeGTAO's "high": 3 x 3) and per direction of ``hbao``.
GTAO_STEPS = 3
HBAO_STEPS = 4


#: The VO estimators' options that an AO estimator has no use for (AO has no half-ball,
#: thickness model or VO falloff); the experiments pass them to every method.
_VO_OPTIONS = ("normal_clamp", "thickness", "falloff")


def _without_vo_options(fn, **fixed):
    """``fn`` called without :data:`_VO_OPTIONS`, with ``fixed`` keywords added."""
    def run(gbuffer, **kwargs):
        for name in _VO_OPTIONS:
            kwargs.pop(name, None)
        return fn(gbuffer, **fixed, **kwargs)
    run.__name__ = run.__qualname__ = fn.__name__
    run.__doc__ = fn.__doc__
    return run


_gtao = _without_vo_options(gtao, steps=GTAO_STEPS)
_hbao = _without_vo_options(hbao, steps=HBAO_STEPS)


register(Method("gtao", _gtao, default_samples=3, fetch="bilinear", samples="slices", taps=_gtao_taps,
                quantity=_cosine_ao, summary="GTAO (Jimenez et al. 2016): horizons per slice, cosine AO; "
                                             "SAMPLES = slices of 3 steps a side"))
register(Method("hbao", _hbao, default_samples=8, fetch="nearest", fetch_parameter=None, samples="directions",
                taps=_hbao_taps, quantity=_uniform_ao,
                summary="HBAO (Bavoil et al. 2008): horizon angles, uniform AO; SAMPLES = directions of 4 steps"))
register(Method("alchemy", _without_vo_options(alchemy), default_samples=12, fetch="nearest", fetch_parameter=None,
                quantity=_obscurance, summary="Alchemy AO (McGuire et al. 2011): obscurance estimator on a disk"))
register(Method("sao", _without_vo_options(sao), default_samples=12, fetch="nearest", fetch_parameter=None,
                quantity=_obscurance, summary="SAO (McGuire et al. 2012): spiral samples, falloff (r^2 - v.v)^3"))

def _no_taps(n: int) -> int:
    """An object-space model reads no depth buffer."""
    return 0


def _sky_visibility(normal_clamp: bool = False) -> str:
    """The vegetation models estimate the visibility of the whole sky (AO with no limit)."""
    return "sky visibility"


def _hegeman_ellipsoid(gbuffer, **kwargs):
    """Hegeman et al. 2006 with the canopy's minimum-volume enclosing ellipsoid (Sec. 3, Fig. 8)."""
    return hegeman_gbuffer(gbuffer, shell="ellipsoid", **kwargs)


register(Method("hegeman", hegeman_gbuffer, default_samples=1, fetch="none", fetch_parameter=None,
                taps=_no_taps, quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Hegeman et al. 2006: canopy sphere (Eqs. 4-6) and ground occluder (Eqs. 7-8); "
                        "vegetation scenes only"))
def _hegeman_multishell(gbuffer, **kwargs):
    """Hegeman et al. 2006 with three spheres by k-means, each point in the closest (Sec. 5)."""
    return hegeman_gbuffer(gbuffer, shell="multishell", k=3, **kwargs)


register(Method("hegeman_ellipsoid", _hegeman_ellipsoid, default_samples=1, fetch="none", fetch_parameter=None,
                taps=_no_taps, quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Hegeman et al. 2006 with an ellipsoidal canopy shell (Sec. 3, Fig. 8); vegetation "
                        "scenes only"))
register(Method("hegeman_multishell", _hegeman_multishell, default_samples=1, fetch="none", fetch_parameter=None,
                taps=_no_taps, quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Hegeman et al. 2006 with three k-means spheres (Sec. 5, Fig. 3); vegetation scenes only"))
register(Method("reeves_blau", reeves_blau_gbuffer, default_samples=1, fetch="none", fetch_parameter=None,
                taps=_no_taps, quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Reeves & Blau 1985: exp(-k depth in the canopy), k the leaves' extinction; the "
                        "baseline of Hegeman et al.; vegetation scenes only"))


def _poisson(gbuffer, **kwargs):
    """The Poisson leaf cloud's expected sky visibility (issue 15), imported when called."""
    from .trees.pixels import poisson_gbuffer

    return poisson_gbuffer(gbuffer, **kwargs)


register(Method("poisson", _poisson, default_samples=1, fetch="none", fetch_parameter=None,
                taps=_no_taps, quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Poisson leaf cloud in the canopy's bounding sphere: the expected visibility "
                        "(1/pi) int exp(-sigma L) cos, sigma = n A / 2 from the leaf statistics, nothing "
                        "fitted; leaves and ground; vegetation scenes only"))


def _uniform_sky_visibility(normal_clamp: bool = False) -> str:
    """Bunnell's disks (Listing 14-1's term) estimate the uniformly weighted visibility of the
    whole sky: a solid-angle fraction per disk, no distance limit."""
    return "uniform sky visibility"


def _bunnell(gbuffer, **kwargs):
    """Bunnell 2005 disk AO per pixel (objectspace.bunnell_gbuffer), the meshes subdivided to
    max_edge="auto" so that coarse walls (the Cornell box's) become surfaces of disks."""
    from .objectspace import bunnell_gbuffer

    kwargs.setdefault("max_edge", "auto")
    return bunnell_gbuffer(gbuffer, **kwargs)


register(Method("bunnell", _bunnell, default_samples=1, fetch="none", fetch_parameter=None, taps=_no_taps,
                quantity=_uniform_sky_visibility, samples=None, needs_scene=True,
                summary="Bunnell 2005 (GPU Gems 2 ch. 14): a disk per vertex, Listing 14-1's shadow term, "
                        "2 passes, tree of aggregated disks; object space, any mesh scene"))


def _ren(gbuffer, **kwargs):
    """Ren et al. 2006 per pixel (objectspace.sphere_set_gbuffer): the scene as 32 inscribed
    spheres, order-4 SH, their log vectors summed and exponentiated once (hybrid exp)."""
    from .objectspace import sphere_set_gbuffer

    return sphere_set_gbuffer(gbuffer, **kwargs)


register(Method("ren", _ren, default_samples=1, fetch="none", fetch_parameter=None, taps=_no_taps,
                quantity=_sky_visibility, samples=None, needs_scene=True,
                summary="Ren et al. 2006: the scene as k = 32 inscribed spheres, SH order 4, log vectors "
                        "summed and exponentiated once (SHEXP, hybrid); cosine AO; any closed mesh scene"))
