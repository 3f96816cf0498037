"""The sample-pattern figure: quality against the number of samples, per method (Sec. 4.5, Fig. 4).

One PNG, ``patterns_quality.png`` (its curves in ``patterns_quality.csv``), that goes with ``docs/patterns.md`` and
``docs/patterns_results.md``:

(a) disk patterns with the centre forced (``center=True``, plain), line sampling;
(b) disk patterns without a forced centre (plain);
(c) ball patterns (plain), point sampling;
(d)-(f) the same with the point-symmetric variants (the estimators' defaults): odd n (with
    the centre) in (d), even n (without) in (e), the ball in (f);
(g)-(i) the electrostatic patterns of (a)-(c) against the power-law trend of their error,
    log(error) - fit(log n): the counts Loos & Sloan call unusually good (Sec. 4.5) marked.

Quality is :func:`vobscure.patterns.quality`: the RMS error of a pattern's VO estimate over
random planes and creases whose exact VO is known, with its standard error. The patterns
come from the tables in ``data/patterns/`` (generated when a table is missing).

Regenerate with ``vobscure figures patterns_quality --out docs/img``; the markdown tables of
``docs/patterns_results.md`` are ``tables(families())`` (:func:`families`, :func:`tables`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "families", "paper_claims", "symmetry_effect", "rival_ratios", "default_choice",
           "tables", "Family", "PAPER_CLAIMS", "PANELS"]

ORDER = 100
FIGSIZE = (16.0, 14.0)

#: Loos & Sloan 2010, Sec. 4.5: "In 3D 6, 12, and 33 samples have extremely low error compared
#: to sets generated with other numbers of samples. In 2D 5, 7, 9, 13, and 16 samples have low
#: error when the center is one of the samples, whereas 12, 13, and 15 samples seem to work
#: optimally if the center is not included."
PAPER_CLAIMS = {"disk-center": (5, 7, 9, 13, 16), "disk-plain": (12, 13, 15), "ball-plain": (6, 12, 33)}

#: The panels: (domain, variant) per family key.
PANELS = {
    "disk-center": ("disk", "center"),
    "disk-plain": ("disk", "plain"),
    "ball-plain": ("ball", "plain"),
    "disk-symmetric": ("disk", "symmetric"),
    "ball-symmetric": ("ball", "symmetric"),
}

#: A count is "below the trend" when its residual from the power-law fit is below minus this
#: many robust standard deviations (1.4826 MAD) of the residuals.
TREND_SIGMAS = 1.0
#: One-sided z of the paired tests "error(n) < error(n - 1)" and "< error(n + 1)": 2.33 is a
#: 1 % false-positive rate per comparison.
DIP_Z = 2.33
#: Counts below this are left out of the trend fit (n = 1, 2 are special cases, far off any
#: power law).
FIT_FROM = 3

_COLORS = {"electrostatic": "#d62728", "lloyd": "#1f77b4", "poisson": "#2ca02c", "sobol": "#9467bd",
           "halton": "#8c564b", "random": "#7f7f7f", "spiral": "#ff7f0e"}
#: The quick profile's methods, trials and largest counts (the full profile: every method, the
#: tables' QUALITY_TRIALS, n up to 33 on the disk and 40 in the ball).
_QUICK = {"methods": ("electrostatic", "sobol", "random"), "trials": 1024, "nmax": {"disk": 12, "ball": 12}}
_FULL_NMAX = {"disk": 33, "ball": 40}


@dataclass
class Family:
    """Quality against n of one method in one family."""

    n: np.ndarray          # (k,) counts
    value: np.ndarray      # (k,) RMS error
    stderr: np.ndarray     # (k,)
    err2: dict             # n -> (trials,) squared errors (for paired comparisons)
    seconds: np.ndarray | None = None    # (k,) generation time recorded in the table (NaN: none)


def families(quick: bool = False, *, methods=None, trials=None, seed=None, family: str = "mixed") -> dict:
    """Quality against n for every method and family, with each trial's squared error (the
    input of :func:`paper_claims`, :func:`symmetry_effect` and :func:`tables`).

    Parameters
    ----------
    quick : bool, optional
        Three methods, n <= 12, 1024 trials (seconds).
    methods : sequence of str, optional
        Default every method of :data:`vobscure.patterns.METHODS`.
    trials, seed, family : optional
        Of :func:`vobscure.patterns.quality`; default its defaults (the tables' settings).

    Returns
    -------
    dict
        ``{family_key: {method: Family}}`` for the keys of :data:`PANELS`, plus
        ``"settings"``: trials, seed and the source of every pattern (table or generated).
    """
    from ... import patterns as P

    quick = bool(quick)
    methods = tuple(methods or (_QUICK["methods"] if quick else P.METHODS))
    trials = trials or (_QUICK["trials"] if quick else P.QUALITY_TRIALS)
    nmax = _QUICK["nmax"] if quick else _FULL_NMAX
    seed = P.QUALITY_SEED if seed is None else seed
    out: dict = {"settings": {"trials": trials, "seed": seed, "family": family, "sources": {}}}
    for key, (domain, variant) in PANELS.items():
        dim = 2 if domain == "disk" else 3
        out[key] = {}
        for method in methods:
            table = P.load_table(domain, method, variant=variant)
            counts = range(1, nmax[domain] + 1)
            ns, val, se, err2, secs = [], [], [], {}, []
            sources = set()
            for n in counts:
                p = table.get(n)
                if p is None:
                    symmetric, center = P.precomputed.variant_flags(variant, n)
                    p = P.constructors.make_pattern(dim, n, method, center, symmetric, 0)
                sources.add(p.provenance.get("source", "?").split(" ")[0])
                secs.append(float(p.provenance.get("seconds", np.nan)))
                e2 = P.metric.squared_errors(p, trials=trials, seed=seed, family=family)
                rms = math.sqrt(float(np.mean(e2)))
                ns.append(n)
                val.append(rms)
                se.append(float(np.std(e2, ddof=1)) / math.sqrt(len(e2)) / (2 * rms) if rms > 0 else 0.0)
                err2[n] = e2
            out[key][method] = Family(np.array(ns), np.array(val), np.array(se), err2, np.array(secs))
            out["settings"]["sources"][f"{key}/{method}"] = sorted(sources)
    return out


def _trend(fam: Family):
    """Least-squares power law log(err) = a + b log n over n >= FIT_FROM, and the residuals."""
    ok = fam.n >= FIT_FROM
    b, a = np.polyfit(np.log(fam.n[ok]), np.log(fam.value[ok]), 1)
    resid = np.log(fam.value) - (a + b * np.log(fam.n))
    mad = float(np.median(np.abs(resid[ok] - np.median(resid[ok]))))
    return a, b, resid, 1.4826 * mad


def _paired_z(fam: Family, n: int, m: int) -> float:
    """z of "MSE(n) < MSE(m)" from the per-trial squared errors (common random numbers)."""
    d = fam.err2[m] - fam.err2[n]
    se = float(np.std(d, ddof=1)) / math.sqrt(len(d))
    return float(np.mean(d)) / se if se > 0 else (np.inf if np.mean(d) > 0 else 0.0)


def paper_claims(data: dict, method: str = "electrostatic") -> list[dict]:
    """Check the "unusually low error" counts of Sec. 4.5 in the plain families.

    A count n is judged on two signs: a **dip** (its MSE is below both neighbours', each by a
    paired one-sided z > :data:`DIP_Z`) and **below trend** (its log error lies more than
    :data:`TREND_SIGMAS` robust standard deviations below the power-law fit). Confirmed: both;
    partly: one; not confirmed: neither.

    Returns
    -------
    list of dict
        One row per family and claimed n: ``family, n, error, stderr, prev, next, z_prev,
        z_next, residual, sigma, dip, below, verdict``; then one row per family with
        ``n = None`` listing the counts that meet both signs in the data (``found``).
    """
    rows = []
    for key, claimed in PAPER_CLAIMS.items():
        fam = data[key][method]
        _, _, resid, sigma = _trend(fam)
        idx = {int(n): i for i, n in enumerate(fam.n)}

        def signs(n):
            i = idx[n]
            z_prev = _paired_z(fam, n, n - 1) if n - 1 in idx else np.nan
            z_next = _paired_z(fam, n, n + 1) if n + 1 in idx else np.nan
            dip = bool(np.nan_to_num(z_prev, nan=np.inf) > DIP_Z and np.nan_to_num(z_next, nan=np.inf) > DIP_Z)
            below = bool(resid[i] < -TREND_SIGMAS * sigma)
            return i, z_prev, z_next, dip, below

        for n in claimed:
            if n not in idx:
                continue
            i, z_prev, z_next, dip, below = signs(n)
            verdict = "confirmed" if dip and below else ("partly" if dip or below else "not confirmed")
            rows.append({"family": key, "n": n, "error": fam.value[i], "stderr": fam.stderr[i],
                         "prev": fam.value[i - 1] if i > 0 else np.nan,
                         "next": fam.value[i + 1] if i + 1 < len(fam.n) else np.nan,
                         "z_prev": z_prev, "z_next": z_next, "residual": resid[i], "sigma": sigma,
                         "dip": dip, "below": below, "verdict": verdict})
        found = [int(n) for n in fam.n if n >= FIT_FROM and all(signs(int(n))[3:])]
        rows.append({"family": key, "n": None, "found": found})
    return rows


def _matched_plain(key: str, n: int) -> str:
    """The plain family a symmetric pattern of n points is compared with: the same centre."""
    if key == "ball-symmetric":
        return "ball-plain"
    return "disk-center" if n % 2 == 1 else "disk-plain"


def symmetry_effect(data: dict) -> list[dict]:
    """Symmetric against plain, per method: the geometric mean over n of error(sym) / error(plain).

    Odd disk counts are compared with the plain patterns with the centre, even ones with
    those without; the ball with the plain ball. n = 1 (identical) is left out.

    Returns
    -------
    list of dict
        ``domain, method, ratio, better, worse, count``: better/worse count the n where the
        paired z of the difference exceeds :data:`DIP_Z` either way.
    """
    rows = []
    for key, domain in (("disk-symmetric", "disk"), ("ball-symmetric", "ball")):
        for method, fam in data[key].items():
            logs, better, worse = [], 0, 0
            for i, n in enumerate(fam.n):
                n = int(n)
                if n == 1:
                    continue
                plain = data[_matched_plain(key, n)][method]
                j = int(np.searchsorted(plain.n, n))
                logs.append(math.log(fam.value[i] / plain.value[j]))
                d = plain.err2[n] - fam.err2[n]
                se = float(np.std(d, ddof=1)) / math.sqrt(len(d))
                z = float(np.mean(d)) / se if se > 0 else 0.0
                better += z > DIP_Z
                worse += z < -DIP_Z
            rows.append({"domain": domain, "method": method, "ratio": math.exp(float(np.mean(logs))),
                         "better": better, "worse": worse, "count": len(logs)})
    return rows


#: Count ranges of the electrostatic-against-rivals comparison ("particularly at low sample
#: counts", Sec. 4.5).
RIVAL_RANGES = {"disk": ((2, 8), (9, 16), (17, 33)), "ball": ((2, 8), (9, 20), (21, 40))}


def rival_ratios(data: dict, method: str = "electrostatic") -> list[dict]:
    """Geometric mean of error(method) / error(rival) over count ranges, plain families."""
    rows = []
    for key in ("disk-center", "disk-plain", "ball-plain"):
        if method not in data.get(key, {}):
            continue
        base = data[key][method]
        for lo, hi in RIVAL_RANGES[key.split("-")[0]]:
            sel = (base.n >= lo) & (base.n <= hi)
            if not sel.any():
                continue
            ratios = {m: math.exp(float(np.mean(np.log(base.value[sel] / f.value[sel]))))
                      for m, f in data[key].items() if m != method}
            rows.append({"family": key, "counts": f"{lo}-{hi}", "ratios": ratios})
    return rows


def default_choice(data: dict) -> list[dict]:
    """Methods ranked by the geometric-mean error of their symmetric patterns (n >= 2)."""
    rows = []
    for key in ("disk-symmetric", "ball-symmetric"):
        scores = {m: math.exp(float(np.mean(np.log(f.value[f.n >= 2])))) for m, f in data[key].items()}
        best = min(scores.values())
        for m in sorted(scores, key=scores.get):
            wins = sum(1 for i, n in enumerate(data[key][m].n) if n >= 2 and data[key][m].value[i]
                       <= min(f.value[i] for f in data[key].values()))
            rows.append({"family": key, "method": m, "geomean": scores[m], "relative": scores[m] / best,
                         "best_at": wins})
    return rows


def tables(data: dict) -> str:
    """The tables of ``docs/patterns_results.md``."""
    st = data["settings"]
    lines = [f"Quality: `vobscure.patterns.quality(pattern)` (trials={st['trials']}, "
             f"seed={st['seed']}, family=\"{st.get('family', 'mixed')}\"): RMS error of the VO estimate.", ""]
    keys = [k for k in PANELS if k in data]
    for key in keys:
        methods = list(data[key])
        lines += [f"### {key}", "", "| n | " + " | ".join(methods) + " |",
                  "|---" * (len(methods) + 1) + "|"]
        fam0 = data[key][methods[0]]
        for i, n in enumerate(fam0.n):
            cells = [f"{data[key][m].value[i]:.4f}" for m in methods]
            lines.append(f"| {n} | " + " | ".join(cells) + " |")
        lines.append("")
    for method in [m for m in ("electrostatic", "lloyd") if m in data["disk-plain"]]:
        lines += [f"### Paper claims ({method}, plain)", "",
                  "| family | n | error +- stderr | error(n-1) | error(n+1) | z vs n-1 | z vs n+1 | "
                  "residual / sigma | dip | below trend | verdict |", "|---" * 11 + "|"]
        founds = []
        for r in paper_claims(data, method):
            if r["n"] is None:
                founds.append(f"- {r['family']}: {', '.join(map(str, r['found'])) or 'none'}")
                continue
            lines.append(f"| {r['family']} | {r['n']} | {r['error']:.4f} +- {r['stderr']:.4f} | "
                         f"{r['prev']:.4f} | {r['next']:.4f} | {r['z_prev']:.1f} | {r['z_next']:.1f} | "
                         f"{r['residual'] / r['sigma']:+.2f} | {'yes' if r['dip'] else 'no'} | "
                         f"{'yes' if r['below'] else 'no'} | {r['verdict']} |")
        lines += ["", f"Counts that meet both signs ({method}, n >= 3):", ""] + founds + [""]
    lines += ["### The electrostatic patterns against each rival", "",
              "Geometric mean over the counts of error(electrostatic) / error(rival), plain families "
              "(below 1: electrostatic better).", "",
              "| family | counts | " + " | ".join(m for m in data["disk-plain"] if m != "electrostatic") + " |",
              "|---|---|" + "---|" * (len(data["disk-plain"]) - 1)]
    for r in rival_ratios(data):
        lines.append(f"| {r['family']} | {r['counts']} | " + " | ".join(f"{v:.3f}" for v in r["ratios"].values())
                     + " |")
    lines += ["", "### Symmetric against plain", "", "| domain | method | error ratio sym / plain (geomean) | "
              "sym better | sym worse | of |", "|---|---|---|---|---|---|"]
    for r in symmetry_effect(data):
        lines.append(f"| {r['domain']} | {r['method']} | {r['ratio']:.3f} | {r['better']} | {r['worse']} | "
                     f"{r['count']} |")
    lines += ["", "### The default: symmetric patterns ranked", "",
              "| family | method | geomean error (n >= 2) | relative to the best | best at (counts) |",
              "|---|---|---|---|---|"]
    for r in default_choice(data):
        lines.append(f"| {r['family']} | {r['method']} | {r['geomean']:.4f} | {r['relative']:.3f} | "
                     f"{r['best_at']} |")
    lines += ["", "### Time per pattern (seconds, recorded in the tables)", "",
              "| family | method | median n <= 33 | max n <= 33 (at n) |", "|---|---|---|---|"]
    for key in keys:
        for method in [m for m in ("electrostatic", "lloyd") if m in data[key]]:
            fam = data[key][method]
            ok = (fam.n <= 33) & np.isfinite(fam.seconds)
            if not ok.any():
                continue
            i = int(np.argmax(np.where(ok, fam.seconds, -1)))
            lines.append(f"| {key} | {method} | {np.median(fam.seconds[ok]):.1f} | "
                         f"{fam.seconds[i]:.1f} ({fam.n[i]}) |")
    return "\n".join(lines) + "\n"


def measure(profile) -> Rows:
    """Quality against n of :func:`families` (the quick profile: three methods, n <= 12, 1024
    trials; the metric's own seed, :data:`vobscure.patterns.QUALITY_SEED`).

    Returns
    -------
    Rows
        One row per (family, method, n): ``rms_error``, its ``stderr`` and the ``seconds`` the
        table records for generating the pattern (NaN: none).
    """
    data = families(profile.quick)
    rows = [{"family": key, "method": method, "n": int(n), "rms_error": float(v), "stderr": float(se),
             "seconds": float(t)}
            for key in PANELS for method, fam in data[key].items()
            for n, v, se, t in zip(fam.n, fam.value, fam.stderr, fam.seconds)]
    settings = data["settings"]
    return Rows(rows, meta={"trials": settings["trials"], "seed": settings["seed"]})


def plot(rows, fig) -> None:
    """Panels (a) to (i) from :func:`measure`'s rows."""
    data = {key: {} for key in PANELS}
    for r in rows:
        data[r["family"]].setdefault(r["method"], []).append(r)
    for key, by_method in data.items():
        for method, rs in by_method.items():
            by_method[method] = Family(np.array([r["n"] for r in rs]), np.array([r["rms_error"] for r in rs]),
                                       np.array([r["stderr"] for r in rs]), {})
    data["settings"] = rows.meta
    axes = fig.subplots(3, 3)
    titles = {
        (0, 0): ("disk-center", None, "(a) disk, centre forced (plain), line sampling"),
        (0, 1): ("disk-plain", None, "(b) disk, no centre forced (plain)"),
        (0, 2): ("ball-plain", None, "(c) ball (plain), point sampling"),
        (1, 0): ("disk-symmetric", 1, "(d) disk, symmetric, odd n (centre + pairs)"),
        (1, 1): ("disk-symmetric", 0, "(e) disk, symmetric, even n (pairs)"),
        (1, 2): ("ball-symmetric", None, "(f) ball, symmetric"),
    }
    for (r, c), (key, parity, title) in titles.items():
        ax = axes[r, c]
        for method, fam in data[key].items():
            keep = np.ones(len(fam.n), bool) if parity is None else (fam.n % 2 == parity)
            ax.errorbar(fam.n[keep], fam.value[keep], yerr=2 * fam.stderr[keep], color=_COLORS[method],
                        marker="o", ms=3, lw=1.2 if method != "electrostatic" else 2.0, capsize=0,
                        label=method)
        claimed = PAPER_CLAIMS.get(key, ())
        for n in claimed:
            ax.axvline(n, color="0.6", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_xlabel("samples n")
        ax.set_ylabel("RMS error of VO (quality)")
        ax.set_title(title, fontsize=11)
        ax.grid(True, which="both", alpha=0.25)
    axes[0, 0].legend(fontsize=8, ncol=2, loc="upper right")

    for c, key in enumerate(("disk-center", "disk-plain", "ball-plain")):
        ax = axes[2, c]
        method = "electrostatic" if "electrostatic" in data[key] else next(iter(data[key]))
        fam = data[key][method]
        a, b, resid, sigma = _trend(fam)
        ok = fam.n >= FIT_FROM
        ax.bar(fam.n[ok], resid[ok], color=np.where(np.isin(fam.n[ok], PAPER_CLAIMS[key]), "#d62728", "0.6"),
               width=0.8)
        ax.axhline(-TREND_SIGMAS * sigma, color="k", lw=0.8, ls="--",
                   label=f"-{TREND_SIGMAS:g} robust sd")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("samples n")
        ax.set_ylabel("log(error) - trend")
        ax.set_title(f"({'ghi'[c]}) {method} {key}: residual from error ~ n^{b:.2f}\n"
                     f"(red: counts the paper calls unusually good)", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
        ax.grid(True, alpha=0.25)
    s = data["settings"]
    fig.suptitle(f"Sample-pattern quality: RMS error of the VO estimate over random planes and creases "
                 f"(vobscure.patterns.quality, {s['trials']} trials, seed {s['seed']}); error bars 2 stderr",
                 fontsize=12)


make = deprecated_make(__name__)
