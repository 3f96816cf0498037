"""Bunnell's disk AO measured against the ray-cast ground truth, per pass and per term.

For each scene (the blob, the Stanford bunny from ``../shared/data/meshes/`` when present, the
Cornell box with its walls subdivided), per vertex and per pixel of the scene's suggested
view, every shadow term of :func:`vobscure.objectspace.disk_shadow` and passes 1, 2, 3 and the
means of passes 1-2 and 2-3 are compared with :func:`vobscure.ambient_occlusion` without a
distance limit (the disks see the whole scene), cosine-weighted and uniformly weighted:
RMSE, bias (disks minus rays) and correlation, beside the reference's mean standard error
(the noise floor of the RMSE).

The vertices compared are a seeded random subset of the disks (``vertices``); the disks are
evaluated at them through ``points``/``normals``, which is the per-vertex result exactly (a
disk does not shadow itself). The tree (``hierarchy=True``, the default) is used throughout.

:func:`objectspace_rows` returns the rows; ``python -m vobscure.experiments.objectspace
[--quick]`` prints them as a table.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..render import render_gbuffer
from ..groundtruth import ambient_occlusion, ground_truth
from ..objectspace import TERMS, bunnell, bunnell_gbuffer, vertex_disks
from ..scenes import get as get_scene
from ..scenes import load

__all__ = ["SCENES", "VARIANTS", "BUNNY", "scene_for", "objectspace_rows", "tree_rows", "contact_rows", "main"]

#: Scenes measured: name -> ``max_edge`` given to the disks (the Cornell box's walls are
#: 8-vertex boxes, subdivided; the blob and the bunny are fine meshes already).
SCENES = {"blob": None, "bunny": None, "cornell_box": "auto"}
#: The Stanford bunny, outside the project (skipped when absent).
BUNNY = Path(__file__).resolve().parents[3] / "shared/data/meshes/stanford-bunny.obj"
#: (label, passes, average): the passes and the means of two consecutive passes.
VARIANTS = (("1", 1, False), ("2", 2, False), ("3", 3, False), ("avg 1-2", 2, True), ("avg 2-3", 3, True))
#: Reference weightings: the cosine-weighted AO (RTR Eq. 9.14) and the uniformly weighted one.
WEIGHTINGS = ("cosine", "uniform")
#: Vertices compared per scene, image size, rays per receiver; full and quick.
VERTICES = {False: 3000, True: 400}
SIZE = {False: (96, 96), True: (32, 32)}
RAYS = {False: 256, True: 64}


def scene_for(name: str):
    """The scene ``name`` ("bunny": the Stanford bunny file; else a built-in), or None when
    the bunny's file is absent."""
    if name == "bunny":
        return load(BUNNY) if BUNNY.exists() else None
    return get_scene(name)


def _stats(est, ref, stderr) -> dict:
    err = np.asarray(est, dtype=np.float64) - ref
    corr = float(np.corrcoef(est, ref)[0, 1]) if np.std(est) > 0 and np.std(ref) > 0 else float("nan")
    return {"rmse": float(np.sqrt(np.mean(err ** 2))), "bias": float(err.mean()), "corr": corr,
            "ref_stderr": float(np.mean(stderr))}


def _disks_of(scenes):
    """(name, scene, max_edge, disk centres, disk normals) of each scene whose data is
    present (the bunny may be absent), with the subdivision :data:`SCENES` gives it."""
    for name in scenes:
        scene = scene_for(name)
        if scene is None:
            continue
        max_edge = SCENES.get(name)
        p, n, _ = vertex_disks(scene, max_edge=max_edge)
        yield name, scene, max_edge, p, n


def objectspace_rows(scenes=tuple(SCENES), *, terms=TERMS, quick: bool = False, seed: int = 0) -> list[dict]:
    """One row per (scene, where, term, variant, weighting): RMSE, bias and correlation of
    Bunnell's disks against ray-cast AO without a distance limit, and the reference's mean
    standard error. ``where`` is "vertex" (a random subset of the disks) or "pixel" (the
    scene's suggested view). Scenes whose data is absent (the bunny) are left out."""
    rows = []
    for name, scene, max_edge, p, n in _disks_of(scenes):
        disks = len(p)
        pick = np.sort(np.random.default_rng(seed).choice(len(p), size=min(VERTICES[quick], len(p)),
                                                          replace=False))
        p, n = p[pick], n[pick]
        gb = render_gbuffer(scene, scene.camera(SIZE[quick]))
        refs = {}
        for w in WEIGHTINGS:
            e = ambient_occlusion(scene, p, n, rays=RAYS[quick], weighting=w, max_distance=np.inf, seed=seed)
            refs["vertex", w] = (e.value, e.stderr)
            g = ground_truth(scene, gb, quantity="ao", rays=RAYS[quick], weighting=w, seed=seed)
            refs["pixel", w] = (g.value[gb.valid], g.stderr[gb.valid])
        for term in terms:
            for label, passes, average in VARIANTS:
                opts = dict(passes=passes, term=term, average=average, max_edge=max_edge)
                est = {"vertex": bunnell(scene, p, n, **opts),
                       "pixel": bunnell_gbuffer(gb, scene=scene, **opts)[gb.valid]}
                for where in ("vertex", "pixel"):
                    for w in WEIGHTINGS:
                        ref, err = refs[where, w]
                        rows.append({"scene": name, "where": where, "disks": disks, "receivers": len(ref),
                                     "term": term, "passes": label, "weighting": w,
                                     **_stats(est[where], ref, err)})
    return rows


