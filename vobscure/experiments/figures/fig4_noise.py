"""Loos & Sloan 2010, Fig. 4: the noise of sample patterns in images, without randomization.

One PNG, ``fig4_noise.png``, and the numbers behind it, ``fig4_noise.csv``. The Cornell box
through its own camera (256 x 256; 48 x 48 in the quick profile), ball radius R = 0.1 x the scene's
extent (as :mod:`vobscure.experiments.claims`), per-pixel randomization off
(``randomize=False``): every pixel uses the same pattern, so a pattern's error shows as
structured noise, as in the paper's Fig. 4.

Left of the paper's figure, line sampling: ``vo_line`` with the disk patterns of
:func:`vobscure.patterns.disk` for ``method`` in electrostatic, random and Sobol'
(scrambled), 9 against 10 samples, and a curve of RMSE against n. Right, point sampling:
``vo_point`` with :func:`vobscure.patterns.ball`, 12 against 13 samples, and a curve.
The error is the RMSE against the converged screen-space VO (:func:`vobscure.vo_reference`,
4096 samples; 512 in the quick profile) with the same ``normal_clamp``. The electrostatic pattern
is the table entry (seed 0, ``data/patterns/``), one deterministic pattern; a random or
Sobol' pattern depends on its seed, so those are measured over 16 seeds (4 quick)
(``seed``, ``seed + 1``, ...) and reported as the mean RMSE with its standard error over
seeds. Variants: ``symmetric`` (antipodal pairs, the centre for odd n: the estimators'
default and the headline), ``plain`` (no centre forced) and, for the disk, ``center`` (plain
with the centre forced, the paper's "when the center is one of the samples"). Both
``normal_clamp`` settings are measured; the figure shows the half-ball
(``normal_clamp=True``, the paper's pictures use the normal).

Under the scene's 39-degree perspective ``vo_line`` does not converge to ``vo_reference``
(``docs/results.md``): its limit, ``vo_line`` with :data:`LIMIT_LINES` lines, is about 0.025
RMSE away, an error every disk pattern shares. So the line rows also carry the RMSE
against that limit, the pure sampling error (``rmse_limit``); for points the limit is the
reference itself.

The issue's goal, "with per-pixel randomization off, the electrostatic 9-sample disk pattern
gives at most 0.7x the RMSE of random patterns and no more than Sobol's", is checked, not
assumed, by :func:`goal`: the ratio electrostatic / mean(random) with its delta-method
standard error from the seeds' spread, and electrostatic against the Sobol' mean (ratio and
z), each judged "met", "not met" or "undecided" at one-sided 95 % (:data:`GOAL_Z`).

(a) Lines, half-ball, symmetric patterns: the converged reference and the lines' own limit;
    electrostatic, random (the first seed) and Sobol' (the first seed) with 9 and 10 lines,
    and their signed error against the reference. Titles: RMSE of the image shown, and the
    mean +- standard error over seeds.
(b) Points, half-ball, symmetric: the same with 12 and 13 points.
(c) RMSE against n, lines, symmetric; error bars 2 standard errors over seeds.
(d) The same for the plain patterns (solid: no centre forced, dashed: centre forced).
(e) RMSE against n, points, symmetric (solid) and plain (dashed).
(f) The goal's ratios against n (lines, symmetric): electrostatic / random with the 0.7
    target and electrostatic / Sobol' with 1.0; error bars 2 standard errors.

Regenerate with ``vobscure figures fig4_noise --out docs/img``, which also writes the
markdown tables of ``docs/patterns_results.md`` as ``fig4_noise.md`` (a few minutes;
``--quick`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.5 and Fig. 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "goal", "markdown", "METHODS", "VARIANTS", "LINE_COUNTS", "POINT_COUNTS",
           "PAPER_COUNTS", "LIMIT_LINES", "GOAL", "GOAL_Z", "HEADLINE"]

ORDER = 20
FIGSIZE = (18.0, 17.0)

#: The pattern generators compared (:data:`vobscure.patterns.METHODS` names).
METHODS = ("electrostatic", "random", "sobol")
#: Pattern variants per estimator: the estimators' default (symmetric) and the paper's plain
#: patterns, for the disk also with the centre forced.
VARIANTS = {"line": ("symmetric", "plain", "center"), "point": ("symmetric", "plain")}
#: The paper's Fig. 4 counts, n against n + 1 (the image rows, and the curves of the quick profile).
PAPER_COUNTS = {"line": (9, 10), "point": (12, 13)}
#: Line (disk) counts of the curves in the full profile.
LINE_COUNTS = tuple(range(3, 17))
#: Point (ball) counts of the curves in the full profile.
POINT_COUNTS = tuple(range(6, 17))
#: Lines of the lines' own converged value (a table entry of ``data/patterns/``).
LIMIT_LINES = 257
#: The issue's targets for electrostatic RMSE / rival RMSE: at most 0.7 x random's, at most
#: Sobol's.
GOAL = {"random": 0.7, "sobol": 1.0}
#: One-sided z of the goal's verdicts: "met" when ratio + GOAL_Z x stderr <= target, "not
#: met" when ratio - GOAL_Z x stderr > target (a 5 % error rate each way), else "undecided".
GOAL_Z = 1.645
#: The goal's configuration: (estimator, samples, variant, normal_clamp).
HEADLINE = ("line", 9, "symmetric", True)

_SCENE = "cornell_box"
_COLUMNS = ("estimator", "normal_clamp", "variant", "method", "samples", "seeds", "width", "height",
            "ref_samples", "rmse_ref", "rmse_ref_se", "rmse_ref_sd", "rmse_ref_first", "bias_ref",
            "rmse_limit", "rmse_limit_se", "limit_rmse_ref", "ref_noise", "target", "ratio",
            "ratio_se", "z", "ratio_limit", "ratio_limit_se", "verdict", "pixels")
_COLORS = {"electrostatic": "#d62728", "random": "#7f7f7f", "sobol": "#9467bd"}
_NAMES = {"electrostatic": "electrostatic", "random": "random", "sobol": "Sobol'"}


# ----------------------------------------------------------------------------- setup
@dataclass(frozen=True)
class _Setup:
    """The G-buffer, radius and references of one (size, seed, reference samples)."""

    gb: object
    radius: float
    reference: dict      # normal_clamp -> (H, W) converged screen-space VO
    limit: dict          # normal_clamp -> (H, W) vo_line with LIMIT_LINES lines
    ref_noise: dict      # normal_clamp -> RMS noise of the reference, or None (not measured)


def _setup(size: tuple, seed: int, ref_samples: int, noise: bool) -> _Setup:
    """The G-buffer, radius, references and the lines' limit of one measurement."""
    from ... import scenes
    from ...render import render_gbuffer
    from ...metrics import error
    from ...screenspace import vo_line, vo_reference
    from ..common import default_radius

    scene = scenes.get(_SCENE)
    gb = render_gbuffer(scene, scene.camera(size))
    radius = default_radius(scene)
    reference, limit, ref_noise = {}, {}, {}
    for nc in (False, True):
        reference[nc] = vo_reference(gb, radius=radius, samples=ref_samples, normal_clamp=nc, seed=seed).value
        limit[nc] = vo_line(gb, radius=radius, samples=LIMIT_LINES, normal_clamp=nc, randomize=False)
        ref_noise[nc] = None
        if noise:
            # two independent references: the RMS of their difference / sqrt(2) is one's noise
            other = vo_reference(gb, radius=radius, samples=ref_samples, normal_clamp=nc,
                                 seed=seed + 1).value
            ref_noise[nc] = error(reference[nc], other).rmse / math.sqrt(2.0)
    return _Setup(gb, radius, reference, limit, ref_noise)


