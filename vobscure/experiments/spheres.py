"""Measurements of Ren et al. (2006)'s sphere sets in spherical harmonics.

Three tables, each a list of dict rows (the figures ``ren_spheres`` and ``proxy_bunny`` plot
them, ``docs/sphere-sets.md`` quotes them):

- :func:`union_rows`: every method ("product", "sum", "shexp" with its exponentials) and
  order against the exact union visibility of the same spheres (:func:`union_visibility`,
  analytic ray-sphere tests), as a function of the number of spheres and of the occlusion
  depth (the exact union's occlusion 1 - V).
- :func:`proxy_rows`: the sphere sets of :func:`sphere_set` (k = 8, 32, 128) against the
  Embree AO of the mesh itself: on the ground plane under the Stanford bunny (when
  ``../shared/data/meshes`` has it) and on the Cornell box's floor around its two boxes
  (walls removed on both sides of the comparison). Rows for the SH methods and for the exact
  union of the spheres (the proxy's own error, without the SH's).
- :func:`timing_rows`: time per receiver against the number of spheres (1 to 256),
  ``"product"`` against ``"shexp"`` and ``"sum"``, all in one run, with the ratio.

Run everything and print the tables: ``python -m vobscure.experiments.spheres [--quick]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..groundtruth import ambient_occlusion
from ..objectspace.spheres import inside_mesh, sphere_set, sphere_set_ao, union_visibility
from ..scenes import Scene, cornell_box, load

__all__ = ["SETTINGS", "setting", "union_rows", "proxy_rows", "timing_rows", "hybrid_rows", "BUNNY_PATH",
           "VARIANTS", "band_limit_rows", "log_table_rows", "bunny_scene", "cornell_boxes_scene", "ground_grid", "main"]

#: The Stanford bunny of the shared data folder (absent on machines without it).
BUNNY_PATH = Path(__file__).resolve().parents[3] / "shared/data/meshes/stanford-bunny.obj"

#: (method, exp) pairs measured against the union.
VARIANTS = (("product", None), ("sum", None), ("shexp", "hybrid"), ("shexp", "ol"), ("shexp", "exact"))

SETTINGS = {
    False: {"orders": (3, 4, 5, 6), "counts": (1, 2, 4, 8, 16, 32, 64, 128, 256), "scales": (0.25, 0.5, 0.8),
            "points": 128, "union_rays": 1024, "proxy_grid": 40, "proxy_rays": 512, "proxy_ks": (8, 32, 128),
            "proxy_order": 4, "timing_points": 1024, "timing_counts": (1, 2, 4, 8, 16, 32, 64, 128, 256),
            "timing_orders": (4, 6), "repeats": 3, "hybrid_fractions": (0.02, 0.05, 0.1, 0.25, 1.0)},
    True: {"orders": (4, 6), "counts": (1, 4, 16), "scales": (0.5,), "points": 24, "union_rays": 128,
           "proxy_grid": 10, "proxy_rays": 64, "proxy_ks": (8, 32), "proxy_order": 4, "timing_points": 64,
           "timing_counts": (1, 4, 16), "timing_orders": (4,), "repeats": 1,
           "hybrid_fractions": (0.05, 1.0)},
}

#: Occlusion-depth bins (exact union occlusion 1 - V) of :func:`union_rows`.
DEPTH_BINS = (0.0, 0.1, 0.25, 0.5, 0.75, 1.0)


def setting(quick: bool) -> dict:
    """The sizes of a full or quick run."""
    return dict(SETTINGS[bool(quick)])


# ----------------------------------------------------------------------------- vs the union
def _configuration(count: int, scale: float, points: int, rng):
    """``count`` random spheres above a receiver plane z = 0 (normals +z), total volume about
    that of one sphere of radius ``scale``; receivers uniform in a square, those inside a
    sphere dropped (their visibility is 0 by definition, for every method)."""
    c = np.column_stack([rng.uniform(-1, 1, count), rng.uniform(-1, 1, count), rng.uniform(0.1, 1.2, count)])
    r = scale * count ** (-1.0 / 3.0) * rng.uniform(0.6, 1.4, count)
    p = np.column_stack([rng.uniform(-1.3, 1.3, points), rng.uniform(-1.3, 1.3, points), np.zeros(points)])
    d = np.linalg.norm(p[:, None, :] - c[None, :, :], axis=-1)
    p = p[np.all(d > r, axis=1)]
    return p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), c, r


def union_rows(quick: bool = False, *, seed: int = 0):
    """Every method and order against the exact union, per sphere count and per depth bin.

    Returns
    -------
    (by_count, by_depth) : two lists of dict rows
        ``by_count``: method, exp, order, count, points, rmse, bias, max_abs, ref_stderr (RMS
        standard error of the union reference); ``by_depth``: method, exp, order, depth_lo,
        depth_hi, points, rmse, bias (all counts and scales pooled).
    """
    s = setting(quick)
    rng = np.random.default_rng(seed)
    pooled = {}
    by_count = []
    for count in s["counts"]:
        cases = []
        for scale in s["scales"]:
            p, n, c, r = _configuration(count, scale, s["points"], rng)
            ref = union_visibility(p, n, c, r, rays=s["union_rays"], seed=rng)
            cases.append((p, n, c, r, ref))
        truth = np.concatenate([case[4].value for case in cases])
        se = np.concatenate([case[4].stderr for case in cases])
        for method, exp in VARIANTS:
            for order in s["orders"]:
                v = np.concatenate([sphere_set_ao(p, n, c, r, order=order, method=method, exp=exp or "hybrid")
                                    for p, n, c, r, _ in cases])
                err = v - truth
                by_count.append({"method": method, "exp": exp or "", "order": order, "count": count,
                                 "points": len(v), "rmse": float(np.sqrt(np.mean(err ** 2))),
                                 "bias": float(np.mean(err)), "max_abs": float(np.max(np.abs(err))),
                                 "ref_stderr": float(np.sqrt(np.mean(se ** 2)))})
                pooled.setdefault((method, exp or "", order), []).append((1.0 - truth, err))
    by_depth = []
    for (method, exp, order), parts in pooled.items():
        depth = np.concatenate([d for d, _ in parts])
        err = np.concatenate([e for _, e in parts])
        for lo, hi in zip(DEPTH_BINS[:-1], DEPTH_BINS[1:]):
            sel = (depth >= lo) & ((depth < hi) if hi < 1.0 else (depth <= hi))
            if not sel.any():
                continue
            by_depth.append({"method": method, "exp": exp, "order": order, "depth_lo": lo, "depth_hi": hi,
                             "points": int(sel.sum()), "rmse": float(np.sqrt(np.mean(err[sel] ** 2))),
                             "bias": float(np.mean(err[sel]))})
    return by_count, by_depth


def hybrid_rows(quick: bool = False, *, seed: int = 0):
    """The hybrid exponential's threshold (``sh.HYBRID_FRACTION``) against accuracy and the
    number of squarings, on the configurations of :func:`union_rows` with 32 spheres
    (quick: 16), order 4: RMSE against the union for each fraction tried."""
    from ..objectspace import sh

    s = setting(quick)
    count = 16 if quick else 32
    rng = np.random.default_rng(seed)
    cases = []
    for scale in s["scales"]:
        p, n, c, r = _configuration(count, scale, s["points"], rng)
        cases.append((p, n, c, r, union_visibility(p, n, c, r, rays=s["union_rays"], seed=rng)))
    truth = np.concatenate([case[4].value for case in cases])
    rows = []
    saved = sh.HYBRID_FRACTION
    try:
        for fraction in s["hybrid_fractions"]:
            sh.HYBRID_FRACTION = fraction
            v = np.concatenate([sphere_set_ao(p, n, c, r, order=4, method="shexp", exp="hybrid")
                                for p, n, c, r, _ in cases])
            rows.append({"fraction": fraction, "count": count, "order": 4,
                         "rmse": float(np.sqrt(np.mean((v - truth) ** 2))), "bias": float(np.mean(v - truth))})
    finally:
        sh.HYBRID_FRACTION = saved
    return rows


# ----------------------------------------------------------------------------- proxies
def bunny_scene() -> Scene | None:
    """The Stanford bunny standing on a ground slab (top face at the bunny's lowest point,
    four bunny heights wide); None when the mesh is absent."""
    import trimesh

    if not BUNNY_PATH.exists():
        return None
    bunny = load(BUNNY_PATH)
    mesh = bunny.mesh
    lo, hi = mesh.bounds
    size = float(np.max(hi - lo))
    centre = 0.5 * (lo + hi)
    ground = trimesh.creation.box(extents=(4 * size, 0.1 * size, 4 * size))
    ground.apply_translation((centre[0], lo[1] - 0.05 * size, centre[2]))
    return Scene({"bunny": mesh, "ground": ground}, name="bunny_on_ground", smooth_angle=0.0)


def cornell_boxes_scene() -> Scene:
    """The Cornell box's floor and its two boxes (no walls, no ceiling)."""
    box = cornell_box()
    return Scene({name: box.meshes[name] for name in ("floor", "short_box", "tall_box")},
                 name="cornell_boxes", smooth_angle=0.0)


