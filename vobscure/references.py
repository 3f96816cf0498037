"""The registry of references: every exact (converged) quantity an estimate is scored against.

Each entry (:class:`Reference`) says what the reference measures and how it is computed:

- the quantity it measures (``"cosine AO"``, ``"ball VO"``, ...), and the one it measures
  with the normal clamp when it follows the estimate's ``normal_clamp`` (``"half-ball VO"``);
- what computes it: :func:`vobscure.vo_reference` (the converged screen-space VO, from the
  G-buffer alone) or :func:`vobscure.ground_truth` with one of its quantities
  (:data:`vobscure.groundtruth.QUANTITIES`), the hemisphere weighting and whether the
  distance is limited to the ball radius;
- its sampling parameter (``rays``, ``volume_samples`` or ``screen_samples`` of a sweep
  configuration) and the estimate's options it shares (``normal_clamp``, ``falloff``, ...);
- how it is cached: the function of :mod:`vobscure.experiments.cache` that computes it
  through the disk cache (:attr:`Reference.cached_by`).

:mod:`vobscure.methods` takes the estimators' quantities from here (:data:`QUANTITIES`), and
:func:`vobscure.experiments.sweep`, ``vobscure compare`` (its ``--reference`` choices and
help) and the figures read the names and the arguments from here. Adding a reference is one
:data:`REFERENCES` entry.

Examples
--------
>>> from vobscure import references
>>> references.names()
('screen', 'volumetric', 'shell', 'ao', 'ao_uniform', 'obscurance', 'sky', 'sky_uniform')
>>> sky = references.get("sky")
>>> sky.ground_truth, sky.weighting, sky.limited, sky.samples, sky.quantity(normal_clamp=True)
('ao', 'cosine', False, 'rays', 'sky visibility')
>>> sky.arguments(radius=0.5, seed=0, rays=64)
{'quantity': 'ao', 'radius': None, 'seed': 0, 'weighting': 'cosine', 'rays': 64}
"""

from __future__ import annotations

from dataclasses import dataclass

from .groundtruth import QUANTITIES as GROUND_TRUTH_QUANTITIES

__all__ = ["Reference", "Quantity", "REFERENCES", "QUANTITIES", "SAMPLE_PARAMETERS", "SHELL_THICKNESS", "WORLD_VO",
           "get", "names", "usable"]

#: The sampling parameters of the references, as named in a sweep configuration and in
#: ``vobscure compare``, and the keyword of the computing function each is passed as.
SAMPLE_PARAMETERS = {"rays": "rays", "volume_samples": "samples", "screen_samples": "samples"}
#: The thickness of the shell reference's surfaces when the estimate has none, as a fraction of
#: the ball radius: every surface is as thick as the ball's radius, so that within a ball
#: nothing behind a surface is taken as empty (docs/groundtruth.md).
SHELL_THICKNESS = 1.0

#: View-ray segments per pixel of the ``screen`` reference by default (:func:`vobscure.vo_reference`
#: in ``vobscure compare`` and sweeps): 8 groups of a randomly shifted 56-point lattice, the
#: fewest tried whose reported standard error is below that of the 800 jittered rays it
#: replaced (and of 2048 stratified points of the ball) on the atrium's and the Cornell box's
#: views (mean, RMS and 95th percentile; ``docs/screenspace.md``, "The converged reference").
SCREEN_SAMPLES = 448
#: The estimate's options a reference may share with it (passed on under the same name).
_SHARED_OPTIONS = ("normal_clamp", "thickness", "falloff", "allow_open")


