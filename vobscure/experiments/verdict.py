"""The verdict of ``vobscure compare``: its rows turned into sentences and numbers.

:func:`verdict` answers "which estimator, with how many samples, at what cost?" per reference
and radius (Pareto fronts in time and taps, the cheapest configuration meeting a target, the
most accurate within a budget, the dominant error term and what reduces it);
:func:`thin_sentence` and :func:`layers_sentence` add what the thin-feature band and a layered
G-buffer change. :func:`vobscure.experiments.compare.compare` measures the rows and calls them.
"""

from __future__ import annotations

import numpy as np

from .. import methods as _methods
from .. import references as _references

__all__ = ["verdict", "pareto_front", "thin_sentence", "layers_sentence", "ms", "TARGET_FACTOR", "POOR_RMSE",
           "SUGGEST_MIN_GAIN", "TERM_NAMES", "REFERENCE_WORDS"]

#: Default target RMSE: the best configuration's error times this factor.
TARGET_FACTOR = 1.5
#: A best RMSE above this (a fifth of the visibility range) is called out in the verdict as a
#: poor fit rather than reported as if it were a good choice.
POOR_RMSE = 0.2
#: A thickness is recommended only when it lowers the RMSE by at least this fraction.
SUGGEST_MIN_GAIN = 0.02
#: How the verdict names the terms of the error decomposition.
TERM_NAMES = {"sampling": "sampling", "screen": "screen-space model", "model": "VO-vs-AO model"}
#: How the verdict names a reference a group of configurations is scored against.
REFERENCE_WORDS = {"screen": "the converged screen-space VO (the sampling error alone)",
                   "volumetric": "the ray-cast world-space VO (the method's own quantity)",
                   "shell": "the ray-cast shell VO (the world-space VO of surfaces of a stated thickness, "
                            "standing in for the solid one on this open scene)"}



def pareto_front(cost, error) -> np.ndarray:
    """Indices of the configurations no other beats in both cost and error, by cost.

    Examples
    --------
    >>> pareto_front([1, 2, 3, 4], [0.5, 0.6, 0.2, 0.1]).tolist()
    [0, 2, 3]
    """
    cost = np.asarray(cost, dtype=float)
    error = np.asarray(error, dtype=float)
    ok = np.flatnonzero(np.isfinite(cost) & np.isfinite(error))
    order = ok[np.lexsort((error[ok], cost[ok]))]
    front, best = [], np.inf
    for i in order:
        if error[i] < best:
            front.append(int(i))
            best = error[i]
    return np.array(front, dtype=np.intp)


def thin_sentence(band, rows) -> str:
    """The verdict's sentence on the thin-feature band at one radius: per reference, the most
    accurate configuration there against the whole frame's error."""
    sel = [r for r in rows if r["radius"] == band["radius"] and np.isfinite(r.get("own_thin_rmse", np.nan))
           and not r.get("reference_only", False)]
    parts = [f"against {ref!r} {b['label']}, RMSE {b['own_thin_rmse']:.4f} (bias {b['own_thin_bias']:+.4f}) "
             f"against {b['own_rmse']:.4f} over the whole frame"
             for ref in dict.fromkeys(r["own_reference"] for r in sel)
             for b in [min((r for r in sel if r["own_reference"] == ref), key=lambda r: r["own_thin_rmse"])]]
    return (f"Thin-feature band at R = {band['radius']:.4g} (the far side of depth edges, where halos live: "
            f"{band['pixels']} pixels, {band['fraction']:.1%} of the covered ones): "
            + ("; ".join(parts) + "." if parts else "no configuration is scored there."))


def _layered(row) -> bool:
    """Whether a row's method read the solid intervals of a layered G-buffer."""
    return row.get("thickness") == "layers"


