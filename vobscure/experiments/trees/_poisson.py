"""The canopy model exact in expectation: the Poisson leaf cloud's visibility, predicted from
the leaf statistics, beside Eq. 6 with the fitted density, on leaf points and per pixel,
and the ellipsoid's affine map against the true ellipsoid."""

from __future__ import annotations

import numpy as np

from ._canopy import _canopy
from ._common import CANOPY_SCENES, REFERENCES, _measurements, _scene, _scores, _sub, _truth, kept, setting

#: Columns of :func:`poisson_rows`.
POISSON_COLUMNS = ("scene", "kind", "points_on", "model", "shell", "parameter", "reference", "rmse", "bias",
                   "corr", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")

#: The uniform leaf clouds that stand beside the clustered trees: name -> the tree.
UNIFORM_TWINS = {"tree_uniform": "tree", "tree_poplar_uniform": "tree_poplar"}

#: Every scene of :func:`poisson_rows`.
POISSON_SCENES = CANOPY_SCENES + tuple(UNIFORM_TWINS)

#: The shells of :func:`poisson_rows`.
POISSON_SHELLS = ("sphere", "ellipsoid")

#: Per-pixel sizes of :func:`poisson_rows` (full, quick): image size and rays per pixel.
POISSON_PIXELS = {False: {"size": (96, 96), "rays": 256}, True: {"size": (24, 24), "rays": 32}}

#: Columns of :func:`ellipsoid_map_rows`.
ELLIPSOID_MAP_COLUMNS = ("scene", "reference", "radii", "sigma", "rmse_map", "max_map", "bias_map",
                         "rmse_truth_map", "rmse_truth_exact", "truth_stderr", "points", "nodes")

#: Leaf points and quadrature nodes of :func:`ellipsoid_map_rows` (full, quick).
ELLIPSOID_MAP = {False: {"points": 256, "nodes": 64}, True: {"points": 12, "nodes": 24}}


@kept
def _uniform_twin(run, name: str):
    """A uniform leaf cloud with the tree's leaf count and leaf size in the tree's bounding
    sphere (the sphere rows) or, as ``(sphere twin, ellipsoid twin)``, in its crown ellipsoid
    (``canopy_radii``, axis-aligned, the ellipsoid rows)."""
    from ... import scenes
    from ... import trees as T

    seed = run.seed
    tree = _scene(run, UNIFORM_TWINS[name])
    md = tree.metadata
    n, size = int(md["n_leaves"]), float(md["parameters"]["leaf_size"])
    R = float(T.bounding_sphere(np.asarray(md["canopy_points"], dtype=np.float64)).radius)
    sphere = scenes.leaf_cloud(n, radii=R, leaf_size=size, seed=seed + 100, name=name)
    ellipsoid = scenes.leaf_cloud(n, shape="ellipsoid", radii=tuple(md["canopy_radii"]), leaf_size=size,
                                  seed=seed + 200, name=f"{name} (ellipsoid)")
    return sphere, ellipsoid

@kept
def _poisson_leaves(run, name: str, shell_label: str) -> dict:
    """Leaf points, their truth and both models for one scene and shell (scored half)."""
    from ... import trees as T
    from ...scenes import leaf_points

    seed = run.seed
    s = setting(run.quick)
    if name in CANOPY_SCENES:
        d = _canopy(run, name)
        scene, points, normals, fit, score, truth = (d["scene"], d["points"], d["normals"], d["fit"], d["score"],
                                                     d["truth"])
        shell = d["shells"][shell_label][0]
        fitted = {c["reference"]: (c["parameter"], c["values"]) for c in d["configs"]
                  if c["model"] == "hegeman" and c["shell"] == shell_label and c["source"] == "fitted"}
    else:
        scene = _uniform_twin(run, name)[0 if shell_label == "sphere" else 1]
        points, normals = leaf_points(scene, s["points"], seed=seed)
        fit, score = np.arange(0, len(points), 2), np.arange(1, len(points), 2)
        truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 1 + i)
                 for i, w in enumerate(REFERENCES)}
        cp = np.asarray(scene.metadata["canopy_points"], dtype=np.float64)
        shell = T.bounding_sphere(cp) if shell_label == "sphere" else T.bounding_ellipsoid(cp)
        fitted = {}
        for w in REFERENCES:
            rho = float(T.fit_density(points[fit], normals[fit], shell, truth[w].value[fit]))
            fitted[w] = (rho, T.canopy_visibility(points[score], normals[score], shell, density=rho))
    md = scene.metadata
    sigma = T.extinction(md["n_leaves"], md["leaf_area"], shell)
    poisson = {w: T.poisson_visibility(points[score], normals[score], shell, extinction=sigma, weighting=w)
               for w in REFERENCES}
    return {"scene": scene, "shell": shell, "sigma": sigma, "fitted": fitted, "poisson": poisson,
            "points": points[score], "normals": normals[score],
            "truth": {w: _sub(truth[w], score) for w in REFERENCES}, "truth_rays": s["truth_rays"]}