@dataclass(frozen=True)
class Reference:
    """One reference: what it measures, how it is computed and cached.

    Parameters
    ----------
    name : str
        Registry key, as written in ``--reference`` and in the result columns
        (``"ao_uniform"``).
    measures : str
        The quantity it measures (a key of :data:`QUANTITIES`), without the normal clamp.
    measures_clamped : str or None
        The quantity it measures with the estimate's ``normal_clamp`` (the half-ball), for a
        reference that follows it; None: the same quantity either way.
    ground_truth : str or None
        The ``quantity`` of :func:`vobscure.ground_truth` that computes it (``"ao"``,
        ``"obscurance"``, ``"volumetric"``); None: :func:`vobscure.vo_reference`, the
        converged screen-space VO, which needs the G-buffer only.
    weighting : {"cosine", "uniform"} or None
        The hemisphere weighting of a ray-cast reference (None: not applicable).
    limited : bool
        Whether occluders count only within the ball radius (False: the whole sky).
    samples : str
        Its sampling parameter, a key of :data:`SAMPLE_PARAMETERS`.
    options : tuple of str
        The estimate's options it is computed with (some of ``normal_clamp``, ``thickness``,
        ``falloff``, ``allow_open``).
    closed_scene : bool
        It needs a closed (watertight) scene: an inside test.
    screen_limit : bool
        :func:`vobscure.vo_reference` is the limit of an estimator of its quantities with
        infinitely many samples, so that an estimate's error against the screen reference is
        its sampling error alone.
    default_thickness : float or None
        With ``"thickness"`` among its options: the thickness, as a fraction of the ball radius,
        used when the estimate has none (the shell reference's surfaces must have one).
    stand_in : str or None
        The reference that scores an estimate of its quantity when this one cannot be computed
        on the scene (a scene that is not closed): ``"shell"`` for ``"volumetric"``.
    summary : str
        One line for ``--help`` and the docs.
    """

    name: str
    measures: str
    ground_truth: str | None
    samples: str
    measures_clamped: str | None = None
    weighting: str | None = None
    limited: bool = True
    options: tuple = ()
    closed_scene: bool = False
    screen_limit: bool = False
    default_thickness: float | None = None
    stand_in: str | None = None
    summary: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ValueError(f"Reference name must be an identifier such as 'ao', got {self.name!r}")
        if self.ground_truth is not None and self.ground_truth not in GROUND_TRUTH_QUANTITIES:
            raise ValueError(f"Reference {self.name!r}: ground_truth must be None or one of "
                             f"{', '.join(GROUND_TRUTH_QUANTITIES)}, got {self.ground_truth!r}")
        if self.samples not in SAMPLE_PARAMETERS:
            raise ValueError(f"Reference {self.name!r}: samples must be one of {', '.join(SAMPLE_PARAMETERS)}, "
                             f"got {self.samples!r}")
        if self.default_thickness is not None and "thickness" not in self.options:
            raise ValueError(f"Reference {self.name!r}: default_thickness needs 'thickness' among its options")
        object.__setattr__(self, "options", tuple(self.options))
        for option in self.options:
            if option not in _SHARED_OPTIONS:
                raise ValueError(f"Reference {self.name!r}: options must be some of {', '.join(_SHARED_OPTIONS)}, "
                                 f"got {option!r}")

    @property
    def needs_scene(self) -> bool:
        """Whether it is ray cast in the scene (False: the G-buffer alone suffices)."""
        return self.ground_truth is not None

    @property
    def cached_by(self) -> str:
        """The function of :mod:`vobscure.experiments.cache` that computes it through the disk
        cache: ``"screen_reference_cached"`` or ``"ground_truth_cached"``."""
        return "ground_truth_cached" if self.needs_scene else "screen_reference_cached"

    def quantity(self, normal_clamp: bool = False) -> str:
        """The quantity it measures with the estimate's ``normal_clamp``."""
        return self.measures_clamped if normal_clamp and self.measures_clamped else self.measures

    def arguments(self, *, radius: float, seed: int, **settings) -> dict:
        """The keyword arguments of the computing function (:attr:`cached_by`, and so
        :func:`vobscure.ground_truth` or :func:`vobscure.vo_reference`).

        ``settings`` holds the sampling parameter :attr:`samples` and the :attr:`options`;
        others are ignored, so that a sweep configuration's whole set can be passed.
        """
        missing = [k for k in (self.samples, *self.options) if k not in settings]
        if missing:
            raise ValueError(f"reference {self.name!r} needs {', '.join(missing)}")
        count = {SAMPLE_PARAMETERS[self.samples]: settings[self.samples]}
        shared = {k: settings[k] for k in self.options}
        if self.default_thickness is not None and shared.get("thickness") is None:
            shared["thickness"] = self.default_thickness * radius
        if not self.needs_scene:
            return dict(radius=radius, **count, **shared, seed=seed)
        args = dict(quantity=self.ground_truth, radius=radius if self.limited else None, seed=seed)
        if self.weighting is not None:
            args["weighting"] = self.weighting
        return {**args, **count, **shared}