def layers_sentence(rows, layers=None) -> str:
    """The verdict's sentence on a comparison with ``thickness="layers"``: which configurations
    read the solid intervals (rows whose ``thickness`` is ``"layers"``), which take no layers and
    ran on the first depth alone, and what the single-depth screen-space reference then measures.
    ``layers``: the depth-peeled layers K rendered (None: the G-buffer's own intervals).

    Examples
    --------
    >>> rows = [dict(label="line:5", thickness="layers", own_reference="volumetric", screen_rmse=0.1),
    ...         dict(label="area:1", thickness=None, own_reference="volumetric", screen_rmse=0.1)]
    >>> print(layers_sentence(rows, 4))  # doctest: +ELLIPSIS
    Thickness from layers (K = 4 depth-peeled layers, docs/layers.md): line:5 read the solid intervals ...; area:1 take no layers and ran as without a thickness... The converged screen-space VO ('screen') has no layers...
    """
    with_layers = list(dict.fromkeys(r["label"] for r in rows if _layered(r)))
    without = list(dict.fromkeys(r["label"] for r in rows if not _layered(r)))
    source = f"K = {layers} depth-peeled layers" if layers is not None else "the G-buffer's own solid intervals"
    text = (f"Thickness from layers ({source}, docs/layers.md): "
            + (f"{', '.join(with_layers)} read the solid intervals (thickness 'layers': what lies behind the "
               f"first surface as the layers saw it)" if with_layers else "no configuration here reads layers"))
    if without:
        text += (f"; {', '.join(without)} take no layers and ran as without a thickness (the first depth alone, "
                 f"every surface solid behind it)")
    text += "."
    if any(_layered(r) and np.isfinite(r.get("screen_rmse", np.nan)) for r in rows):
        text += (" The converged screen-space VO ('screen') has no layers: it stays the single-depth model, so the "
                 "error of a configuration with layers against it is its sampling error plus the difference "
                 "between the two models; those configurations are left out of the sampling-error ranking and "
                 "of the split of the error by cause.")
        if any(_layered(r) and r.get("own_reference") == "screen" for r in rows):
            text += (" With no ray-cast reference, 'screen' is also their own reference here, and their scores "
                     "hold that model difference.")
    return text


def ms(seconds) -> str:
    """Seconds as milliseconds with one decimal: ``"4.0 ms"``."""
    return f"{1e3 * seconds:.1f} ms"


