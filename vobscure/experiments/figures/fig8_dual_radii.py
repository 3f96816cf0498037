"""Loos & Sloan 2010, Fig. 8 / Sec. 6: a small and a large radius, and their combination.

One PNG, ``fig8_dual_radii.png``, and the numbers it plots, ``fig8_dual_radii.csv``. The
Cornell box through its own camera (256 x 256; 48 x 48 in the quick profile), half-ball VO
(``normal_clamp=True``), radii r = :data:`RADII` x the scene's extent, seed 0.

(a) ``vo_line`` (9 lines) at the small radius and at the large one, each after the
    edge-aware blur (:func:`vobscure.bilateral_blur`, defaults), and their combinations
    ``vo.combine_radii(small, large, mode="product")`` and ``mode="min"``.
(b) The same four images made of the Embree ground truth
    (``ground_truth(quantity="volumetric", normal_clamp=True)``) at the two radii: what the
    combination would be without any screen-space or sampling error.
(c) One image row (marked in (a) and (b)) across the floor, the base of the tall box and the
    front of the short one: estimates (solid) and ground truths (dashed).
(d) What each image captures, as Pearson correlations over pixels: with the small-radius
    truth (the fine features: creases, edges), with the large-radius truth (contact and
    large-scale darkening) and with ray-cast AO within the large radius; and the RMSE of
    each estimate against its own truth.

The paper's claim: a small radius captures fine features but loses contact shadows and
large-scale features, a large radius the reverse, and their product (or minimum) keeps both.

Regenerate with ``vobscure figures fig8_dual_radii --out docs/img`` (a few minutes, most of
it the two ground truths; ``--quick`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 6 and Fig. 8.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "RADII", "SAMPLES", "MODES", "PROFILE_ROW"]

ORDER = 60
FIGSIZE = (17.0, 13.0)

#: (small, large) radius as fractions of the scene's extent (the Cornell box's 3.75: radii
#: 0.11 and 0.75, about the wall thickness and the boxes' size).
RADII = (0.03, 0.2)
#: Lines per pixel of the estimates.
SAMPLES = 9
#: Combination modes of :func:`vobscure.combine_radii`.
MODES = ("product", "min")
#: The image row of panel (c), as a fraction of the height.
PROFILE_ROW = 0.86

_SCENE = "cornell_box"
_NORMAL_CLAMP = True         # half-ball VO, estimates and truth alike
_KINDS = ("small", "large") + MODES
_COLUMNS = ("image", "truth", "radius", "radius_large", "mean", "corr_small_truth",
            "corr_large_truth", "corr_ao", "rmse_own_truth", "bias_own_truth")
_COLORS = {"small": "#1f77b4", "large": "#ff7f0e", "product": "#2ca02c", "min": "#9467bd"}


def measure(profile) -> Rows:
    """The two radii, their combinations, and the same of the ground truth.

    ``vo_line`` (:data:`SAMPLES` lines) at both radii of :data:`RADII`, each after the
    edge-aware blur, combined by each of :data:`MODES`; the ground truth with 128 points per
    ball quick (1024 full) and ray-cast AO within the large radius with 64 rays (256). Image
    size and seed as the profile's.

    Returns
    -------
    Rows
        One row per image (small, large, product, min) and source (``truth`` 0: estimate,
        1: ground truth); arrays: the eight images and the truths' standard errors.
    """
    from ... import scenes
    from ...render import render_gbuffer
    from ...groundtruth import ground_truth
    from ...screenspace import bilateral_blur, combine_radii, vo_line

    size, seed = profile.size, profile.seed
    small, large = RADII
    scene = scenes.get(_SCENE)
    gb = render_gbuffer(scene, scene.camera(size))
    r = {"small": small * scene.extent, "large": large * scene.extent}
    est, truth = {}, {}
    for k, name in enumerate(("small", "large")):
        v = vo_line(gb, radius=r[name], samples=SAMPLES, normal_clamp=_NORMAL_CLAMP, seed=seed)
        est[name] = bilateral_blur(v, gb)
        truth[name] = ground_truth(scene, gb, quantity="volumetric", radius=r[name],
                                   samples=profile.pick(128, 1024), normal_clamp=_NORMAL_CLAMP,
                                   seed=seed + k, progress=False)
    ao = ground_truth(scene, gb, quantity="ao", radius=r["large"], rays=profile.pick(64, 256),
                      seed=seed + 2, progress=False)
    truth_img = {"small": truth["small"].value, "large": truth["large"].value}
    for mode in MODES:
        est[mode] = combine_radii(est["small"], est["large"], mode=mode)
        truth_img[mode] = combine_radii(truth_img["small"], truth_img["large"], mode=mode)
    arrays = {**{f"estimate|{k}": v for k, v in est.items()}, **{f"truth|{k}": v for k, v in truth_img.items()},
              **{f"stderr|{k}": t.stderr for k, t in truth.items()}}
    meta = {"size": list(size), "seed": seed, "quick": profile.quick, "radii": r}
    return Rows(_rows(est, truth_img, ao.value, r), columns=_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """Panels (a) to (d) from :func:`measure`'s rows."""
    m, a = rows.meta, rows.arrays
    size, r = m["size"], m["radii"]
    est = {k: a[f"estimate|{k}"] for k in _KINDS}
    truth = {k: a[f"truth|{k}"] for k in _KINDS}
    stderr = {k: SimpleNamespace(stderr=a[f"stderr|{k}"]) for k in ("small", "large")}
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.15], hspace=0.03)
    row = min(size[1] - 1, int(PROFILE_ROW * size[1]))
    _image_row(parts[0], est, rows, r, row, "a", truth=False)
    _image_row(parts[1], truth, rows, r, row, "b", truth=True, stderr=stderr)
    _plots(parts[2], est, truth, rows, row)
    w, h = size
    small, large = RADII
    fig.suptitle(f"Loos & Sloan 2010, Fig. 8 / Sec. 6: dual radii on the Cornell box ({w} x {h}, "
                 f"{'half-ball' if _NORMAL_CLAMP else 'ball'} VO, r = {small:g} and {large:g} x extent, "
                 f"lines {SAMPLES}, seed {m['seed']}{', quick' if m['quick'] else ''})", fontsize=13)