def _pattern(estimator: str, n: int, method: str, variant: str, seed: int):
    """The pattern of one row: the electrostatic table entry (seed 0), else the seed's draw."""
    from ... import patterns as P

    make = P.disk if estimator == "line" else P.ball
    kwargs = {"symmetric": variant == "symmetric"}
    if variant == "center":
        kwargs["center"] = True
    return make(n, method=method, seed=0 if method == "electrostatic" else seed, **kwargs)


def _estimate(setup: _Setup, estimator: str, pattern, normal_clamp: bool):
    from ... import methods

    return methods.get(estimator).run(setup.gb, pattern, radius=setup.radius, normal_clamp=normal_clamp,
                                      randomize=False)


# ----------------------------------------------------------------------------- data
def measure(profile, *, seeds=None, line_counts=None, point_counts=None) -> Rows:
    """RMSE of every (estimator, normal_clamp, variant, method, samples), randomization off.

    Parameters
    ----------
    profile : Profile
        Quick: 512 reference samples, 4 seeds, only :data:`PAPER_COUNTS`; full: 4096
        samples, 16 seeds, :data:`LINE_COUNTS` and :data:`POINT_COUNTS`. Image size
        ``profile.size``; ``profile.seed`` seeds the reference, and the random and Sobol'
        patterns use it, it + 1, ... The electrostatic pattern is always the table entry
        (seed 0).
    seeds : int, optional
        Seeds per random / Sobol' pattern, instead of the profile's.
    line_counts, point_counts : iterable of int, optional
        Counts of the curves, instead of the profile's.

    Returns
    -------
    Rows
        One row per configuration, with the columns of the CSV: ``rmse_ref`` is the mean RMSE
        against the converged screen-space VO over the seeds (the one pattern's for
        electrostatic), ``rmse_ref_se`` its standard error over seeds (None for
        electrostatic), ``rmse_ref_first`` the first seed's, ``rmse_limit`` the mean RMSE
        against the estimator's own converged value. Rows of random and Sobol' also carry
        the comparison with the electrostatic pattern of the same configuration:
        ``ratio`` = electrostatic / mean RMSE with ``ratio_se`` (delta method), ``z`` =
        (mean - electrostatic) / stderr (positive: electrostatic lower), the same ratio
        against the limit, and the ``verdict`` of :func:`goal`'s rule against ``target``
        (:data:`GOAL`). Arrays: the images of panels (a) and (b).
    """
    from ..._validate import check_int

    size, seed = profile.size, profile.seed
    seeds = profile.pick(4, 16) if seeds is None else check_int(seeds, "seeds", minimum=2)
    counts = {"line": tuple(profile.pick(PAPER_COUNTS["line"], LINE_COUNTS) if line_counts is None
                            else line_counts),
              "point": tuple(profile.pick(PAPER_COUNTS["point"], POINT_COUNTS) if point_counts is None
                             else point_counts)}
    ref_samples = profile.pick(512, 4096)
    setup = _setup(size, seed, ref_samples, not profile.quick)
    rows = _rows(setup, counts, size, seed, seeds, ref_samples)
    arrays, meta = _images(setup, counts, seed)
    meta.update(size=list(size), seed=seed, quick=profile.quick, radius=setup.radius)
    return Rows(rows, columns=_COLUMNS, arrays=arrays, meta=meta)