def ground_grid(scene: Scene, occluders, n: int, *, margin: float, y: float, seed: int = 0):
    """An n x n grid of ground points (normal +y) over the occluders' footprint grown by
    ``margin`` on each side, without the points inside an occluder."""
    tri = np.asarray(scene.triangles)[np.isin(scene.mesh_index, [list(scene.meshes).index(m) for m in occluders])]
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    xs = np.linspace(lo[0] - margin, hi[0] + margin, n)
    zs = np.linspace(lo[2] - margin, hi[2] + margin, n)
    X, Z = np.meshgrid(xs, zs)
    p = np.column_stack([X.ravel(), np.full(X.size, y), Z.ravel()])
    lifted = p + np.array([0.0, 1e-4 * scene.extent, 0.0])
    keep = ~inside_mesh(scene, lifted, meshes=occluders, seed=seed)
    return p, keep, (n, n)


def _proxy_targets():
    out = []
    bunny = bunny_scene()
    if bunny is not None:
        lo, hi = bunny.meshes["bunny"].bounds
        out.append(("bunny", bunny, ("bunny",), float(lo[1]), 0.5 * float(np.max(hi - lo))))
    out.append(("cornell_boxes", cornell_boxes_scene(), ("short_box", "tall_box"), 0.0, 0.3))
    return out


