"""Loos & Sloan 2010, Fig. 5: the thickness model off and on at silhouettes.

One PNG, ``fig5_thickness.png``, and the numbers it plots, ``fig5_thickness.csv``. The scene
is the Cornell box through its own camera (256 x 256; 48 x 48 with ``quick``), the ball
radius R = 0.1 x the scene's extent, seed 0; the G-buffer and the ground truth are those of
:func:`vobscure.experiments.claims.measurement` (so the numbers agree with
``docs/results.md``, and a process that also draws Fig. 6 or Fig. 7 computes them once).

(a) Visibility, half-ball (``normal_clamp=True``; ``normal_clamp=False`` draws the ball):
    ``vo_line`` (9 lines) and ``vo_area`` (1 area sample) without the thickness model and
    with ``thickness`` = :data:`THICKNESS_SHOWN` x R, one frame each, no blur, beside the
    Embree ground truth (``ground_truth(quantity="volumetric")``). Titles: RMSE and bias
    in the silhouette band and on its far side.
(b) Signed error (estimate - ground truth) of the same four images (red: darker than the
    truth, blue: more open), and the silhouette band of
    :func:`vobscure.experiments.claims.silhouette_mask` (pixels within a few pixels of a
    relative depth jump > 10 %; its far side, the surface behind the silhouette where the
    paper's shadowed edges are, in a darker shade).
(c) RMSE in the silhouette band against thickness / R (log axis), lines and area, ball and
    half-ball; the thickness-off value of each at the left ("off"). The Cornell box's wall
    thickness (0.1) and box width (0.6) in units of R are marked: the model gives every
    surface one thickness, and no single value fits both.
(d) Bias on the far side of the silhouettes against thickness / R: the halo of Fig. 5 is
    the large negative bias with the model off.

Regenerate with::

    python -c "from vobscure.experiments.figures import fig5_thickness as f; f.make('docs/img')"

(about 3-4 minutes, most of it the ground truth; ``quick=True`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.3 and Fig. 5.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "FACTORS", "THICKNESS_SHOWN",
           "METHODS"]

#: Name of the PNG :func:`make` writes.
FILENAME = "fig5_thickness.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "fig5_thickness.csv"
#: Thicknesses of the sweep, as fractions of the ball radius (full, quick).
FACTORS = {False: (0.125, 0.177, 0.25, 0.354, 0.5, 0.707, 1.0, 1.41, 2.0, 2.83, 4.0),
           True: (0.25, 1.0, 4.0)}
#: The thickness of the images, a fraction of R: the value docs/results.md quotes (between
#: the box's 0.1-thick walls, 0.27 R, and its 0.6-wide boxes, 1.6 R).
THICKNESS_SHOWN = 0.5
#: The estimators compared: (label, method, samples).
METHODS = (("lines 9", "line", 9), ("area 1", "area", 1))
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"samples": (1, 64), "normal_clamp": (0, 1), "factor": (0.0, 100.0),
              "thickness": (0.0, 100.0), "rmse_band": (0.0, 1.0), "bias_band": (-1.0, 1.0),
              "rmse_far": (0.0, 1.0), "bias_far": (-1.0, 1.0), "rmse_all": (0.0, 1.0),
              "bias_all": (-1.0, 1.0), "pixels_band": (1, 10 ** 8), "pixels_far": (1, 10 ** 8)}

_SCENE = "cornell_box"
_COLUMNS = ("method", "samples", "normal_clamp", "factor", "thickness", "rmse_band", "bias_band",
            "rmse_far", "bias_far", "rmse_all", "bias_all", "pixels_band", "pixels_far")
_COLORS = {"lines 9": "#1f77b4", "area 1": "#2ca02c"}
_WALL, _BOX = 0.1, 0.6     # the Cornell box's wall thickness and box width (scene units)


def make(out_dir, quick: bool = False, *, size=None, seed: int = 0,
         normal_clamp: bool = True) -> list[Path]:
    """Draw ``fig5_thickness.png`` and write ``fig5_thickness.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        48 x 48 pixels, fewer reference samples and three thicknesses (seconds), for CI.
    size : (int, int), optional
        Image size; default 256 x 256 (48 x 48 with ``quick``).
    seed : int, optional
        Seed of the estimators' noise and of the ground truth.
    normal_clamp : bool, optional
        Which quantity panels (a) and (b) show: the half-ball (default, where the silhouettes
        are the main error) or the ball. Panels (c) and (d) always show both.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``, each written atomically. The CSV has
        one row per (method, normal_clamp, thickness); ``factor`` and ``thickness`` are empty
        for the model switched off.

    Examples
    --------
    >>> from vobscure.experiments.figures import fig5_thickness
    >>> fig5_thickness.FILENAME
    'fig5_thickness.png'
    """
    from .. import claims as C
    from ..common import new_figure
    from ._common import size_for, write_figure

    quick = bool(quick)
    size = size_for(quick, size)
    m = C.measurement(_SCENE, size=size, seed=seed, quick=quick)
    width = max(1, int(round(min(size) / 128)))   # "a few pixels", as in claims
    band, far = C.silhouette_mask(m.gb.depth, width=width)
    rows, shown = _sweep(m, band, far, FACTORS[quick], seed, bool(normal_clamp))

    fig = new_figure(17.0, 12.5)
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.15], hspace=0.03)
    _images(parts[0], parts[1], m, shown, rows, band, far, bool(normal_clamp))
    _plots(parts[2], rows, m.radius)
    w, h = size
    fig.suptitle(f"Loos & Sloan 2010, Fig. 5 / Sec. 4.3: the thickness model at silhouettes "
                 f"(Cornell box, {w} x {h}, R = {m.radius:.3g} = 0.1 x extent, seed {seed}"
                 f"{', quick' if quick else ''})", fontsize=13)
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, _COLUMNS)


# ----------------------------------------------------------------------------- data
def _estimate(gb, method, samples, *, radius, normal_clamp, thickness, seed):
    from ... import methods

    return methods.get(method).run(gb, samples, radius=radius, normal_clamp=normal_clamp,
                                   thickness=thickness, seed=seed)


def _sweep(m, band, far, factors, seed, normal_clamp_shown):
    """Error rows for every (method, normal_clamp, thickness) and the images of panel (a)."""
    from ...metrics import error

    rows, shown = [], {}
    for label, method, samples in METHODS:
        for nc in (False, True):
            truth = m.truth[nc].value
            for f in (None,) + tuple(factors):
                t = None if f is None else f * m.radius
                v = _estimate(m.gb, method, samples, radius=m.radius, normal_clamp=nc, thickness=t,
                              seed=seed)
                e_band, e_far, e_all = (error(v, truth, mask=k) for k in (band, far, None))
                rows.append({"method": label, "samples": samples, "normal_clamp": nc, "factor": f,
                             "thickness": t, "rmse_band": e_band.rmse, "bias_band": e_band.bias,
                             "rmse_far": e_far.rmse, "bias_far": e_far.bias, "rmse_all": e_all.rmse,
                             "bias_all": e_all.bias, "pixels_band": e_band.pixels,
                             "pixels_far": e_far.pixels})
            if nc == normal_clamp_shown:
                for f in (None, THICKNESS_SHOWN):
                    t = None if f is None else f * m.radius
                    shown[(label, f)] = _estimate(m.gb, method, samples, radius=m.radius,
                                                  normal_clamp=nc, thickness=t, seed=seed)
    return rows, shown


# ----------------------------------------------------------------------------- drawing
def _images(top, bottom, m, shown, rows, band, far, nc):
    import matplotlib as mpl

    from ...metrics import error
    from ._common import BACKGROUND, error_panel, fmt, image_panel

    truth = m.truth[nc]
    panels = []
    for label, _, _ in METHODS:
        for f in (None, THICKNESS_SHOWN):
            v = shown[(label, f)]
            e_band, e_far = error(v, truth.value, mask=band), error(v, truth.value, mask=far)
            what = "thickness off" if f is None else f"thickness {f:g} R"
            panels.append((label, f, v, f"{label}, {what}\nband RMSE {fmt(e_band.rmse)}, "
                                        f"far-side bias {e_far.bias:+.3f}"))
    axes = top.subplots(1, len(panels) + 1)
    for ax, (_, _, img, title) in zip(axes, panels):
        im = image_panel(ax, img, title)
    image_panel(axes[-1], truth.value, f"Embree ground truth\n{truth.samples} points per ball, "
                f"mean stderr {np.nanmean(truth.stderr):.4f}")
    top.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
    quantity = "half-ball VO (normal_clamp=True)" if nc else "ball VO (normal_clamp=False)"
    top.suptitle(f"(a) {quantity}: one frame each, no blur; the shadowed silhouette edges of "
                 f"Fig. 5 (left) and the model's fix (right)", fontsize=11)

    axes = bottom.subplots(1, len(panels) + 1)
    for ax, (label, f, img, _) in zip(axes, panels):
        im = error_panel(ax, img, truth.value,
                         f"{label}, {'off' if f is None else f'{f:g} R'}: estimate - truth")
    top_mask = np.where(m.gb.valid, 0.0, np.nan)
    top_mask[band] = 1.0
    top_mask[far] = 2.0
    cmap = mpl.colors.ListedColormap(["#f2f2f2", "#fdae61", "#b2182b"]).with_extremes(bad=BACKGROUND)
    axes[-1].imshow(np.ma.masked_invalid(top_mask), cmap=cmap, vmin=-0.5, vmax=2.5,
                    interpolation="nearest")
    axes[-1].set_xticks([])
    axes[-1].set_yticks([])
    axes[-1].set_title(f"silhouette band ({int(band.sum())} px, orange)\nits far side "
                       f"({int(far.sum())} px, dark red)", fontsize=9.5)
    bottom.colorbar(im, ax=axes[:-1], shrink=0.85, label="estimate - ground truth")
    bottom.suptitle("(b) signed error: red = darker than the truth, blue = more open; "
                    "where it is measured (right)", fontsize=11)


def _plots(subfig, rows, radius):
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FormatStrFormatter

    axes = subfig.subplots(1, 2)
    specs = (("rmse_band", "(c) RMSE in the silhouette band against thickness",
              "RMSE vs ground truth, silhouette band"),
             ("bias_far", "(d) bias behind the silhouettes (far side) against thickness",
              "bias vs ground truth, far side of the band"))
    factors = sorted({r["factor"] for r in rows if r["factor"] is not None})
    x_off = factors[0] / 2.0   # where "thickness off" is drawn: an octave left of the sweep
    for ax, (key, title, ylabel) in zip(axes, specs):
        for label, _, _ in METHODS:
            for nc in (False, True):
                rs = [r for r in rows if r["method"] == label and r["normal_clamp"] == nc]
                off = next(r for r in rs if r["factor"] is None)
                on = [r for r in rs if r["factor"] is not None]
                color = _COLORS[label]
                style = {"color": color, "marker": "o" if nc else "s", "mfc": color if nc else "white",
                         "ms": 5}
                ax.plot([r["factor"] for r in on], [r[key] for r in on], ls="-" if nc else "--", lw=1.8,
                        **style)
                ax.plot([x_off], [off[key]], ls="", **dict(style, ms=7))
        ax.axvline(np.sqrt(x_off * factors[0]), color="0.3", lw=0.8)
        for value, name in ((_WALL, "wall thickness"), (_BOX, "box width")):
            ax.axvline(value / radius, color="0.5", lw=1.0, ls=":")
            top = key != "bias_far"   # the bias panel's data crowd its top left
            ax.annotate(f"{name}\n{value:g} = {value / radius:.2f} R",
                        xy=(value / radius, 0.98 if top else 0.02),
                        xycoords=("data", "axes fraction"), xytext=(3, 0), textcoords="offset points",
                        ha="left", va="top" if top else "bottom", fontsize=8, color="0.35",
                        bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1})
        if key == "bias_far":
            ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlim(x_off / 1.3, factors[-1] * 1.3)
        ax.set_xticks([x_off] + [f for f in (0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
                                 if factors[0] <= f <= factors[-1]])
        ax.set_xticklabels(["off"] + [f"{f:g}" for f in ax.get_xticks()[1:]])
        ax.xaxis.set_minor_formatter(FormatStrFormatter(""))
        ax.set_xlabel("thickness / R (log); left: the thickness model switched off")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=11)
        ax.grid(True, which="major", color="0.9", lw=0.6)
    handles = [Line2D([], [], color=_COLORS[label], lw=2, label=label) for label, _, _ in METHODS]
    handles += [Line2D([], [], color="0.3", ls="--", marker="s", mfc="white",
                       label="ball (normal_clamp=False)"),
                Line2D([], [], color="0.3", ls="-", marker="o", label="half-ball (normal_clamp=True)"),
                Line2D([], [], color="0.3", ls="", marker="o", ms=7,
                       label="thickness off (left of the line)")]
    subfig.legend(handles=handles, loc="outside lower center", ncol=5, fontsize=9.5, frameon=False)
