"""Figure modules: one module per figure, each with ``make(out_dir, quick=False) -> list[Path]``.

``quick=True`` draws the same figure with fewer samples and smaller images, in seconds; CI
runs every figure that way. Figures are drawn on matplotlib ``Figure`` objects with the Agg
canvas (never ``pyplot``, never a display) and written atomically.

:data:`FIGURES` maps each figure's name to its module; :func:`make_all` runs some or all of
them (``vobscure figures`` is built on it). The figures of Loos & Sloan 2010 are
``fig4_noise``, ``fig5_thickness``, ``fig6_normals``, ``fig7_lines_vs_points``,
``fig8_dual_radii`` and ``table1_timings``; ``docs/figures.md`` shows each with what it
confirms. ``patterns_quality`` is the analytic sample-pattern measure of Sec. 4.5
(``docs/patterns_results.md``).
"""

from __future__ import annotations

import importlib
from pathlib import Path

__all__ = ["FIGURES", "make_all", "conventions", "screenspace_claims", "fig4_noise", "fig5_thickness",
           "fig6_normals", "fig7_lines_vs_points", "fig8_dual_radii", "table1_timings",
           "error_decomposition", "temporal_stability", "patterns_quality", "hegeman_fig2", "hegeman_fig8",
           "hegeman_fig9", "hegeman_fig10", "hegeman_tradeoff", "cornell_shading",
           "canopy_models", "ren_spheres", "proxy_bunny"]

#: Figure name -> module name in this package, in the order :func:`make_all` runs them.
#: Figures 5-7 share the measurements of :func:`vobscure.experiments.claims.measurement`
#: (cached per process), so running them together costs little more than the first.
FIGURES = {
    "conventions": "conventions",
    "screenspace_claims": "screenspace_claims",
    "fig4_noise": "fig4_noise",
    "fig5_thickness": "fig5_thickness",
    "fig6_normals": "fig6_normals",
    "fig7_lines_vs_points": "fig7_lines_vs_points",
    "fig8_dual_radii": "fig8_dual_radii",
    "table1_timings": "table1_timings",
    "error_decomposition": "error_decomposition",
    "temporal_stability": "temporal_stability",
    "patterns_quality": "patterns_quality",
    "hegeman_fig2": "hegeman_fig2",
    "hegeman_fig8": "hegeman_fig8",
    "hegeman_fig9": "hegeman_fig9",
    "hegeman_fig10": "hegeman_fig10",
    "hegeman_tradeoff": "hegeman_tradeoff",
    "cornell_shading": "cornell_shading",
    "canopy_models": "canopy_models",
    "ren_spheres": "ren_spheres",
    "proxy_bunny": "proxy_bunny",
}


def make_all(out_dir, quick: bool = False, names=None, *, progress: bool = False) -> list[Path]:
    """Run the ``make`` of each named figure (default: all of :data:`FIGURES`).

    Parameters
    ----------
    out_dir : str or path-like
        Directory every figure writes into; created if missing.
    quick : bool, optional
        Passed to every ``make``: small, fast versions (what CI runs).
    names : iterable of str, optional
        Names of :data:`FIGURES`, run in the order given; default all, in registry order.
    progress : bool, optional
        A tqdm progress bar over the figures (off by default, as everywhere; the command turns it on).

    Returns
    -------
    list of Path
        Every file written, in order.

    Raises
    ------
    ValueError
        If a name is not in :data:`FIGURES` (the message lists the valid names).

    Examples
    --------
    >>> from vobscure.experiments.figures import FIGURES
    >>> "fig8_dual_radii" in FIGURES and "table1_timings" in FIGURES
    True
    """
    from tqdm.auto import tqdm

    names = list(FIGURES) if names is None else [names] if isinstance(names, str) else list(names)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        raise ValueError(f"unknown figure name(s) {', '.join(map(repr, unknown))}; expected one of "
                         f"{', '.join(FIGURES)}")
    paths = []
    bar = tqdm(names, desc="figures", unit="figure", disable=not progress)
    for name in bar:
        bar.set_postfix_str(name)
        module = importlib.import_module(f"{__name__}.{FIGURES[name]}")
        paths.extend(Path(p) for p in module.make(out_dir, quick=bool(quick)))
    return paths
