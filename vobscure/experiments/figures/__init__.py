"""Figure modules: one module per figure, each a ``measure`` and a ``plot``.

A figure module ``NAME.py`` in this package defines

``measure(profile) -> rows``
    Everything the figure shows, measured at a :class:`Profile` (quick or full: sizes,
    samples, seeds): a list of dicts (a :class:`Rows`, which can also carry images and title
    numbers). The rows are written as ``NAME.csv``, the images and title numbers, if any, as
    ``NAME.npz``.
``plot(rows, fig)``
    Draws on the matplotlib ``Figure`` it is given, from the rows read back from those files
    (matplotlib only; nothing is measured), which the driver writes as ``NAME.png``.

and optionally ``FIGSIZE`` (inches, default :data:`DEFAULT_FIGSIZE`), ``DPI`` (default 100), ``ORDER`` (its place in
:func:`names`), and ``markdown(rows) -> str`` (tables for the docs, written as ``NAME.md``).
A ``measure`` that takes a keyword of :data:`_SHARED` is given that shared measurement, made
once per :func:`make` (when the first figure asks for it), passed to every figure of the run
that asks for it and dropped after the last one: ``claims``, the claims' measurement
(:func:`~vobscure.experiments.figures._common.claims_measurements`), and ``trees``, the
measurements of :mod:`vobscure.experiments.trees`
(:func:`~vobscure.experiments.figures._common.tree_measurements`). Called alone, such a
``measure`` makes its own.

Figures are found by discovery: every module of this package whose name does not start with
an underscore. :func:`names` orders them by ``ORDER`` (the paper's figures first), then by
name. ``vobscure figures NAME ... [--quick] [--out DIR] [--from-csv]`` runs :func:`make` or
:func:`replot`; ``docs/figures.md`` shows each figure with what it confirms and how to add one.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import pkgutil
import warnings
from pathlib import Path

from ._common import Profile, Rows, claims_measurements, read_rows, tree_measurements, write_rows

__all__ = ["Profile", "Rows", "DEFAULT_FIGSIZE", "names", "module", "measure", "plot", "make", "replot",
           "make_all"]

#: Size (width, height) in inches of a figure that sets no ``FIGSIZE``.
DEFAULT_FIGSIZE = (16.0, 12.0)
#: Place in :func:`names` of a figure that sets no ``ORDER``: after the ordered ones.
_LAST = 10 ** 6
#: Measurements several figures share: keyword of ``measure`` -> function of the profile.
_SHARED = {"claims": claims_measurements, "trees": tree_measurements}


def __getattr__(name: str):
    """``FIGURES`` (every figure name mapped to itself), deprecated: a ``DeprecationWarning``
    naming :func:`names`, which lists the figures."""
    if name == "FIGURES":
        warnings.warn("vobscure.experiments.figures.FIGURES is deprecated; use "
                      "vobscure.experiments.figures.names()", DeprecationWarning, stacklevel=2)
        return {n: n for n in names()}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def names(package: str = __name__) -> list[str]:
    """The figures of ``package``: its modules not starting with ``_``, by ``ORDER``, then name.

    Examples
    --------
    >>> names()[:3]
    ['conventions', 'screenspace_claims', 'fig4_noise']
    """
    pkg = importlib.import_module(package)
    found = [m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_")]
    return sorted(found, key=lambda n: (getattr(module(n, package), "ORDER", _LAST), n))


def module(name: str, package: str = __name__):
    """The figure module ``name`` of ``package`` (a ValueError lists the valid names)."""
    if not isinstance(name, str) or name.startswith("_") or "." in name \
            or importlib.util.find_spec(f"{package}.{name}") is None:
        valid = ", ".join(names(package))
        raise ValueError(f"unknown figure name {name!r}; expected one of {valid}")
    return importlib.import_module(f"{package}.{name}")


def _paths(name: str, out_dir) -> dict:
    out_dir = Path(out_dir)
    return {ext: out_dir / f"{name}.{ext}" for ext in ("png", "csv", "npz", "md")}


def _needs(name: str, package: str) -> list[str]:
    """The shared measurements (keys of :data:`_SHARED`) the figure's ``measure`` takes."""
    params = inspect.signature(module(name, package).measure).parameters
    return [key for key in _SHARED if key in params]


def measure(name: str, profile: Profile, *, package: str = __name__, shared=None) -> Rows:
    """``measure`` of the figure ``name`` at ``profile``, as :class:`Rows`.

    ``shared`` (a dict) holds the shared measurements (:data:`_SHARED`) already made; those
    the figure asks for are made and added to it when missing.
    """
    shared = {} if shared is None else shared
    kwargs = {}
    for key in _needs(name, package):
        if key not in shared:
            shared[key] = _SHARED[key](profile)
        kwargs[key] = shared[key]
    rows = module(name, package).measure(profile, **kwargs)
    return rows if isinstance(rows, Rows) else Rows(rows)