@dataclass(frozen=True)
class Quantity:
    """A quantity an estimator estimates, and the reference that measures it exactly.

    Attributes
    ----------
    name : str
        Human-readable name, e.g. ``"half-ball VO"``.
    reference : str
        The :data:`REFERENCES` entry that measures it.
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


def _registry(*entries: Reference) -> dict[str, Reference]:
    out = {}
    for ref in entries:
        if ref.name in out:
            raise ValueError(f"two references named {ref.name!r}")
        out[ref.name] = ref
    return out


#: The references, by name, in the order of the result columns.
REFERENCES = _registry(
    Reference("screen", "screen-space ball VO", None, "screen_samples",
              measures_clamped="screen-space half-ball VO", options=("normal_clamp", "thickness", "falloff"),
              screen_limit=True,
              summary="the converged screen-space VO (vobscure.vo_reference, same settings as the estimate)"),
    Reference("volumetric", "ball VO", "volumetric", "volume_samples", measures_clamped="half-ball VO",
              options=("falloff", "normal_clamp", "allow_open"), closed_scene=True, screen_limit=True,
              stand_in="shell",
              summary="the ray-cast world-space VO of the ball (half-ball with the normal clamp); closed scenes"),
    Reference("shell", "shell ball VO", "volumetric", "volume_samples", measures_clamped="shell half-ball VO",
              options=("falloff", "normal_clamp", "thickness"), screen_limit=True,
              default_thickness=SHELL_THICKNESS,
              summary="the ray-cast world-space VO of surfaces a thickness thick behind them (the estimate's "
                      "--thickness, else the radius): any scene, closed or not"),
    Reference("ao", "cosine AO", "ao", "rays", weighting="cosine",
              summary="ray-cast ambient occlusion within the radius, cosine-weighted"),
    Reference("ao_uniform", "uniform AO", "ao", "rays", weighting="uniform",
              summary="ray-cast ambient occlusion within the radius, uniformly weighted"),
    Reference("obscurance", "obscurance", "obscurance", "rays", weighting="cosine",
              summary="ray-cast obscurance within the radius (linear falloff), cosine-weighted"),
    Reference("sky", "sky visibility", "ao", "rays", weighting="cosine", limited=False,
              summary="ray-cast sky visibility (ambient occlusion with no distance limit), cosine-weighted"),
    Reference("sky_uniform", "uniform sky visibility", "ao", "rays", weighting="uniform", limited=False,
              summary="ray-cast sky visibility, uniformly weighted"),
)


def _quantities() -> dict[str, Quantity]:
    out = {}
    for ref in REFERENCES.values():
        clamps = (False, True) if ref.measures_clamped else (None,)
        for clamp in clamps:
            q = Quantity(ref.quantity(bool(clamp)), ref.name, normal_clamp=clamp, screen_limit=ref.screen_limit)
            if q.name in out:
                raise ValueError(f"two references measure {q.name!r}")
            out[q.name] = q
    return out


#: The quantities the references measure, by name: what :mod:`vobscure.methods` says an
#: estimator estimates.
QUANTITIES = _quantities()


def names() -> tuple[str, ...]:
    """The reference names, in registry order."""
    return tuple(REFERENCES)


def get(name: str) -> Reference:
    """The reference registered as ``name``; the error lists the valid names."""
    return lookup(REFERENCES, name, "reference")


def lookup(registry: dict, name, what: str):
    """``registry[name]``, or a ValueError naming the unknown ``what`` and listing the valid names
    (the lookup of this registry and of :mod:`vobscure.methods`')."""
    try:
        return registry[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown {what} {name!r}; expected one of {', '.join(registry)}") from None


#: The world-space VO references, in the order of preference: what the screen-space term of an
#: error decomposition (:func:`vobscure.metrics.decompose`) is measured against.
WORLD_VO = ("volumetric", "shell")


def usable(name: str, scene) -> str | None:
    """The reference that scores the quantity of reference ``name`` on ``scene``: ``name`` when it
    can be computed there, else its :attr:`Reference.stand_in` (None when there is none).

    Examples
    --------
    >>> import vobscure as vo
    >>> usable("volumetric", vo.scenes.slab()), usable("volumetric", vo.scenes.leaf_cloud())
    ('volumetric', 'shell')
    """
    ref = get(name)
    if not ref.closed_scene or scene.is_watertight:
        return name
    return ref.stand_in


def describe() -> str:
    """One line per reference, for ``--help``."""
    return "\n".join(f"{r.name}: {r.summary}" for r in REFERENCES.values())