def tree_rows(scenes=tuple(SCENES), *, terms=TERMS, receivers: int = 1000, passes=(1, 2), seed: int = 0,
              open_ratio: float = 4.0) -> list[dict]:
    """The tree against the exact sum: per (scene, term, pass), the largest and the RMS
    difference of the visibility at ``receivers`` random disks, and the shadow evaluations
    of one pass as a fraction of the exact sum's."""
    from ..objectspace import shadow_evaluations

    rows = []
    for name, scene, max_edge, p, n in _disks_of(scenes):
        pick = np.random.default_rng(seed).choice(len(p), size=min(receivers, len(p)), replace=False)
        fraction = shadow_evaluations(scene, p[pick], n[pick], max_edge=max_edge, open_ratio=open_ratio) / (
            len(pick) * len(p))
        for term in terms:
            for P in passes:
                opts = dict(passes=P, term=term, max_edge=max_edge)
                tree = bunnell(scene, p[pick], n[pick], open_ratio=open_ratio, **opts)
                exact = bunnell(scene, p[pick], n[pick], hierarchy=False, **opts)
                d = tree - exact
                rows.append({"scene": name, "disks": len(p), "receivers": len(pick), "term": term, "passes": P,
                             "max_abs": float(np.abs(d).max()), "rmse": float(np.sqrt(np.mean(d ** 2))),
                             "mean_diff": float(d.mean()), "evaluations": fraction})
    return rows


def contact_rows(*, terms=TERMS, rays: int = 64, seed: int = 0) -> list[dict]:
    """Where surfaces touch: the Cornell box's disks (``max_edge="auto"``) in the plane where
    the right wall stands on the floor (the floor's top-face disks under the wall, the
    wall's bottom-face disks on the floor), pass 1 of every term against uniform AO."""
    scene = get_scene("cornell_box")
    p, n, _ = vertex_disks(scene, max_edge="auto")
    under = (np.abs(p[:, 1]) < 1e-9) & (p[:, 0] > 1.01) & (p[:, 0] < 1.09) & (np.abs(p[:, 2]) < 0.9)
    rows = []
    for where, facing in (("floor under the wall", n[:, 1] > 0.99), ("wall's bottom face", n[:, 1] < -0.99)):
        pick = np.flatnonzero(under & facing)
        ref = ambient_occlusion(scene, p[pick], n[pick], rays=rays, weighting="uniform", max_distance=np.inf,
                                seed=seed)
        row = {"disks": where, "count": len(pick), "ray-cast": float(ref.value.mean())}
        for term in terms:
            row[term] = float(bunnell(scene, p[pick], n[pick], passes=1, term=term, max_edge="auto").mean())
        rows.append(row)
    return rows


def main(argv=None) -> int:
    """``python -m vobscure.experiments.objectspace [--quick]``: the table."""
    import argparse

    from .common import markdown_table

    parser = argparse.ArgumentParser(prog="python -m vobscure.experiments.objectspace",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="few receivers and rays (under a minute)")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated: " + ", ".join(SCENES))
    parser.add_argument("--terms", default=",".join(TERMS), help="comma-separated: " + ", ".join(TERMS))
    parser.add_argument("--tree", action="store_true",
                        help="instead: the tree against the exact sum at 1000 random disks (passes 1, 2)")
    parser.add_argument("--contact", action="store_true",
                        help="instead: the Cornell box's disks where a wall stands on the floor")
    args = parser.parse_args(argv)
    if args.contact:
        print(markdown_table(contact_rows(terms=[t.strip() for t in args.terms.split(",")]), digits=3))
        return 0
    if args.tree:
        print(markdown_table(tree_rows([s.strip() for s in args.scenes.split(",")],
                                       terms=[t.strip() for t in args.terms.split(",")]),
                             ["scene", "disks", "receivers", "term", "passes", "max_abs", "rmse", "mean_diff",
                              "evaluations"], digits=3))
        return 0
    rows = objectspace_rows([s.strip() for s in args.scenes.split(",")],
                            terms=[t.strip() for t in args.terms.split(",")], quick=args.quick)
    if not BUNNY.exists() and "bunny" in args.scenes:
        print(f"(bunny left out: {BUNNY} is absent)")
    # one line per (scene, where, term, passes): both weightings side by side
    merged = {}
    for r in rows:
        key = (r["scene"], r["where"], r["term"], r["passes"])
        m = merged.setdefault(key, {"scene": r["scene"], "where": r["where"], "disks": r["disks"],
                                    "receivers": r["receivers"], "term": r["term"], "passes": r["passes"]})
        tag = "cos" if r["weighting"] == "cosine" else "uni"
        for stat in ("rmse", "bias", "corr", "ref_stderr"):
            m[f"{stat}_{tag}"] = r[stat]
    print(markdown_table(list(merged.values()),
                         ["scene", "where", "disks", "receivers", "term", "passes", "rmse_cos", "bias_cos",
                          "corr_cos", "rmse_uni", "bias_uni", "corr_uni", "ref_stderr_cos", "ref_stderr_uni"],
                         digits=3))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