def _images(setup: _Setup, counts, seed):
    """The images of panels (a) and (b) and the RMSE of each (the headline's normal setting)."""
    from ...metrics import error

    nc = HEADLINE[3]
    arrays = {"reference": setup.reference[nc], "limit": setup.limit[nc]}
    meta = {"limit_rmse": error(setup.limit[nc], setup.reference[nc]).rmse, "shown_rmse": {}}
    for estimator in ("line", "point"):
        for n in (n for n in PAPER_COUNTS[estimator] if n in counts[estimator]):
            for method in METHODS:
                v = _estimate(setup, estimator, _pattern(estimator, n, method, "symmetric", seed), nc)
                arrays[f"{estimator}|{n}|{method}"] = v
                meta["shown_rmse"][f"{estimator}|{n}|{method}"] = error(v, setup.reference[nc]).rmse
    return arrays, meta


def _rows(setup: _Setup, counts, size, seed, seeds, ref_samples) -> list[dict]:
    from ...metrics import error

    rows = []
    for estimator in ("line", "point"):
        for variant in VARIANTS[estimator]:
            for n in counts[estimator]:
                errors = {}      # (method, normal_clamp) -> [(rmse_ref, bias_ref, rmse_limit, pixels)]
                for method in METHODS:
                    draws = [seed] if method == "electrostatic" else [seed + k for k in range(seeds)]
                    for s in draws:
                        p = _pattern(estimator, n, method, variant, s)
                        for nc in (False, True):
                            v = _estimate(setup, estimator, p, nc)
                            rmse, bias, pixels = _rmse_bias(v, setup.reference[nc])
                            lim = setup.limit[nc] if estimator == "line" else setup.reference[nc]
                            e_lim = _rmse_bias(v, lim)[0]
                            errors.setdefault((method, nc), []).append((rmse, bias, e_lim, pixels))
                for nc in (False, True):
                    lim_ref = (error(setup.limit[nc], setup.reference[nc]).rmse
                               if estimator == "line" else 0.0)
                    base = None
                    for method in METHODS:
                        a = np.array(errors[(method, nc)], dtype=np.float64)
                        k = len(a)
                        row = {"estimator": estimator, "normal_clamp": nc, "variant": variant,
                               "method": method, "samples": n, "seeds": k, "width": size[0],
                               "height": size[1], "ref_samples": ref_samples,
                               "rmse_ref": float(a[:, 0].mean()), "rmse_ref_first": float(a[0, 0]),
                               "rmse_ref_se": _se(a[:, 0]), "rmse_ref_sd": _sd(a[:, 0]),
                               "bias_ref": float(a[:, 1].mean()), "rmse_limit": float(a[:, 2].mean()),
                               "rmse_limit_se": _se(a[:, 2]), "limit_rmse_ref": lim_ref,
                               "ref_noise": setup.ref_noise[nc], "pixels": int(a[0, 3])}
                        if method == "electrostatic":
                            base = row
                        else:
                            row.update(_compare(base, row, GOAL[method]))
                        rows.append(row)
    return rows


