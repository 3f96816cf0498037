"""The registry of estimators: every method the experiments can run, in one place.

Each entry (:class:`Method`) says what a method is and what it costs:

- the function and the keyword that counts its samples (``samples`` for the VO estimators);
- its default depth fetch and how many depth texels one tap of that fetch reads;
- ``taps(n)``, the depth-buffer taps per pixel it makes with ``n`` samples, and
  ``texels(n)``, the texels those taps read (the cost model of DESIGN.md);
- the quantity it estimates (:data:`QUANTITIES`: ball VO, half-ball VO, cosine AO,
  obscurance, ..., taken from the reference registry :mod:`vobscure.references`) and so the
  reference it is compared with;
- the kinds of ``thickness`` it takes (:data:`THICKNESS_KINDS`: a constant thickness, the
  solid intervals of a layered G-buffer, ``thickness="layers"``), so that an experiment can
  pass every method the same ``thickness`` and each gets it only when it takes that kind.

:meth:`Method.run` returns the (H, W) image and passes the function the options it takes
(:func:`filter_options`); :meth:`Method.estimate` gives the standard error of a method that
has one.

``vobscure compare``, :func:`vobscure.experiments.sweep`, the claims of Loos & Sloan, the
figures and the benchmarks read it; ``vobscure compare --help`` lists it. Adding an estimator
is one function plus one :func:`register` call (``docs/methods.md``, "Adding an
estimator"). A configuration -- a method with a sample count and, optionally, another fetch
-- is a :class:`Config`, written ``NAME:SAMPLES[:FETCH]`` (``line:9``, ``point:12:nearest``).

Examples
--------
>>> from vobscure import methods
>>> methods.names()
('point', 'line', 'area', 'reference', 'gtao', 'vbao', 'vbao_uniform', 'hbao', 'alchemy', 'sao', 'hegeman', 'hegeman_ellipsoid', 'hegeman_multishell', 'reeves_blau', 'poisson', 'bunnell', 'ren')
>>> m = methods.get("point")
>>> m.taps(33), m.texels(33), m.quantity(normal_clamp=True), m.reference(normal_clamp=True)
(32, 128, 'half-ball VO', 'volumetric')
>>> [c.label for c in methods.parse("line:9, point:12:nearest")]
['line:9', 'point:12:nearest']
>>> [n for n in methods.names() if methods.get(n).takes_thickness("layers")]
['point', 'line', 'gtao', 'vbao', 'vbao_uniform']
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from .estimate import DEFAULT_GROUPS, Estimate
from .objectspace import bunnell_gbuffer, sphere_set_gbuffer
from .references import QUANTITIES, Quantity, lookup
from .screenspace import alchemy, gtao, hbao, point_taps, sao, vbao, vo_area, vo_line, vo_point, vo_reference
from .screenspace import crop_guard, inner_shape
from .trees.pixels import hegeman_gbuffer, poisson_gbuffer, reeves_blau_gbuffer

__all__ = ["Method", "Config", "Quantity", "QUANTITIES", "TEXELS_PER_TAP", "THICKNESS_KINDS", "register", "get",
           "names", "parse", "unregister", "filter_options", "thickness_kind"]

#: Depth texels one tap reads with each fetch: a nearest fetch reads one texel, a bilinear
#: fetch 2 x 2; ``vo_area``'s mip-map lookup reads two levels of 2 x 2 (trilinear) or 3 x 3
#: (its default quadratic B-spline) texels; ``"none"``: an object-space model that reads no
#: depth buffer.
TEXELS_PER_TAP = {"nearest": 1, "bilinear": 4, "trilinear": 8, "bspline": 18, "none": 0}

#: The kinds of ``thickness`` a method can take: ``"constant"``, a positive number (the thickness
#: model of Loos & Sloan 2010, Sec. 4.3; VBAO's constant thickness), and ``"layers"``, the solid
#: intervals of a layered G-buffer (``render_gbuffer(..., layers=K)``, ``docs/layers.md``).
THICKNESS_KINDS = ("constant", "layers")


def thickness_kind(thickness) -> str | None:
    """The kind (:data:`THICKNESS_KINDS`) of a ``thickness`` option: None for None (no
    thickness: every surface solid behind its depth), ``"layers"`` for ``"layers"``,
    ``"constant"`` for anything else (the function checks the number).

    Examples
    --------
    >>> thickness_kind(None), thickness_kind(0.2), thickness_kind("layers")
    (None, 'constant', 'layers')
    """
    if thickness is None:
        return None
    return "layers" if isinstance(thickness, str) and thickness == "layers" else "constant"


def _parameters(function) -> frozenset | None:
    """The keywords ``function(gbuffer, ...)`` takes after the G-buffer; None when it takes
    any keyword (``**kwargs``)."""
    params = list(inspect.signature(function).parameters.values())[1:]
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    return frozenset(p.name for p in params if p.kind in (inspect.Parameter.KEYWORD_ONLY,
                                                          inspect.Parameter.POSITIONAL_OR_KEYWORD))


def filter_options(function, options: dict) -> dict:
    """The ``options`` that ``function`` takes (all of them when it takes ``**kwargs``): the
    one place where the options an experiment passes to every method are fitted to each.

    Examples
    --------
    >>> def f(gbuffer, *, radius, seed=0):
    ...     return radius
    >>> filter_options(f, dict(radius=0.5, normal_clamp=True, seed=1))
    {'radius': 0.5, 'seed': 1}
    """
    return _taken(_parameters(function), options)


def _taken(accepted: frozenset | None, options: dict) -> dict:
    """The ``options`` named in ``accepted`` (all of them when ``accepted`` is None)."""
    return dict(options) if accepted is None else {k: v for k, v in options.items() if k in accepted}


def _vo_quantity(normal_clamp: bool = False) -> str:
    """The VO estimators estimate the ball's VO, or the half-ball's with the normal clamp."""
    return "half-ball VO" if normal_clamp else "ball VO"


def _one_tap_per_sample(n: int) -> int:
    return int(n)


def _reference_taps(n: int) -> int:
    """vo_reference rounds its samples (view rays, one depth tap each) up to a multiple of 2 x DEFAULT_GROUPS."""
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
        ``function(gbuffer, *, radius, <samples>=n, ...)`` returning an (H, W) visibility
        image (or an :class:`~vobscure.Estimate`, whose value :meth:`run` returns). It takes
        the options it uses, by name (:func:`filter_options` passes it those).
    default_samples : int
        The sample count of a configuration that gives none.
    fetch : str
        The default fetch (a key of :data:`TEXELS_PER_TAP`).
    taps : callable
        ``taps(n) -> int``: depth-buffer taps per pixel with ``n`` samples.
    quantity : callable
        ``quantity(normal_clamp) -> str``: a key of :data:`QUANTITIES`.
    samples : str or None
        The keyword of ``function`` that counts samples (``samples``, GTAO's ``slices``,
        HBAO's ``directions``: the table of ``docs/methods.md``); None for a model without
        samples (the count of its configurations is then 1 and is not passed).
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
    thickness_kinds : tuple of str, optional
        The kinds of ``thickness`` (:data:`THICKNESS_KINDS`) the function takes: it is passed
        a ``thickness`` option only of these kinds (and None), else it runs as without it.
        Default: ``("constant",)`` when the function takes a ``thickness`` keyword (or any
        keyword), else ``()``.

    Examples
    --------
    >>> line = get("line")
    >>> line.taps(9), line.texels(9), line.fetch, line.thickness_kinds
    (9, 9, 'nearest', ('constant', 'layers'))
    >>> get("gtao").thickness_kinds, get("area").thickness_kinds, get("sao").thickness_kinds
    (('layers',), ('constant',), ())
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
    thickness_kinds: tuple | None = None
    _parameters: frozenset | None = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ValueError(f"Method name must be an identifier such as 'line', got {self.name!r}")
        if not callable(self.function):
            raise ValueError(f"Method {self.name!r}: function must be callable, got {self.function!r}")
        if self.fetch not in TEXELS_PER_TAP:
            raise ValueError(f"Method {self.name!r}: fetch must be one of {', '.join(TEXELS_PER_TAP)}, "
                             f"got {self.fetch!r}")
        params = _parameters(self.function)
        object.__setattr__(self, "_parameters", params)
        takes = params is None or "thickness" in params
        kinds = self.thickness_kinds
        if kinds is None:
            kinds = ("constant",) if takes else ()
        kinds = (kinds,) if isinstance(kinds, str) else tuple(kinds)
        bad = [k for k in kinds if k not in THICKNESS_KINDS]
        if bad:
            raise ValueError(f"Method {self.name!r}: thickness_kinds must be some of {', '.join(THICKNESS_KINDS)}, "
                             f"got {', '.join(map(repr, bad))}")
        if kinds and not takes:
            raise ValueError(f"Method {self.name!r}: thickness_kinds {kinds} needs a function that takes the "
                             f"keyword thickness")
        object.__setattr__(self, "thickness_kinds", tuple(k for k in THICKNESS_KINDS if k in kinds))

    def takes_thickness(self, thickness) -> bool:
        """Whether :meth:`run` passes the function ``thickness=thickness``: None when the
        function takes the keyword, a number with ``"constant"`` and ``"layers"`` with
        ``"layers"`` among :attr:`thickness_kinds`.

        Examples
        --------
        >>> get("gtao").takes_thickness(0.2), get("gtao").takes_thickness("layers")
        (False, True)
        """
        kind = thickness_kind(thickness)
        if kind is None:
            return self._parameters is None or "thickness" in self._parameters
        return kind in self.thickness_kinds

    def texels(self, n: int, fetch: str | None = None) -> int:
        """Depth texels read per pixel with ``n`` samples: ``taps(n)`` x texels per tap of
        ``fetch`` (default the method's own)."""
        return self.taps(n) * TEXELS_PER_TAP[fetch or self.fetch]

    def reference(self, normal_clamp: bool = False) -> str:
        """The reference the method's estimate is scored against (its own quantity's)."""
        return QUANTITIES[self.quantity(normal_clamp)].reference

    def _call(self, gbuffer, samples, fetch, options):
        """The function's own result, with the sample count, the fetch and the options it takes."""
        if self.samples is not None and self.samples in options:
            raise ValueError(f"method {self.name!r}: give its sample count as samples=, not {self.samples}=")
        if self.fetch_parameter is not None and self.fetch_parameter in options:
            raise ValueError(f"method {self.name!r}: give its depth fetch as fetch=, not {self.fetch_parameter}=")
        unknown = sorted(k for k in options if not _anyone_takes(k))
        if unknown:
            raise ValueError(f"no registered method takes the option(s) {', '.join(map(repr, unknown))}; "
                             f"method {self.name!r} takes {', '.join(sorted(self._parameters or ()))}")
        kwargs = _taken(self._parameters, options)
        if "thickness" in kwargs and not self.takes_thickness(kwargs["thickness"]):
            del kwargs["thickness"]    # a kind of thickness the method does not take: run as without it
        if self.samples is not None:
            kwargs[self.samples] = self.default_samples if samples is None else samples
        if fetch is not None:
            if self.fetch_parameter is None:
                raise ValueError(f"method {self.name!r} has a fixed fetch; got fetch={fetch!r}")
            kwargs[self.fetch_parameter] = fetch
        return self.function(gbuffer, **kwargs)

    def run(self, gbuffer, samples: int | None = None, *, fetch: str | None = None, **options) -> np.ndarray:
        """The (H, W) visibility image: the function called with ``samples`` (default
        :attr:`default_samples`) as its :attr:`samples` keyword, ``fetch`` (default the
        method's own) as its :attr:`fetch_parameter`, and those of ``options`` it takes.

        The experiments pass every method the same options (``radius``, ``normal_clamp``,
        ``thickness``, ``falloff``, ``seed``, ``scene``); each gets the ones its function
        takes (:func:`filter_options`), ``thickness`` only of a kind it takes
        (:attr:`thickness_kinds`, :meth:`takes_thickness`). An option that no registered
        method takes is an error. A method whose function returns an :class:`~vobscure.Estimate` gives its
        value here and the whole estimate from :meth:`estimate`.

        Examples
        --------
        >>> import vobscure as vo
        >>> gb = vo.render_gbuffer(vo.scenes.slab(), vo.scenes.slab().camera((8, 8)))
        >>> get("gtao").run(gb, 2, radius=0.5, normal_clamp=True).shape  # GTAO has no clamp
        (8, 8)
        >>> get("line").run(gb, radius=0.5, thicknes=0.1)
        Traceback (most recent call last):
        ...
        ValueError: no registered method takes the option(s) 'thicknes'; method 'line' takes falloff, fetch, frame, noise_size, normal_clamp, offscreen, radius, randomize, samples, schedule, seed, thickness
        """
        out = crop_guard(self._call(gbuffer, samples, fetch, options), gbuffer)
        value = out.value if isinstance(out, Estimate) else out
        shape = inner_shape(gbuffer) if hasattr(gbuffer, "shape") else None
        if not isinstance(value, np.ndarray) or (shape is not None and value.shape != tuple(shape)):
            raise ValueError(f"method {self.name!r} must return an (H, W) array of the G-buffer's shape "
                             f"{shape}, got {type(value).__name__} {getattr(value, 'shape', '')}")
        return value

    def estimate(self, gbuffer, samples: int | None = None, *, fetch: str | None = None, **options) -> Estimate:
        """As :meth:`run`, for a method whose function returns an :class:`~vobscure.Estimate`
        (value and standard error, e.g. ``reference``); an error for the others."""
        out = crop_guard(self._call(gbuffer, samples, fetch, options), gbuffer)
        if not isinstance(out, Estimate):
            raise ValueError(f"method {self.name!r} gives no standard error (its function returns "
                             f"{type(out).__name__}); use run()")
        return out


def _anyone_takes(option: str) -> bool:
    """Whether some registered method's function takes the keyword ``option``."""
    return any(m._parameters is None or option in m._parameters for m in _REGISTRY.values())


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
    return lookup(_REGISTRY, name, "method")


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

    def run(self, gbuffer, **options) -> np.ndarray:
        """The (H, W) estimate on ``gbuffer`` with this configuration's samples and fetch
        (:meth:`Method.run`)."""
        return self.spec.run(gbuffer, self.samples, fetch=self.fetch, **options)

    def estimate(self, gbuffer, **options) -> Estimate:
        """The estimate with its standard error (:meth:`Method.estimate`)."""
        return self.spec.estimate(gbuffer, self.samples, fetch=self.fetch, **options)


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
    ValueError: --methods entry 'ray:3': unknown method 'ray'; expected one of point, line, area, reference, gtao, vbao, vbao_uniform, hbao, alchemy, sao, hegeman, hegeman_ellipsoid, hegeman_multishell, reeves_blau, poisson, bunnell, ren
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
        # ASCII decimal digits only: str.isdigit accepts superscripts such as '²', which int() rejects
        if count and not (count.isascii() and count.isdecimal()):
            raise ValueError(f"--methods entry {item!r} must be NAME[:SAMPLES[:FETCH]] with SAMPLES a "
                             f"positive integer in ASCII digits 0-9, got SAMPLES {count!r}; e.g. 'line:9' "
                             f"or 'point:12:nearest'")
        samples = int(count) if count else _REGISTRY[name].default_samples
        try:
            out.append(Config(name, samples, fetch=fetch.strip() or None))
        except ValueError as exc:
            raise ValueError(f"--methods entry {item!r}: {exc}") from None
    if len(set(out)) != len(out):
        raise ValueError(f"--methods lists a configuration twice: {', '.join(c.label for c in out)}")
    return tuple(out)


# --------------------------------------------------------------------------- the registry
# the VO estimators read the layers at the pixel a sample falls in (docs/screenspace.md, "Thickness from layers")
register(Method("point", vo_point, default_samples=12, fetch="bilinear", taps=point_taps,
                thickness_kinds=("constant", "layers"), summary="point sampling of the ball (Loos & Sloan 2010, Sec. 4)"))
register(Method("line", vo_line, default_samples=9, fetch="nearest", thickness_kinds=("constant", "layers"),
                summary="line sampling: exact chords through the ball (Sec. 4.1)"))
register(Method("area", vo_area, default_samples=1, fetch="bspline", thickness_kinds=("constant",),
                summary="area sampling with mip-mapped depth moments (Sec. 4.2)"))
register(Method("reference", vo_reference, default_samples=4096, fetch="bilinear", taps=_reference_taps,
                thickness_kinds=("constant",), summary="the converged screen-space VO (dense stratified points)", reference_only=True))


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


def _vbao_taps(n: int) -> int:
    """VBAO with n slices of 3 steps a side: two taps a step, as GTAO."""
    return 2 * int(n) * VBAO_STEPS


#: Steps per side of the registered ``gtao`` (XeGTAO's "high": 3 x 3) and per direction of ``hbao``.
GTAO_STEPS = 3
#: Steps per side of the registered ``vbao`` and ``vbao_uniform`` (GTAO's, so that they cost the same taps).
VBAO_STEPS = GTAO_STEPS
HBAO_STEPS = 4

# GTAO as the registry runs it, XeGTAO's "high" steps. Its ``thickness`` takes only the layers
# (a constant thickness is the VO model; GTAO's heuristic for thin occluders is thin_occluder):
# a number passed to every method does not reach it
register(Method("gtao", partial(gtao, steps=GTAO_STEPS), default_samples=3, fetch="bilinear", samples="slices",
                taps=_gtao_taps, quantity=_cosine_ao, thickness_kinds=("layers",),
                summary="GTAO (Jimenez et al. 2016): horizons per slice, cosine AO; SAMPLES = slices of 3 steps "
                        "a side"))
# Therrien et al. 2023 on GTAO's slices and taps: the cosine weighting scored against cosine AO,
# the uniform one (the solid angle of each sector) against uniform AO
register(Method("vbao", partial(vbao, steps=VBAO_STEPS), default_samples=3, fetch="bilinear", samples="slices",
                taps=_vbao_taps, quantity=_cosine_ao, thickness_kinds=("constant", "layers"),
                summary="VBAO (Therrien et al. 2023): a bitmask of occluded sectors per slice, thickness 0.5 R by "
                        "default, cosine AO; SAMPLES = slices of 3 steps a side"))
register(Method("vbao_uniform", partial(vbao, steps=VBAO_STEPS, weighting="uniform"), default_samples=3,
                fetch="bilinear", samples="slices", taps=_vbao_taps, quantity=_uniform_ao,
                thickness_kinds=("constant", "layers"),
                summary="VBAO with each sector weighed by its solid angle: uniform AO; SAMPLES = slices of 3 steps "
                        "a side"))
register(Method("hbao", partial(hbao, steps=HBAO_STEPS), default_samples=8, fetch="nearest", fetch_parameter=None,
                samples="directions", taps=_hbao_taps, quantity=_uniform_ao,
                summary="HBAO (Bavoil et al. 2008): horizon angles, uniform AO; SAMPLES = directions of 4 steps"))
register(Method("alchemy", alchemy, default_samples=12, fetch="nearest", fetch_parameter=None,
                quantity=_obscurance, summary="Alchemy AO (McGuire et al. 2011): obscurance estimator on a disk"))
register(Method("sao", sao, default_samples=12, fetch="nearest", fetch_parameter=None,
                quantity=_obscurance, summary="SAO (McGuire et al. 2012): spiral samples, falloff (r^2 - v.v)^3"))


# --------------------------------------------------------------------------- object-space models
def _no_taps(n: int) -> int:
    """An object-space model reads no depth buffer."""
    return 0


def _sky_visibility(normal_clamp: bool = False) -> str:
    """The vegetation models estimate the visibility of the whole sky (AO with no limit)."""
    return "sky visibility"


def _uniform_sky_visibility(normal_clamp: bool = False) -> str:
    """Bunnell's disks (Listing 14-1's term) estimate the uniformly weighted visibility of the
    whole sky: a solid-angle fraction per disk, no distance limit."""
    return "uniform sky visibility"


def _object_space(name, function, quantity, summary):
    """An object-space model: no samples, no depth fetch, the scene's description passed."""
    return register(Method(name, function, default_samples=1, fetch="none", fetch_parameter=None, taps=_no_taps,
                           quantity=quantity, samples=None, needs_scene=True, summary=summary))


_object_space("hegeman", hegeman_gbuffer, _sky_visibility,
              "Hegeman et al. 2006: canopy sphere (Eqs. 4-6) and ground occluder (Eqs. 7-8); vegetation scenes only")
# Sec. 3, Fig. 8: the canopy's minimum-volume enclosing ellipsoid
_object_space("hegeman_ellipsoid", partial(hegeman_gbuffer, shell="ellipsoid"), _sky_visibility,
              "Hegeman et al. 2006 with an ellipsoidal canopy shell (Sec. 3, Fig. 8); vegetation scenes only")
# Sec. 5: three spheres by k-means, each point in the closest
_object_space("hegeman_multishell", partial(hegeman_gbuffer, shell="multishell", k=3), _sky_visibility,
              "Hegeman et al. 2006 with three k-means spheres (Sec. 5, Fig. 3); vegetation scenes only")
_object_space("reeves_blau", reeves_blau_gbuffer, _sky_visibility,
              "Reeves & Blau 1985: exp(-k depth in the canopy), k the leaves' extinction; the baseline of "
              "Hegeman et al.; vegetation scenes only")
_object_space("poisson", poisson_gbuffer, _sky_visibility,
              "Poisson leaf cloud in the canopy's bounding sphere: the expected visibility (1/pi) int exp(-sigma L) "
              "cos, sigma = n A / 2 from the leaf statistics, nothing fitted; leaves and ground; vegetation scenes "
              "only")
# the meshes subdivided to max_edge="auto", so that coarse walls (the Cornell box's) become surfaces of disks
_object_space("bunnell", partial(bunnell_gbuffer, max_edge="auto"), _uniform_sky_visibility,
              "Bunnell 2005 (GPU Gems 2 ch. 14): a disk per vertex, Listing 14-1's shadow term, 2 passes, tree of "
              "aggregated disks; object space, any mesh scene")
_object_space("ren", sphere_set_gbuffer, _sky_visibility,
              "Ren et al. 2006: the scene as k = 32 inscribed spheres, SH order 4, log vectors summed and "
              "exponentiated once (SHEXP, hybrid); cosine AO; any closed mesh scene")
