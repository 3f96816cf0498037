"""Points on the ground around the trees (Fig. 9, the occluder models of Eqs. 7-8) and on
the grass blades (Fig. 10, Eq. 9) against the sky visibility."""

from __future__ import annotations

import numpy as np

from ._common import GRASS_SCENE, REFERENCES, TREE_SCENES, _measurements, _scene, _scores, _sub, _truth, kept, setting

#: Columns of :func:`ground_rows`.
GROUND_COLUMNS = ("scene", "model", "reference", "distance", "distance_r", "sphere_radius", "rmse",
                  "bias", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")

#: Columns of :func:`grass_rows`.
GRASS_COLUMNS = ("scene", "model", "reference", "height_lo", "height_hi", "cos_lo", "cos_hi", "rmse",
                 "bias", "corr", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")


@kept
def _ground(run, name: str) -> dict:
    from ... import trees as T

    seed = run.seed
    s = setting(run.quick)
    scene = _scene(run, name)
    md = scene.metadata
    sphere = T.bounding_sphere(np.asarray(md["canopy_points"], dtype=np.float64))
    R = float(sphere.radius)
    c = np.asarray(md["canopy_center"], dtype=np.float64)
    y = float(md["ground_y"])
    rng = np.random.default_rng(seed)
    m = s["ring_points"]
    dist, pts = [], []
    for f in s["rings"]:
        # a ring may reach past the ground square: an upward hemisphere never sees the
        # ground plane, so a point at ground height sees the same sky with or without it
        rho = f * R
        phi = 2 * np.pi * (np.arange(m) + rng.random()) / m
        ring = np.column_stack([c[0] + rho * np.cos(phi), np.full(m, y), c[2] + rho * np.sin(phi)])
        pts.append(ring)
        dist.append(np.full(m, rho))
    points = np.concatenate(pts)
    distance = np.concatenate(dist)
    normals = np.tile([0.0, 1.0, 0.0], (len(points), 1))
    truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 11 + i)
             for i, w in enumerate(REFERENCES)}
    # the porous sphere's extinction: the Poisson leaf cloud's sigma = n A / 2 (G = 1/2 for
    # leaves of random orientation), the leaves spread over the bounding sphere's volume
    sigma = T.extinction(md["n_leaves"], md["leaf_area"], sphere)
    values = {(mdl, w): T.occluder_visibility(points, normals, [sphere], model=mdl, weighting=w,
                                              **({"sigma": sigma} if mdl == "porous" else {}))
              for mdl in ("hegeman", "exact", "porous") for w in REFERENCES}
    return {"scene": scene, "points": points, "normals": normals, "distance": distance, "radius": R,
            "truth": truth, "values": values, "sphere": sphere, "sigma": sigma,
            "truth_rays": s["truth_rays"]}

def ground_rows(quick: bool = False, *, seed: int = 0, scenes=TREE_SCENES, measurements=None) -> list[dict]:
    """Fig. 9: the occluder models on the ground around a tree against the sky visibility.

    One row per (scene, model, reference, ring distance) and one per (scene, model,
    reference) over all rings (``distance`` empty); columns :data:`GROUND_COLUMNS`.
    ``distance_r`` is the distance from the trunk in bounding-sphere radii. ``measurements``:
    the run's :class:`Measurements` to share, default a new one.
    """
    run = _measurements(quick, seed, measurements)
    rows = []
    for name in scenes:
        d = _ground(run, name)
        for (mdl, w), v in d["values"].items():
            truth = d["truth"][w]
            for rho in [*np.unique(d["distance"]), None]:
                idx = np.arange(len(v)) if rho is None else np.flatnonzero(d["distance"] == rho)
                sc = _scores(v[idx], _sub(truth, idx))
                del sc["corr"], sc["mae"]
                rows.append({"scene": name, "model": mdl, "reference": w,
                             "distance": None if rho is None else float(rho),
                             "distance_r": None if rho is None else float(rho / d["radius"]),
                             "sphere_radius": d["radius"], **sc, "truth_rays": d["truth_rays"]})
    return rows

def ground_data(name: str, quick: bool = False, *, seed: int = 0, measurements=None) -> dict:
    """The ground points behind :func:`ground_rows` (kept in ``measurements``): ``points``,
    ``distance`` (n,), ``radius`` (the bounding sphere's), ``truth`` (reference -> Estimate),
    ``values`` ((model, reference) -> (n,)), ``sigma`` of the porous model. Read only."""
    return _ground(_measurements(quick, seed, measurements), str(name))