def _rmse_bias(estimate, reference) -> tuple[float, float, int]:
    """RMSE, bias and pixel count exactly as :func:`vobscure.error` computes them, without its
    SSIM (which would be most of this experiment's time)."""
    est = np.asarray(estimate, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    use = np.isfinite(est) & np.isfinite(ref)
    diff = est[use] - ref[use]
    return float(np.sqrt(float(np.mean(diff * diff)))), float(np.mean(diff)), int(use.sum())


def _sd(x) -> float | None:
    return float(np.std(x, ddof=1)) if len(x) > 1 else None


def _se(x) -> float | None:
    return float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else None


def _ratio(e: float, mean: float, se: float) -> tuple[float, float]:
    """e / mean and its delta-method standard error (e is one fixed pattern's, exact)."""
    r = e / mean
    return r, r * se / mean


def _compare(es: dict, row: dict, target: float) -> dict:
    """The electrostatic pattern against a rival's seed mean in the same configuration."""
    r, r_se = _ratio(es["rmse_ref"], row["rmse_ref"], row["rmse_ref_se"])
    rl, rl_se = _ratio(es["rmse_limit"], row["rmse_limit"], row["rmse_limit_se"])
    se = row["rmse_ref_se"]
    z = (row["rmse_ref"] - es["rmse_ref"]) / se if se > 0 else math.copysign(1e4, row["rmse_ref"] - es["rmse_ref"])
    return {"target": target, "ratio": r, "ratio_se": r_se, "z": float(np.clip(z, -1e4, 1e4)),
            "ratio_limit": rl, "ratio_limit_se": rl_se, "verdict": _verdict(r, r_se, target)}


def _verdict(ratio: float, se: float, target: float) -> str:
    if ratio + GOAL_Z * se <= target:
        return "met"
    if ratio - GOAL_Z * se > target:
        return "not met"
    return "undecided"


def goal(rows, *, estimator: str = HEADLINE[0], samples: int = HEADLINE[1], variant: str = HEADLINE[2],
         normal_clamp: bool = HEADLINE[3]) -> list[dict]:
    """The issue's goal in one configuration: electrostatic against random and against Sobol'.

    "With per-pixel randomization off, the electrostatic 9-sample disk pattern gives at most
    0.7x the RMSE of random patterns and no more than Sobol's." Judged on the RMSE against
    the converged screen-space VO: the ratio electrostatic / mean over seeds, its standard
    error by the delta method, r x stderr(mean) / mean (the electrostatic pattern is one
    fixed pattern, its RMSE exact given the reference); "met" when the one-sided 95 % upper
    bound ratio + :data:`GOAL_Z` x stderr is at most the target (0.7 against random, 1 against
    Sobol'), "not met" when the lower bound exceeds it, else "undecided".

    Parameters
    ----------
    rows : list of dict
        From :func:`measure`.
    estimator, samples, variant, normal_clamp : optional
        The configuration; default :data:`HEADLINE` (lines, 9, symmetric, half-ball).

    Returns
    -------
    list of dict
        One per rival: ``rival, target, electrostatic, mean, stderr, seeds, ratio, ratio_se,
        upper, lower, z, ratio_limit, ratio_limit_se, verdict``.

    Raises
    ------
    ValueError
        If the rows do not hold the configuration.

    Examples
    --------
    >>> measured = (("electrostatic", 0.05, None, 1), ("random", 0.1, 0.005, 16),
    ...             ("sobol", 0.06, 0.002, 16))
    >>> rows = [{"estimator": "line", "samples": 9, "variant": "symmetric", "normal_clamp": True,
    ...          "method": m, "rmse_ref": e, "rmse_ref_se": se, "seeds": k, "rmse_limit": e,
    ...          "rmse_limit_se": se} for m, e, se, k in measured]
    >>> [(g["rival"], round(g["ratio"], 3), g["verdict"]) for g in goal(rows)]
    [('random', 0.5, 'met'), ('sobol', 0.833, 'met')]
    """
    sel = {r["method"]: r for r in rows if r["estimator"] == estimator and r["samples"] == samples
           and r["variant"] == variant and bool(r["normal_clamp"]) == bool(normal_clamp)}
    if "electrostatic" not in sel:
        raise ValueError(f"rows hold no electrostatic row for estimator={estimator!r}, samples={samples}, "
                         f"variant={variant!r}, normal_clamp={normal_clamp}")
    es = sel["electrostatic"]
    out = []
    for rival, target in GOAL.items():
        if rival not in sel:
            continue
        r = sel[rival]
        c = _compare(es, r, target)
        out.append({"rival": rival, "target": target, "electrostatic": es["rmse_ref"], "mean": r["rmse_ref"],
                    "stderr": r["rmse_ref_se"], "seeds": r["seeds"], "ratio": c["ratio"],
                    "ratio_se": c["ratio_se"], "upper": c["ratio"] + GOAL_Z * c["ratio_se"],
                    "lower": c["ratio"] - GOAL_Z * c["ratio_se"], "z": c["z"],
                    "ratio_limit": c["ratio_limit"], "ratio_limit_se": c["ratio_limit_se"],
                    "verdict": c["verdict"]})
    return out


# ----------------------------------------------------------------------------- figure
def plot(rows, fig) -> None:
    """Panels (a) to (f) from :func:`measure`'s rows."""
    m = rows.meta
    nc = HEADLINE[3]
    parts = fig.subfigures(3, 1, height_ratios=[1.45, 1.45, 1.1], hspace=0.02)
    _image_rows(parts[0], rows, "line", nc, m["seed"])
    _image_rows(parts[1], rows, "point", nc, m["seed"])
    _curves(parts[2], rows, nc)
    w, h = m["size"]
    k = max((r["seeds"] for r in rows), default=1)
    fig.suptitle(f"Loos & Sloan 2010, Fig. 4 / Sec. 4.5: sample patterns without per-pixel randomization "
                 f"(Cornell box, {w} x {h}, R = {m['radius']:.3g} = 0.1 x extent, half-ball; random and "
                 f"Sobol' over {k} seeds{', quick' if m['quick'] else ''})", fontsize=13)


def _image_rows(subfig, rows, estimator, nc, seed):
    from ._common import error_panel, fmt, image_panel

    a = rows.arrays

    by = {(r["method"], r["samples"]): r for r in rows if r["estimator"] == estimator
          and r["variant"] == "symmetric" and bool(r["normal_clamp"]) == nc}
    counts = [n for n in PAPER_COUNTS[estimator] if ("electrostatic", n) in by]
    ref = a["reference"]
    axes = subfig.subplots(max(1, len(counts)), 1 + 2 * len(METHODS), squeeze=False)
    for i, n in enumerate(counts):
        first = axes[i, 0]
        if i == 0:
            im = image_panel(first, ref, "converged screen-space VO\n(vo_reference)", fontsize=9)
        elif estimator == "line":
            lim_rmse = rows.meta["limit_rmse"]
            image_panel(first, a["limit"], f"lines' limit ({LIMIT_LINES} lines)\n"
                                                f"RMSE {fmt(lim_rmse, 4)}", fontsize=9)
        else:
            first.axis("off")
        for j, method in enumerate(METHODS):
            v = a[f"{estimator}|{n}|{method}"]
            r = by[(method, n)]
            shown = rows.meta["shown_rmse"][f"{estimator}|{n}|{method}"]
            if method == "electrostatic":
                stat = "table pattern (seed 0)"
            else:
                stat = f"{r['seeds']} seeds: {fmt(r['rmse_ref'], 4)} \u00b1 {fmt(r['rmse_ref_se'], 4)}"
            im = image_panel(axes[i, 1 + j], v, f"{_NAMES[method]} {n}: RMSE {fmt(shown, 4)}\n{stat}",
                             fontsize=9)
            err = error_panel(axes[i, 1 + len(METHODS) + j], v, ref, f"error, {_NAMES[method]} {n}",
                              limit=0.25, fontsize=9)
    subfig.colorbar(im, ax=axes[:, :1 + len(METHODS)], shrink=0.8, label="visibility (1 = open)")
    subfig.colorbar(err, ax=axes[:, 1 + len(METHODS):], shrink=0.8, label="estimate - reference")
    name = ("(a) lines (vo_line, disk patterns), 9 against 10" if estimator == "line"
            else "(b) points (vo_point, ball patterns), 12 against 13")
    subfig.suptitle(f"{name}: symmetric patterns, randomize=False; random and Sobol' images at seed {seed}",
                    fontsize=11)


def _series(rows, estimator, variant, method, nc, key="rmse_ref"):
    rs = sorted((r for r in rows if r["estimator"] == estimator and r["variant"] == variant
                 and r["method"] == method and bool(r["normal_clamp"]) == nc), key=lambda r: r["samples"])
    n = np.array([r["samples"] for r in rs])
    y = np.array([r[key] for r in rs], dtype=np.float64)
    se_key = {"rmse_ref": "rmse_ref_se", "ratio": "ratio_se"}[key]
    se = np.array([r.get(se_key) or 0.0 for r in rs], dtype=np.float64)
    return n, y, se


def _axes_style(ax, log: bool):
    from matplotlib.ticker import FormatStrFormatter, LogLocator, MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    if log:
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 3.0, 5.0, 7.0)))
        ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(FormatStrFormatter(""))
    ax.grid(True, which="both", color="0.9", lw=0.6)


