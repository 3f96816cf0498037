"""Loos & Sloan 2010, Fig. 5: the thickness model off and on at silhouettes.

One PNG, ``fig5_thickness.png``, and the numbers it plots, ``fig5_thickness.csv``. The scene
is the Cornell box through its own camera (256 x 256; 48 x 48 quick), the ball
radius R = 0.1 x the scene's extent, seed 0; the G-buffer and the ground truth are those of
:func:`vobscure.experiments.claims.measurement` (so the numbers agree with
``docs/results.md``, and a process that also draws Fig. 6 or Fig. 7 measures them once).

(a) Visibility, half-ball (``normal_clamp=True``, where the silhouettes are the main error):
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

Regenerate with ``vobscure figures fig5_thickness --out docs/img`` (about 3-4 minutes, most
of it the ground truth; ``--quick`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.3 and Fig. 5.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from . import deprecated_make
from ._common import Rows, claims_measurements

__all__ = ["measure", "plot", "THICKNESS_SHOWN", "METHODS"]

ORDER = 30
FIGSIZE = (17.0, 12.5)

#: The thickness of the images, a fraction of R: the value docs/results.md quotes (between
#: the box's 0.1-thick walls, 0.27 R, and its 0.6-wide boxes, 1.6 R).
THICKNESS_SHOWN = 0.5
#: The estimators compared: (label, method, samples).
METHODS = (("lines 9", "line", 9), ("area 1", "area", 1))

_SCENE = "cornell_box"
_NORMAL_CLAMP_SHOWN = True   # panels (a) and (b): the half-ball, where the silhouettes are the main error
_COLUMNS = ("method", "samples", "normal_clamp", "factor", "thickness", "rmse_band", "bias_band",
            "rmse_far", "bias_far", "rmse_all", "bias_all", "pixels_band", "pixels_far")
_COLORS = {"lines 9": "#1f77b4", "area 1": "#2ca02c"}
_WALL, _BOX = 0.1, 0.6     # the Cornell box's wall thickness and box width (scene units)


def measure(profile, *, claims=None) -> Rows:
    """The error of lines and area at silhouettes for every thickness, and the images shown.

    Parameters
    ----------
    profile : Profile
        Quick: thicknesses 0.25, 1 and 4 R; full: 11 from 0.125 to 4 R (half octaves).
        Image size and seed as the profile's.
    claims : dict, optional
        The claims' measurement of ``profile`` (see :mod:`vobscure.experiments.figures`).

    Returns
    -------
    Rows
        One row per (method, normal_clamp, thickness); ``factor`` and ``thickness`` are empty
        for the model switched off. Arrays: the images of panels (a) and (b), the ground
        truth and the silhouette masks.
    """
    from .. import claims as C
    from ...metrics import error

    claims = claims_measurements(profile) if claims is None else claims
    m = claims[_SCENE]
    factors = profile.pick((0.25, 1.0, 4.0), (0.125, 0.177, 0.25, 0.354, 0.5, 0.707, 1.0, 1.41, 2.0, 2.83, 4.0))
    width = max(1, int(round(min(profile.size) / 128)))   # "a few pixels", as in claims
    band, far = C.silhouette_mask(m.gb.depth, width=width)
    rows, shown = _sweep(m, band, far, factors, profile.seed, _NORMAL_CLAMP_SHOWN)
    truth = m.truth[_NORMAL_CLAMP_SHOWN]
    arrays = {"truth": truth.value, "truth_stderr": truth.stderr, "band": band, "far": far, "valid": m.gb.valid}
    titles = {}
    for (label, f), v in shown.items():
        arrays[f"{label}|{f}"] = v
        titles[f"{label}|{f}"] = [error(v, truth.value, mask=band).rmse, error(v, truth.value, mask=far).bias]
    meta = {"radius": m.radius, "size": list(profile.size), "seed": profile.seed, "quick": profile.quick,
            "truth_samples": int(truth.samples), "shown": titles}
    return Rows(rows, columns=_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """Panels (a) to (d) from :func:`measure`'s rows."""
    m = rows.meta
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.15], hspace=0.03)
    _images(parts[0], parts[1], rows, _NORMAL_CLAMP_SHOWN)
    _plots(parts[2], rows, m["radius"])
    w, h = m["size"]
    fig.suptitle(f"Loos & Sloan 2010, Fig. 5 / Sec. 4.3: the thickness model at silhouettes "
                 f"(Cornell box, {w} x {h}, R = {m['radius']:.3g} = 0.1 x extent, seed {m['seed']}"
                 f"{', quick' if m['quick'] else ''})", fontsize=13)


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
def _images(top, bottom, rows, nc):
    import matplotlib as mpl

    from ._common import BACKGROUND, error_panel, fmt, image_panel

    a = rows.arrays
    truth = SimpleNamespace(value=a["truth"], stderr=a["truth_stderr"], samples=rows.meta["truth_samples"])
    band, far, valid = a["band"].astype(bool), a["far"].astype(bool), a["valid"].astype(bool)
    panels = []
    for label, _, _ in METHODS:
        for f in (None, THICKNESS_SHOWN):
            v = a[f"{label}|{f}"]
            rmse_band, bias_far = rows.meta["shown"][f"{label}|{f}"]
            what = "thickness off" if f is None else f"thickness {f:g} R"
            panels.append((label, f, v, f"{label}, {what}\nband RMSE {fmt(rmse_band)}, "
                                        f"far-side bias {bias_far:+.3f}"))
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
    top_mask = np.where(valid, 0.0, np.nan)
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


make = deprecated_make(__name__)