def proxy_rows(quick: bool = False, *, seed: int = 0, images: bool = False):
    """The proxies' error against the Embree AO of the mesh, per target and k.

    Returns
    -------
    rows : list of dict
        target, k, method ("shexp", "product", "union"), order, points, rmse, bias, corr,
        ref_stderr, spheres_volume_ratio (the spheres' summed volume over the mesh's; overlaps
        count more than once, so it can exceed 1).
    images : dict, only when ``images=True``
        target -> {"truth": (n, n), k: {method: (n, n)}} with NaN where a point is inside.
    """
    s = setting(quick)
    rows = []
    pictures = {}
    for target, scene, occluders, y, margin in _proxy_targets():
        p, keep, shape = ground_grid(scene, occluders, s["proxy_grid"], margin=margin, y=y, seed=seed)
        pts = p[keep]
        nrm = np.tile([0.0, 1.0, 0.0], (len(pts), 1))
        truth = ambient_occlusion(scene, pts, nrm, rays=s["proxy_rays"], weighting="cosine", seed=seed)
        volume = sum(float(scene.meshes[m].volume) for m in occluders)
        pics = {"truth": _image(truth.value, keep, shape)}
        for k in s["proxy_ks"]:
            spheres = sphere_set(scene, k, seed=seed, meshes=occluders)
            ratio = float(np.sum(4.0 / 3.0 * np.pi * spheres.radii ** 3) / volume)
            values = {
                "shexp": sphere_set_ao(pts, nrm, spheres.centers, spheres.radii, order=s["proxy_order"]),
                "product": sphere_set_ao(pts, nrm, spheres.centers, spheres.radii, order=s["proxy_order"],
                                         method="product"),
                "union": union_visibility(pts, nrm, spheres.centers, spheres.radii, rays=s["proxy_rays"],
                                          seed=seed).value,
            }
            pics[k] = {}
            for method, v in values.items():
                err = v - truth.value
                rows.append({"target": target, "k": k, "method": method,
                             "order": s["proxy_order"] if method != "union" else 0, "points": len(v),
                             "rmse": float(np.sqrt(np.mean(err ** 2))), "bias": float(np.mean(err)),
                             "corr": float(np.corrcoef(v, truth.value)[0, 1]) if np.std(v) > 0 else 0.0,
                             "ref_stderr": float(np.sqrt(np.mean(truth.stderr ** 2))),
                             "spheres_volume_ratio": ratio})
                pics[k][method] = _image(v, keep, shape)
        pictures[target] = pics
    return (rows, pictures) if images else rows


def _image(values, keep, shape):
    out = np.full(keep.shape, np.nan)
    out[keep] = values
    return out.reshape(shape)