def _curves(subfig, rows, nc):
    axes = subfig.subplots(1, 4)
    panels = [("(c) lines, symmetric", "line", (("symmetric", "-"),)),
              ("(d) lines, plain (dashed: centre forced)", "line", (("plain", "-"), ("center", "--"))),
              ("(e) points, symmetric (solid), plain (dashed)", "point", (("symmetric", "-"), ("plain", "--")))]
    for ax, (title, estimator, styles) in zip(axes, panels):
        for variant, ls in styles:
            for method in METHODS:
                n, y, se = _series(rows, estimator, variant, method, nc)
                if not len(n):
                    continue
                label = _NAMES[method] if ls == "-" else None
                ax.errorbar(n, y, yerr=2 * se, color=_COLORS[method], ls=ls, marker="o", ms=3.5,
                            lw=2.0 if method == "electrostatic" else 1.3, capsize=2, label=label)
        if estimator == "line":
            lim = [r["limit_rmse_ref"] for r in rows if r["estimator"] == "line" and bool(r["normal_clamp"]) == nc]
            if lim:
                ax.axhline(lim[0], color="k", lw=0.9, ls=":", label=f"lines' limit ({lim[0]:.3f})")
        _axes_style(ax, log=True)
        ax.set_xlabel(f"{'lines' if estimator == 'line' else 'points'} n")
        ax.set_ylabel("RMSE vs converged screen-space VO")
        ax.set_title(title, fontsize=10.5)
        ax.legend(fontsize=8.5, loc="upper right")
    ax = axes[3]
    for method in ("random", "sobol"):
        n, y, se = _series(rows, "line", "symmetric", method, nc, key="ratio")
        if len(n):
            ax.errorbar(n, y, yerr=2 * se, color=_COLORS[method], marker="o", ms=3.5, lw=1.3, capsize=2,
                        label=f"electrostatic / {_NAMES[method]}")
            ax.axhline(GOAL[method], color=_COLORS[method], lw=1.0, ls="--",
                       label=f"target {GOAL[method]:g} vs {_NAMES[method]}")
    ax.axvline(HEADLINE[1], color="0.6", lw=0.8, ls=":")
    _axes_style(ax, log=False)
    ax.set_xlabel("lines n")
    ax.set_ylabel("RMSE ratio (below the target: met)")
    ax.set_title("(f) the goal: lines, symmetric", fontsize=10.5)
    ax.legend(fontsize=8.5, loc="lower right")
    subfig.suptitle("RMSE against the number of samples, half-ball (normal_clamp=True); "
                    "error bars: 2 standard errors over seeds", fontsize=11)