# ----------------------------------------------------------------------------- data
def _rows(est, truth, ao, r):
    from ...metrics import error
    from ._common import corr

    rows = []
    for kind in _KINDS:
        for is_truth, img in ((False, est[kind]), (True, truth[kind])):
            e = error(img, truth[kind])
            rows.append({"image": kind, "truth": is_truth, "radius": r.get(kind),
                         "radius_large": r["large"], "mean": float(np.nanmean(img)),
                         "corr_small_truth": corr(img, truth["small"]),
                         "corr_large_truth": corr(img, truth["large"]), "corr_ao": corr(img, ao),
                         "rmse_own_truth": e.rmse, "bias_own_truth": e.bias})
    return rows


# ----------------------------------------------------------------------------- drawing
def _title(kind, r):
    if kind in r:
        return f"{kind} radius r = {r[kind]:.3g}"
    return f"combine_radii(mode=\"{kind}\")"


def _image_row(subfig, images, rows, r, row, letter, *, truth, blur=True, stderr=None):
    from ._common import fmt, image_panel

    by = {x["image"]: x for x in rows if x["truth"] == truth}
    axes = subfig.subplots(1, len(_KINDS))
    for ax, kind in zip(axes, _KINDS):
        x = by[kind]
        extra = (f"RMSE vs its truth {fmt(x['rmse_own_truth'])}" if not truth else
                 (f"mean stderr {np.nanmean(stderr[kind].stderr):.4f}" if kind in stderr else
                  f"mean {fmt(x['mean'])}"))
        im = image_panel(ax, images[kind], f"{_title(kind, r)}\n{extra}")
        ax.axhline(row, color=_COLORS[kind], lw=1.0, ls=":")
    subfig.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
    if truth:
        what = "(b) Embree ground truth at both radii and the same combinations"
    else:
        what = (f"(a) vo_line, {SAMPLES} lines, one frame{' after the edge-aware blur' if blur else ''}, "
                f"at both radii and combined")
    subfig.suptitle(f"{what}; dotted: the row of (c)", fontsize=11)


def _plots(subfig, est, truth, rows, row):
    from matplotlib.lines import Line2D

    ax, bx = subfig.subplots(1, 2, width_ratios=[1.3, 1.0])
    # "min" often equals "large" (the larger radius is the darker): drawn thinner, on top of it
    widths = {"small": 1.6, "large": 3.0, "product": 1.6, "min": 1.1}
    for kind in _KINDS:
        ax.plot(est[kind][row], color=_COLORS[kind], lw=widths[kind])
        ax.plot(truth[kind][row], color=_COLORS[kind], lw=1.1, ls="--")
    ax.set_xlabel("column (pixels)")
    ax.set_ylabel("visibility (1 = open)")
    ax.set_ylim(0.0, 1.05)
    ax.grid(True, color="0.9", lw=0.6)
    ax.set_title(f"(c) image row {row}: estimate (solid) and ground truth (dashed)", fontsize=11)
    handles = [Line2D([], [], color=_COLORS[k], lw=2, label=k) for k in _KINDS]
    handles += [Line2D([], [], color="0.3", lw=1.6, label="estimate"),
                Line2D([], [], color="0.3", lw=1.1, ls="--", label="ground truth")]
    ax.legend(handles=handles, fontsize=8.5, loc="lower left", ncol=3, framealpha=0.9)

    metrics = (("corr_small_truth", "corr. with small-r truth\n(fine features)"),
               ("corr_large_truth", "corr. with large-r truth\n(contact, large scale)"),
               ("corr_ao", "corr. with ray-cast AO\nwithin the large r"))
    x = np.arange(len(metrics), dtype=float)
    width = 0.8 / len(_KINDS)
    by = {(q["image"], q["truth"]): q for q in rows}
    for k, kind in enumerate(_KINDS):
        xs = x + (k - (len(_KINDS) - 1) / 2) * width
        bx.bar(xs, [by[(kind, False)][m] for m, _ in metrics], width, color=_COLORS[kind],
               edgecolor="k", lw=0.5, zorder=2, label=f"{kind} (estimate)")
        bx.plot(xs, [by[(kind, True)][m] for m, _ in metrics], "_", color="k", ms=12, mew=2.2, zorder=3)
    bx.plot([], [], "_", color="k", ms=12, mew=2.2, label="the same image of the ground truth")
    bx.set_xticks(x)
    bx.set_xticklabels([label for _, label in metrics], fontsize=9)
    lo = min(min(q[m] for m, _ in metrics) for q in rows)
    bx.set_ylim(min(0.0, lo - 0.05), 1.3)
    bx.set_yticks([t for t in bx.get_yticks() if t <= 1.0])
    bx.set_ylabel("Pearson correlation over pixels")
    bx.grid(True, axis="y", color="0.9", lw=0.6, zorder=0)
    bx.legend(fontsize=8.5, loc="upper center", ncol=3, framealpha=0.9)
    bx.set_title("(d) what each image captures", fontsize=11)


make = deprecated_make(__name__)