# ----------------------------------------------------------------------------- timing
def timing_rows(quick: bool = False, *, seed: int = 0):
    """Time per receiver against the number of spheres, for each method, in one run.

    Each configuration is timed ``repeats`` times (the minimum kept) on ``timing_points``
    receivers, single process; ``ratio_product_shexp`` = product time / shexp time.
    """
    s = setting(quick)
    rng = np.random.default_rng(seed)
    rows = []
    for order in s["timing_orders"]:
        for count in s["timing_counts"]:
            p, n, c, r = _configuration(count, 0.5, 4 * s["timing_points"], rng)
            p, n = p[:s["timing_points"]], n[:s["timing_points"]]
            times = {}
            for method in ("product", "shexp", "sum"):
                best = np.inf
                for _ in range(s["repeats"]):
                    t0 = time.perf_counter()
                    sphere_set_ao(p, n, c, r, order=order, method=method)
                    best = min(best, time.perf_counter() - t0)
                times[method] = best / len(p)
            rows.append({"order": order, "count": count, "points": len(p),
                         "product_us": 1e6 * times["product"], "shexp_us": 1e6 * times["shexp"],
                         "sum_us": 1e6 * times["sum"], "ratio_product_shexp": times["product"] / times["shexp"]})
    return rows


# ----------------------------------------------------------------------------- closed forms
#: Angular radii (degrees) of the band-limit and log-table tables.
TABLE_ALPHAS = (5, 10, 20, 30, 45, 60, 75, 90)


def band_limit_rows(orders=(3, 4, 5, 6)):
    """The band limit's error on one sphere wholly above the horizon, per order and angular
    radius: the SH AO (``"product"``, exact for one sphere) minus the closed form
    1 - cos(theta) sin(alpha)^2, on axis (theta = 0) and its largest magnitude over
    theta in [0, pi/2 - alpha] (181 angles). Deterministic."""
    rows = []
    p, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    for order in orders:
        for a_deg in TABLE_ALPHAS:
            alpha = np.radians(a_deg)
            thetas = np.linspace(0.0, np.pi / 2 - alpha, 181)
            err = []
            for theta in thetas:
                c = np.array([[np.sin(theta), 0.0, np.cos(theta)]]) * 2.0
                v = sphere_set_ao(p, n, c, [2.0 * np.sin(alpha)], order=order, method="product", clip=False)[0]
                err.append(v - (1.0 - np.cos(theta) * np.sin(alpha) ** 2))
            err = np.array(err)
            rows.append({"order": order, "alpha_deg": a_deg, "error_on_axis": float(err[0]),
                         "max_abs_error": float(np.max(np.abs(err))),
                         "theta_of_max_deg": float(np.degrees(thetas[np.argmax(np.abs(err))]))})
    return rows


def log_table_rows(orders=(3, 4, 5, 6)):
    """The log table's quality per order and angular radius: the round trip
    ``||exp*(log*(g)) - g||`` (L2 over the sphere, exact exp*) and the optimal-linear
    exponential's ``||OL(log*(g)) - g||``, with g the visibility vector of one sphere, and
    whether the eigenvalue floor of :func:`~vobscure.objectspace.sh.sh_log` was active."""
    from ..objectspace import sh

    rows = []
    for order in orders:
        idx = np.arange(order) * (np.arange(order) + 1)
        for a_deg in TABLE_ALPHAS:
            alpha = np.radians(a_deg)
            g = np.zeros(order * order)
            g[idx] = -sh.cap_zonal(alpha, order)
            g[0] += np.sqrt(4 * np.pi)
            lam = np.linalg.eigvalsh(sh.product_matrix(g))
            f = sh.sh_log(g)
            rows.append({"order": order, "alpha_deg": a_deg,
                         "clamped": bool(lam[0] < sh.LOG_EPSILON * lam[-1]),
                         "round_trip": float(np.linalg.norm(sh.sh_exp(f, method="exact") - g)),
                         "ol": float(np.linalg.norm(sh.sh_exp(f, method="ol") - g)),
                         "hybrid": float(np.linalg.norm(sh.sh_exp(f, method="hybrid") - g))})
    return rows


def _print(title, rows):
    print(f"\n## {title}")
    if not rows:
        return
    cols = list(rows[0])
    print(" | ".join(cols))
    for r in rows:
        print(" | ".join(f"{r[c]:.4g}" if isinstance(r[c], float) else str(r[c]) for c in cols))


def main(argv=None) -> int:
    """Print every table: ``python -m vobscure.experiments.spheres [--quick] [--seed N]``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    quick = "--quick" in argv
    seed = int(argv[argv.index("--seed") + 1]) if "--seed" in argv else 0
    by_count, by_depth = union_rows(quick, seed=seed)
    _print("against the exact union, per sphere count", by_count)
    _print("against the exact union, per occlusion depth", by_depth)
    _print("band limit, one sphere above the horizon", band_limit_rows())
    _print("log table", log_table_rows())
    _print("hybrid threshold", hybrid_rows(quick, seed=seed))
    _print("proxies against the mesh (Embree AO)", proxy_rows(quick, seed=seed))
    _print("time per point", timing_rows(quick, seed=seed))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