@kept
def _poisson_pixels(run, name: str, shell_label: str) -> dict:
    """Per-pixel truth (both weightings) and both models on one scene's view."""
    from ... import trees as T
    from ...camera import Camera
    from ...render import render_gbuffer

    seed = run.seed
    px = POISSON_PIXELS[run.quick]
    leaves = _poisson_leaves(run, name, shell_label)
    scene, shell, sigma = leaves["scene"], leaves["shell"], leaves["sigma"]
    v = scene.view
    kw = {"fov_y": v["fov_y"]} if "fov_y" in v else {"ortho_height": v["ortho_height"]}
    cam = Camera.look_at(v["eye"], v["target"], up=v.get("up", (0, 1, 0)), size=tuple(px["size"]), **kw)
    gb = render_gbuffer(scene, cam)
    valid = np.asarray(gb.valid)
    H, W = valid.shape
    pos = np.asarray(gb.world_position, dtype=np.float64)[valid]
    nrm = np.asarray(gb.world_normal, dtype=np.float64)[valid]
    names = list(scene.meshes)
    mesh = np.asarray(scene.mesh_index)[np.asarray(gb.primitive)[valid]]
    foliage = mesh == names.index(scene.metadata["foliage_mesh"])
    ground = (mesh == names.index("ground")) if "ground" in names else np.zeros(len(pos), bool)
    use = foliage | ground
    idx = np.flatnonzero(valid.ravel())[use]
    pos, nrm, foliage, ground = pos[use], nrm[use], foliage[use], ground[use]

    def image(values):
        out = np.full(H * W, np.nan)
        out[idx] = values
        return out.reshape(H, W)

    truth, hegeman, poisson = {}, {}, {}
    sphere = T.bounding_sphere(np.asarray(scene.metadata["canopy_points"], dtype=np.float64))
    for i, w in enumerate(REFERENCES):
        truth[w] = _truth(scene, pos, nrm, w, px["rays"], seed + 31 + i)
        rho = leaves["fitted"][w][0]
        h = np.empty(len(pos))
        h[foliage] = T.canopy_visibility(pos[foliage], nrm[foliage], shell, density=rho)      # Eqs. 4-6
        if ground.any():                                                                     # Eqs. 7-8
            h[ground] = T.occluder_visibility(pos[ground], nrm[ground], sphere, model="hegeman")
        hegeman[w] = h
        poisson[w] = T.poisson_visibility(pos, nrm, shell, extinction=sigma, weighting=w)
    return {"foliage": foliage, "ground": ground, "truth": truth, "hegeman": hegeman, "poisson": poisson,
            "image": image, "rays": px["rays"], "size": (H, W)}

def poisson_rows(quick: bool = False, *, seed: int = 0, scenes=POISSON_SCENES, measurements=None) -> list[dict]:
    """The Poisson leaf cloud's expected visibility, predicted, beside Eq. 6 with the fitted
    density, against the ray-cast sky visibility.

    One row per (scene, points_on, model, shell, reference); columns
    :data:`POISSON_COLUMNS`. ``points_on``: ``"leaves"`` (the scored half of the leaf points
    of :func:`canopy_rows`; for the uniform twins their own leaf points), ``"foliage pixels"``
    and ``"ground pixels"`` (trees only; Hegeman's model there is Eqs. 7-8 of the bounding
    sphere) of the scene's view at :data:`POISSON_PIXELS`. ``model``: ``"hegeman fitted"``
    (``parameter`` = alpha rho fitted on the fit half of the leaf points to that reference)
    or ``"poisson predicted"`` (``parameter`` = sigma = n A / 2 from the leaf statistics,
    nothing fitted). ``truth_stderr`` is the reference's RMS standard error (its noise floor).
    The scenes ``tree_uniform`` and ``tree_poplar_uniform`` (:data:`UNIFORM_TWINS`) are
    uniform leaf clouds with each tree's leaf count and leaf size, in its bounding sphere (the
    sphere rows) or its crown ellipsoid (the ellipsoid rows): the Poisson model's error there
    is its own, the difference on the tree is the clustering's. ``measurements``: the run's
    :class:`Measurements` to share, default a new one.
    """
    run = _measurements(quick, seed, measurements)
    rows = []
    for name in scenes:
        for label in POISSON_SHELLS:
            lv = _poisson_leaves(run, name, label)
            kind = lv["scene"].metadata.get("kind", "")
            pix = _poisson_pixels(run, name, label)
            for w in REFERENCES:
                rho, hv = lv["fitted"][w]
                groups = [("leaves", hv, lv["poisson"][w], lv["truth"][w], lv["truth_rays"])]
                for where, mask in (("foliage pixels", pix["foliage"]), ("ground pixels", pix["ground"])):
                    if mask.any():
                        idx = np.flatnonzero(mask)
                        groups.append((where, pix["hegeman"][w][idx], pix["poisson"][w][idx],
                                       _sub(pix["truth"][w], idx), pix["rays"]))
                for where, h, p, truth, rays in groups:
                    for model, values, param in (("hegeman fitted", h, rho), ("poisson predicted", p, lv["sigma"])):
                        sc = _scores(values, truth)
                        del sc["mae"]
                        rows.append({"scene": name, "kind": kind, "points_on": where, "model": model,
                                     "shell": label, "parameter": float(param), "reference": w, **sc,
                                     "truth_rays": int(rays)})
    return rows