def plot(name: str, rows, *, package: str = __name__):
    """A new Agg ``Figure`` of ``FIGSIZE`` with the figure ``name``'s ``plot`` drawn on it."""
    from ..common import new_figure

    mod = module(name, package)
    fig = new_figure(*getattr(mod, "FIGSIZE", DEFAULT_FIGSIZE), dpi=getattr(mod, "DPI", 100))
    mod.plot(rows, fig)
    return fig


def _draw(name, out, package) -> Path:
    from ..common import save_figure

    rows = read_rows(out["csv"], out["npz"])
    return save_figure(plot(name, rows, package=package), out["png"])


def make(names_, out_dir, profile: Profile | None = None, *, package: str = __name__,
         progress: bool = False) -> list[Path]:
    """Measure, write and draw figures: for each name, ``measure`` -> ``NAME.csv`` (and
    ``NAME.npz``, ``NAME.md``) -> ``plot`` of the rows read back -> ``NAME.png``.

    The PNG is drawn from the files, as :func:`replot` draws it, so that a re-plot without
    measuring gives the same figure.

    Parameters
    ----------
    names_ : str or iterable of str
        Figure names (:func:`names`), run in the order given.
    out_dir : str or path-like
        Directory of every file; created if missing.
    profile : Profile, optional
        Default ``Profile()`` (full).
    package : str, optional
        The package the figures are found in (this one by default).
    progress : bool, optional
        A tqdm progress bar over the figures.

    Returns
    -------
    list of Path
        Every file written, in order (per figure: CSV, NPZ, MD, PNG as present).
    """
    from tqdm.auto import tqdm

    from ..common import write_text

    todo = [names_] if isinstance(names_, str) else list(names_)
    for name in todo:
        module(name, package)               # every name checked before anything is measured
    profile = Profile() if profile is None else profile
    if not isinstance(profile, Profile):
        raise ValueError(f"profile must be a Profile, got {type(profile).__name__}")
    # a shared measurement is kept until the last figure of the run that asks for it
    last_use = {key: i for i, name in enumerate(todo) for key in _needs(name, package)}
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    shared, written = {}, []
    bar = tqdm(todo, desc="figures", unit="figure", disable=not progress)
    for i, name in enumerate(bar):
        bar.set_postfix_str(name)
        out = _paths(name, out_dir)
        rows = measure(name, profile, package=package, shared=shared)
        for key in [k for k, last in last_use.items() if last == i]:
            shared.pop(key, None)
        written += write_rows(rows, out["csv"], out["npz"])
        markdown = getattr(module(name, package), "markdown", None)
        if markdown is not None:
            written.append(write_text(out["md"], markdown(rows)))
        written.append(_draw(name, out, package))
    return written


def replot(names_, out_dir, *, package: str = __name__) -> list[Path]:
    """Draw figures again from the ``NAME.csv`` (and ``NAME.npz``) that :func:`make` wrote in
    ``out_dir``, measuring nothing; returns the PNGs written.

    Raises
    ------
    FileNotFoundError
        If a figure's CSV is not in ``out_dir`` (the message says to make it first).
    """
    todo = [names_] if isinstance(names_, str) else list(names_)
    for name in todo:
        module(name, package)
        csv_path = _paths(name, out_dir)["csv"]
        if not csv_path.is_file():
            raise FileNotFoundError(f"no {csv_path}: make the figure {name!r} first (without --from-csv)")
    return [_draw(name, _paths(name, out_dir), package) for name in todo]


def make_all(out_dir, quick: bool = False, names=None, *, progress: bool = False) -> list[Path]:
    """:func:`make` of the named figures (default all, in the order of :func:`names`) at
    ``Profile(quick=quick)``."""
    chosen = globals()["names"]() if names is None else names
    return make(chosen, out_dir, Profile(quick=bool(quick)), progress=progress)


def deprecated_make(module_name: str):
    """The deprecated ``make(out_dir, quick=False, *, seed=0)`` of the figure module
    ``module_name`` (its ``__name__``): a ``DeprecationWarning`` naming ``vobscure figures
    NAME`` and :func:`vobscure.experiments.figures.make`, then that driver on the one figure at
    ``Profile(quick=quick, seed=seed)``; returns the files written.

    A figure module keeps its old entry point as the one line ``make = deprecated_make(__name__)``.
    """
    name = module_name.rpartition(".")[2]

    def deprecated(out_dir, quick: bool = False, *, seed: int = 0) -> list[Path]:
        warnings.warn(f"{module_name}.make(out_dir, quick) is deprecated; use `vobscure figures {name}` or "
                      f"vobscure.experiments.figures.make({name!r}, out_dir, profile)",
                      DeprecationWarning, stacklevel=2)
        return make(name, out_dir, Profile(quick=quick, seed=seed))

    deprecated.__name__ = deprecated.__qualname__ = "make"
    deprecated.__module__, deprecated.__doc__ = module_name, (
        f"Deprecated: ``vobscure figures {name}``, or :func:`vobscure.experiments.figures.make` "
        f"``({name!r}, out_dir, Profile(quick=quick, seed=seed))``, which this runs after a warning.")
    return deprecated