# ----------------------------------------------------------------------------- report
def _f(x, digits=4) -> str:
    return "" if x is None else ("nan" if not np.isfinite(x) else f"{x:.{digits}f}")


def markdown(rows, *, command=None, seconds=None) -> str:
    """The tables of ``docs/patterns_results.md``, section "Effect on images (Fig. 4)"."""
    from ..common import machine

    info = machine()
    first = rows[0]
    k = max(r["seeds"] for r in rows)
    noise = {bool(r["normal_clamp"]): r["ref_noise"] for r in rows}
    lines = []
    if command:
        lines.append(f"Command: `{command}`" + (f" ({seconds / 60:.1f} min)" if seconds else "") + "\n")
    lines.append(f"Machine: {info['cores']} cores, {info['cpu']}, Python {info['python']}, numpy "
                 f"{info['numpy']}, scipy {info['scipy']}, vobscure {info['vobscure']}.\n")
    lines.append(f"Cornell box, {first['width']} x {first['height']}, R = 0.1 x extent, randomize=False; "
                 f"RMSE against vo_reference ({first['ref_samples']} samples; its own RMS noise "
                 f"{_f(noise.get(True))} half-ball, {_f(noise.get(False))} ball); random and Sobol': mean "
                 f"+- standard error over {k} seeds; electrostatic: the table entry (seed 0).\n")
    lines += ["### The goal (lines 9, symmetric, half-ball)", "",
              "| rival | electrostatic RMSE | rival mean +- se | ratio +- se | one-sided 95 % bound | z | "
              "ratio vs own limit +- se | target | verdict |", "|---|---|---|---|---|---|---|---|---|"]
    for g in goal(rows):
        lines.append(f"| {_NAMES[g['rival']]} | {_f(g['electrostatic'])} | {_f(g['mean'])} +- {_f(g['stderr'])} | "
                     f"{_f(g['ratio'], 3)} +- {_f(g['ratio_se'], 3)} | "
                     f"[{_f(g['lower'], 3)}, {_f(g['upper'], 3)}] | "
                     f"{g['z']:.1f} | {_f(g['ratio_limit'], 3)} +- {_f(g['ratio_limit_se'], 3)} | "
                     f"<= {g['target']:g} | **{g['verdict']}** |")
    lines += ["", "### The paper's counts, every variant", "",
              "ratio = electrostatic / rival mean (RMSE vs reference), z = (rival mean - electrostatic) / se; "
              "verdict against 0.7 (random) and 1 (Sobol').", "",
              "| estimator | normal | variant | n | electrostatic | random mean +- se | ratio +- se | verdict | "
              "Sobol' mean +- se | ratio +- se | z | verdict |", "|---" * 12 + "|"]
    for estimator in ("line", "point"):
        for nc in (True, False):
            for variant in VARIANTS[estimator]:
                for n in PAPER_COUNTS[estimator]:
                    sel = {r["method"]: r for r in rows if r["estimator"] == estimator and r["samples"] == n
                           and r["variant"] == variant and bool(r["normal_clamp"]) == nc}
                    if len(sel) < len(METHODS):
                        continue
                    es, ra, so = (sel[m] for m in METHODS)
                    lines.append(f"| {estimator} | {'half-ball' if nc else 'ball'} | {variant} | {n} | "
                                 f"{_f(es['rmse_ref'])} | {_f(ra['rmse_ref'])} +- {_f(ra['rmse_ref_se'])} | "
                                 f"{_f(ra['ratio'], 3)} +- {_f(ra['ratio_se'], 3)} | {ra['verdict']} | "
                                 f"{_f(so['rmse_ref'])} +- {_f(so['rmse_ref_se'])} | "
                                 f"{_f(so['ratio'], 3)} +- {_f(so['ratio_se'], 3)} | {so['z']:.1f} | "
                                 f"{so['verdict']} |")
    lines += ["", "### The paper's pairs: 9 against 10 lines, 12 against 13 points (electrostatic)", "",
              "RMSE of the electrostatic pattern at n and n + 1, against the reference and against the "
              "estimator's own limit (points: the reference); 'lower' names the count with the lower RMSE.", "",
              "| estimator | normal | variant | vs reference: n / n + 1 | lower | vs own limit: n / n + 1 "
              "| lower |",
              "|---|---|---|---|---|---|---|"]
    for estimator in ("line", "point"):
        a, b = PAPER_COUNTS[estimator]
        for nc in (True, False):
            for variant in VARIANTS[estimator]:
                sel = {r["samples"]: r for r in rows if r["estimator"] == estimator
                       and r["method"] == "electrostatic" and r["variant"] == variant
                       and bool(r["normal_clamp"]) == nc and r["samples"] in (a, b)}
                if len(sel) < 2:
                    continue
                cells = []
                for key in ("rmse_ref", "rmse_limit"):
                    x, y = sel[a][key], sel[b][key]
                    cells.append(f"{_f(x)} / {_f(y)} | {a if x < y else b if y < x else 'tie'}")
                lines.append(f"| {estimator} | {'half-ball' if nc else 'ball'} | {variant} | "
                             + " | ".join(cells) + " |")
    for estimator in ("line", "point"):
        variants = VARIANTS[estimator]
        ns = sorted({r["samples"] for r in rows if r["estimator"] == estimator})
        if len(ns) <= len(PAPER_COUNTS[estimator]):
            continue
        lines += ["", f"### RMSE against n, {'lines' if estimator == 'line' else 'points'}, half-ball "
                  "(electrostatic / random mean / Sobol' mean)", "",
                  "| n | " + " | ".join(variants) + " |", "|---" * (len(variants) + 1) + "|"]
        for n in ns:
            cells = []
            for variant in variants:
                sel = {r["method"]: r for r in rows if r["estimator"] == estimator and r["samples"] == n
                       and r["variant"] == variant and r["normal_clamp"]}
                cells.append(" / ".join(_f(sel[m]["rmse_ref"]) if m in sel else "" for m in METHODS))
            lines.append(f"| {n} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


make = deprecated_make(__name__)