def ellipsoid_map_rows(quick: bool = False, *, seed: int = 0,
                       scenes=("tree", "tree_poplar", "tree_uniform", "tree_poplar_uniform"),
                       measurements=None) -> list[dict]:
    """The affine map of an ellipsoid (Hegeman 2006, Sec. 3), as :func:`vobscure.trees.poisson_visibility`
    uses it, against the Poisson leaf cloud's expected visibility in the true ellipsoid
    (:func:`vobscure.trees.poisson_quadrature`, brute-force quadrature over the hemisphere).

    On the first ``points`` scored leaf points of :func:`poisson_rows` (ellipsoid shell):
    ``rmse_map``, ``max_map`` and ``bias_map`` of the mapped model against the true
    ellipsoid's; ``rmse_truth_map`` and ``rmse_truth_exact`` of each against the ray-cast sky
    visibility (how much of the model's error the map is). Columns
    :data:`ELLIPSOID_MAP_COLUMNS`; ``measurements`` as in :func:`poisson_rows`.
    """
    from ... import trees as T

    run = _measurements(quick, seed, measurements)
    cfg = ELLIPSOID_MAP[bool(quick)]
    rows = []
    for name in scenes:
        lv = _poisson_leaves(run, name, "ellipsoid")
        if name in CANOPY_SCENES:
            d = _canopy(run, name)
            P, N = d["points"][d["score"]], d["normals"][d["score"]]
        else:
            P, N = lv["points"], lv["normals"]
        k = min(cfg["points"], len(P))
        P, N = P[:k], N[:k]
        shell, sigma = lv["shell"], lv["sigma"]
        for w in REFERENCES:
            mapped = lv["poisson"][w][:k]
            exact = T.poisson_quadrature(P, N, shell, extinction=sigma, weighting=w, nodes=cfg["nodes"])
            t = np.asarray(lv["truth"][w].value)[:k]
            diff = mapped - exact
            rows.append({"scene": name, "reference": w, "radii": "x".join(f"{r:.3g}" for r in shell.radii),
                         "sigma": float(sigma), "rmse_map": float(np.sqrt(np.mean(diff ** 2))),
                         "max_map": float(np.max(np.abs(diff))), "bias_map": float(np.mean(diff)),
                         "rmse_truth_map": float(np.sqrt(np.mean((mapped - t) ** 2))),
                         "rmse_truth_exact": float(np.sqrt(np.mean((exact - t) ** 2))),
                         "truth_stderr": float(np.sqrt(np.mean(np.asarray(lv["truth"][w].stderr)[:k] ** 2))),
                         "points": int(k), "nodes": cfg["nodes"]})
    return rows

def poisson_images(name: str, *, shell: str = "sphere", reference: str = "cosine", quick: bool = False,
                   seed: int = 0, measurements=None) -> dict:
    """The per-pixel images behind :func:`poisson_rows` (the figure ``canopy_models``):
    ``truth``, ``stderr``, ``hegeman`` (Eq. 6 fitted; Eqs. 7-8 on the ground), ``poisson``
    (predicted), each (H, W) with NaN where no foliage or ground is seen, and the parameters
    ``density`` and ``sigma``; ``measurements`` as in :func:`poisson_rows`."""
    run = _measurements(quick, seed, measurements)
    lv = _poisson_leaves(run, str(name), shell)
    pix = _poisson_pixels(run, str(name), shell)
    img = pix["image"]
    t = pix["truth"][reference]
    return {"truth": img(np.asarray(t.value)), "stderr": img(np.asarray(t.stderr)),
            "hegeman": img(pix["hegeman"][reference]), "poisson": img(pix["poisson"][reference]),
            "density": float(lv["fitted"][reference][0]), "sigma": float(lv["sigma"]), "rays": pix["rays"]}