def verdict(rows, *, target_rmse=None, budget_ms=None, thickness_trials=()) -> dict:
    """The answer to "which estimator, with how many samples, at what cost?" from compare rows.

    Each configuration is judged against its own reference (``own_reference``: the reference
    of the quantity it estimates), and, where the converged screen-space VO is its limit,
    against that too (``screen_rmse``: the sampling error alone, which is what the choice of
    estimator and sample count controls). Per reference (and radius): the Pareto front in time
    and in taps, the cheapest configuration meeting the target RMSE (default
    :data:`TARGET_FACTOR` x the best error) in time and in taps, the most accurate one
    within ``budget_ms``; then which term of the decomposition dominates the best
    configuration's error and what reduces it, with the measured thickness trials when given.
    A row with ``thickness="layers"`` (it read a layered G-buffer's solid intervals) is ranked
    against its own reference only: its error against the single-depth screen-space VO is not
    its sampling error alone (:func:`layers_sentence`).

    Returns
    -------
    dict
        ``text`` (list of sentences), ``groups`` (per reference, radius and error column:
        ``error``, ``front_time``,
        ``front_taps``, ``target_rmse``, ``cheapest_time``, ``cheapest_taps``,
        ``best_in_budget``, ``best``), ``dominant`` (per radius: the terms' RMSE and the
        dominant one), ``thickness`` (the trials and the best of them).

    Examples
    --------
    >>> rows = [dict(label="line:5", method="line", radius=1.0, seconds=0.004, taps_per_pixel=5,
    ...              own_reference="screen", own_rmse=0.05),
    ...         dict(label="point:33", method="point", radius=1.0, seconds=0.07, taps_per_pixel=32,
    ...              own_reference="screen", own_rmse=0.02)]
    >>> v = verdict(rows, target_rmse=0.03)
    >>> v["groups"][0]["cheapest_time"], [r for r in v["groups"][0]["front_time"]]
    ('point:33', ['line:5', 'point:33'])
    """
    text, groups, dominant = [], [], []
    shippable = [r for r in rows if not r.get("reference_only", False)]
    # (reference, radius, error column): each configuration against its own quantity's
    # reference, and -- for estimators whose limit is the converged screen-space VO -- against
    # that as well, which isolates the sampling error the choice of estimator controls
    keys = {(r["own_reference"], r["radius"], "own_rmse") for r in shippable if r.get("own_reference")}
    def screen_limited(r):
        # a configuration with layers has another model than the single-depth screen-space VO
        q = r.get("quantity")
        return r.get("own_reference") not in (None, "screen") and np.isfinite(r.get("screen_rmse", np.nan)) \
            and (q is None or _methods.QUANTITIES[q].screen_limit) and not _layered(r)

    keys |= {("screen", r["radius"], "screen_rmse") for r in shippable if screen_limited(r)}
    order = _references.names()
    for ref, radius, col in sorted(keys, key=lambda k: (k[1], k[2] != "own_rmse", order.index(k[0]))):
        sel = [r for r in shippable if r["radius"] == radius and np.isfinite(r.get(col, np.nan))
               and (r.get("own_reference") == ref if col == "own_rmse" else screen_limited(r))]
        if not sel:
            continue
        err = np.array([r[col] for r in sel])
        best = sel[int(np.argmin(err))]
        target = float(target_rmse) if target_rmse is not None else TARGET_FACTOR * best[col]
        g = dict(reference=ref, radius=radius, error=col, target_rmse=target, best=best["label"],
                 best_rmse=best[col])
        for cost, name in (("seconds", "time"), ("taps_per_pixel", "taps")):
            x = np.array([r[cost] for r in sel], float)
            g[f"front_{name}"] = [sel[i]["label"] for i in pareto_front(x, err)]
            ok = [r for r in sel if r[col] <= target and np.isfinite(r[cost])]
            g[f"cheapest_{name}"] = min(ok, key=lambda r: (r[cost], r[col]))["label"] if ok else None
        if budget_ms is not None:
            within = [r for r in sel if np.isfinite(r["seconds"]) and 1e3 * r["seconds"] <= budget_ms]
            g["best_in_budget"] = min(within, key=lambda r: r[col])["label"] if within else None
        groups.append(g)
        what = REFERENCE_WORDS.get(ref, f"the ray-cast {_references.get(ref).measures} ({ref!r}, the method's "
                                         f"own quantity)")
        by_label = {r["label"]: r for r in sel}
        lines = [f"Against {what} at R = {radius:.4g}: the most accurate is {best['label']} "
                 f"(RMSE {best[col]:.4f}, {ms(best['seconds'])}, {best['taps_per_pixel']} taps/px)."]
        if best[col] > POOR_RMSE:
            lines.append(f"That is a poor fit: even the best is off by {best[col]:.2f} on a visibility range of 1, "
                         f"so no configuration here estimates this reference well on this scene"
                         + (" (an object-space model whose proxy does not fit the geometry: see its page in the "
                            "docs)." if best["taps_per_pixel"] == 0 else "; the error split below says why."
                            if ref == "volumetric" else "."))
        for name, unit in (("time", "time"), ("taps", "taps per pixel")):
            cheap = g[f"cheapest_{name}"]
            if cheap is None:
                lines.append(f"No configuration reaches RMSE {target:.4f}.")
                break
            c = by_label[cheap]
            lines.append(f"Cheapest in {unit} with RMSE <= {target:.4f}"
                         f"{'' if target_rmse is not None else f' ({TARGET_FACTOR:g} x the best)'}: "
                         f"{cheap} (RMSE {c[col]:.4f}, {ms(c['seconds'])}, {c['taps_per_pixel']} taps/px).")
        lines.append(f"Pareto front in time: {', '.join(g['front_time'])}; in taps: {', '.join(g['front_taps'])}.")
        if budget_ms is not None:
            b = g["best_in_budget"]
            lines.append(f"Within {budget_ms:g} ms: " + (f"{b} (RMSE {by_label[b][col]:.4f})." if b
                                                         else "no configuration fits."))
        text.append(" ".join(lines))
    # which error term dominates, for the most accurate configuration against the world-space VO
    def vo_estimator(r):
        # the decomposition (estimate - screen VO - world VO - AO) describes VO estimators only
        q = r.get("quantity")
        return q is None or _methods.QUANTITIES[q].screen_limit

    for radius in sorted({r["radius"] for r in shippable}):
        sel = [r for r in shippable if r["radius"] == radius and "screen_error_rmse" in r and vo_estimator(r)
               and not _layered(r)]
        if not sel:
            continue
        world = next((w for w in _references.WORLD_VO if any(f"{w}_rmse" in r for r in sel)), "volumetric")
        best = min(sel, key=lambda r: r.get(f"{world}_rmse", np.inf))
        terms = {t: best[f"{t}_error_rmse"] for t in ("sampling", "screen", "model") if f"{t}_error_rmse" in best}
        top = max(terms, key=terms.get)
        dominant.append(dict(radius=radius, label=best["label"], dominant=top, **{f"{t}_rmse": v for t, v in terms.items()}))
        parts = ", ".join(f"{TERM_NAMES[t]} {v:.4f}" for t, v in terms.items())
        sentence = (f"Error of {best['label']} at R = {radius:.4g}, split by cause (RMSE): {parts}; "
                    f"the {TERM_NAMES[top]} error dominates. ")
        if top == "sampling":
            sentence += ("More samples or a method further along the front reduce it; "
                         "the bilateral blur (vobscure.bilateral_blur) trades it for bias.")
        elif top == "screen":
            sentence += ("The depth buffer treats every surface as infinitely thick and knows nothing "
                         "behind it or outside the image; more samples cannot fix that.")
        else:
            sentence += ("Even the exact world-space VO differs this much from ray-cast AO: VO is not AO. "
                         "The normal clamp (--normals, the half-ball) or an AO estimator targets AO more closely.")
        if "model" in terms and top != "model":
            sentence += (f" Against ray-cast AO, a different quantity, it is further off by the model "
                         f"error ({terms['model']:.4f}); that is not the estimator's sampling accuracy.")
        text.append(sentence)
    thick = None
    if thickness_trials:
        best_t = min(thickness_trials, key=lambda t: t["volumetric_rmse"])
        thick = dict(trials=list(thickness_trials), best=best_t)
        tried = ", ".join(f"{t['thickness']:.3g} ({t['factor']:g} R): {t['volumetric_rmse']:.4f}"
                          for t in thickness_trials)
        gain = best_t["baseline_rmse"] - best_t["volumetric_rmse"]
        if gain > SUGGEST_MIN_GAIN * best_t["baseline_rmse"]:
            text.append(f"Thickness model (Loos & Sloan 2010, Sec. 4.3), measured on {best_t['label']}: "
                        f"RMSE against the world-space VO {best_t['baseline_rmse']:.4f} without it; {tried}. "
                        f"Use --thickness {best_t['thickness']:.3g}: RMSE {best_t['volumetric_rmse']:.4f} "
                        f"({gain / best_t['baseline_rmse']:.0%} lower) in {ms(best_t['seconds'])}.")
        else:
            text.append(f"Thickness model measured on {best_t['label']} ({tried}): no thickness beats "
                        f"none (RMSE {best_t['baseline_rmse']:.4f}).")
    return dict(text=text, groups=groups, dominant=dominant, thickness=thick)