@kept
def _grass(run) -> dict:
    from ... import trees as T

    seed = run.seed
    s = setting(run.quick)
    scene = _scene(run, GRASS_SCENE)
    md = scene.metadata
    index = list(scene.meshes).index(md["foliage_mesh"])
    tri = scene.triangles[np.asarray(scene.mesh_index) == index]     # base-, base+, tip per blade
    bases = np.asarray(md["blade_bases"], dtype=np.float64)
    central = np.flatnonzero(np.all(np.abs(bases[:, [0, 2]]) <= 0.25 * md["field_size"], axis=1))
    rng = np.random.default_rng(seed)
    n = s["grass_points"]
    blade = rng.choice(central, size=n)
    t = (np.arange(n) + rng.random(n)) / n          # stratified relative heights P_z / h
    rng.shuffle(t)
    a = rng.uniform(0.1, 0.9, size=n)
    tb = tri[blade]
    points = (1 - t)[:, None] * (a[:, None] * tb[:, 0] + (1 - a)[:, None] * tb[:, 1]) + t[:, None] * tb[:, 2]
    normals = np.asarray(scene.face_normals)[np.asarray(scene.mesh_index) == index][blade].copy()
    normals[normals[:, 1] < 0] *= -1.0                  # the side that looks up
    h = np.asarray(md["blade_heights"], dtype=np.float64)[blade]
    P_z = points[:, 1] - md["ground_y"]
    cos_theta = normals[:, 1]
    truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 21 + i)
             for i, w in enumerate(REFERENCES)}
    model = np.asarray(T.grass_visibility(P_z, h, cos_theta), dtype=np.float64)   # Eq. 9
    return {"scene": scene, "points": points, "normals": normals, "height": P_z / h, "cos": cos_theta,
            "blade_height": h, "truth": truth, "model": model, "truth_rays": s["truth_rays"]}

def grass_rows(quick: bool = False, *, seed: int = 0, measurements=None) -> list[dict]:
    """Fig. 10: Eq. 9 against the sky visibility at points on grass blades.

    Rows per (reference, relative-height bin) over all orientations, per (reference,
    height bin, orientation bin), and one per reference over every point (``height_lo`` 0,
    ``height_hi`` 1, ``cos_lo`` / ``cos_hi`` the observed range); columns
    :data:`GRASS_COLUMNS`. ``cos`` is cos theta of Eq. 9, the normal's vertical component.
    ``measurements``: the run's :class:`Measurements` to share, default a new one.
    """
    s = setting(quick)
    d = _grass(_measurements(quick, seed, measurements))
    hb = np.linspace(0.0, 1.0, s["height_bins"] + 1)
    cos = d["cos"]
    cb = np.quantile(cos, np.linspace(0, 1, s["cos_bins"] + 1))
    cos_all = (float(cos.min()), float(cos.max()))
    rows = []
    for w in REFERENCES:
        def add(idx, hl, hh, cl, ch):
            if len(idx) == 0:
                return
            sc = _scores(d["model"][idx], _sub(d["truth"][w], idx))
            del sc["mae"]
            rows.append({"scene": GRASS_SCENE, "model": "eq9", "reference": w, "height_lo": hl,
                         "height_hi": hh, "cos_lo": cl, "cos_hi": ch, **sc, "truth_rays": d["truth_rays"]})
        add(np.arange(len(cos)), 0.0, 1.0, *cos_all)
        for i in range(len(hb) - 1):
            inh = (d["height"] >= hb[i]) & (d["height"] < hb[i + 1])
            add(np.flatnonzero(inh), float(hb[i]), float(hb[i + 1]), *cos_all)
            for j in range(len(cb) - 1):
                inc = (cos >= cb[j]) & ((cos < cb[j + 1]) if j < len(cb) - 2 else (cos <= cb[j + 1]))
                add(np.flatnonzero(inh & inc), float(hb[i]), float(hb[i + 1]), float(cb[j]), float(cb[j + 1]))
    return rows

def grass_data(quick: bool = False, *, seed: int = 0, measurements=None) -> dict:
    """The blade points behind :func:`grass_rows` (kept in ``measurements``): ``points``,
    ``height`` (P_z / h), ``cos`` (cos theta), ``blade_height``, ``truth`` (reference ->
    Estimate), ``model`` (Eq. 9). Read only."""
    return _grass(_measurements(quick, seed, measurements))
