"""The Cornell box shaded with each ambient term of RTR 3rd ed. Sec. 9.2, and the
interreflection corrections against the ray-traced multi-bounce reference.

One PNG, ``cornell_shading.png``, and the numbers of its lower row, ``cornell_shading.csv``
(the rows of :func:`vobscure.experiments.shading.interreflection_rows`).

Upper row, shaded in colour (display colours resembling the Cornell box's red, green and
white walls, ambient light L_A = 1): the ambient light without occlusion, ``c_amb L_A``; with
the ray-traced k_A (Eq. 9.17, :func:`vobscure.shading.ambient`); with Stewart and Langer's
k'_A (Eq. 9.23) and Jimenez et al.'s multi-bounce fit, each with the wall's own colour as the
albedo; and the bent-normal lookup of a sky brighter at the zenith
(:func:`vobscure.shading.bent_normal_lookup`, :class:`~vobscure.shading.LinearSky`).

Lower row, grey surfaces of albedo 0.6: the ray-traced visibility with interreflections
(the reference, ``ambient_occlusion(..., bounces, albedo)``), the error of each correction
applied to the ray-traced k_A, and the RMSE of each correction per albedo.

Regenerate with ``vobscure figures cornell_shading --out docs/img`` (about a minute; ``--quick`` in seconds).

References
----------
Akenine-Moller, Haines & Hoffman, Real-Time Rendering 3rd ed., Sec. 9.2.1, Eqs. 9.17,
9.22-9.23; Stewart & Langer 1997; Jimenez, Wu, Pesce & Jarabo 2016.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "WALL_COLOURS", "SHOWN_ALBEDO"]

ORDER = 160
FIGSIZE = (17.0, 7.2)

#: Display colours (albedos) of the upper row: red left wall, green right wall, white rest.
#: Chosen to look like the Cornell box, not measured reflectances.
WALL_COLOURS = {"left_wall": (0.63, 0.07, 0.05), "right_wall": (0.14, 0.45, 0.09)}
WHITE = (0.73, 0.71, 0.68)
#: The grey albedo of the lower row's images.
SHOWN_ALBEDO = 0.6


#: The corrections whose error the bottom row shows, and their titles.
_ERRORS = {"none": "k_A (black occluders)", "stewart_langer": "Stewart-Langer", "jimenez": "Jimenez fit"}


def _colours(scene, gbuffer) -> np.ndarray:
    """(H, W, 3) albedo per pixel from the mesh each pixel sees (NaN on background)."""
    names = list(scene.meshes)
    out = np.full(gbuffer.valid.shape + (3,), np.nan)
    mesh = scene.mesh_index[gbuffer.primitive[gbuffer.valid]]
    palette = np.array([WALL_COLOURS.get(name, WHITE) for name in names])
    out[gbuffer.valid] = palette[mesh]
    return out


def measure(profile) -> Rows:
    """The rows of :func:`vobscure.experiments.shading.interreflection_rows` on the Cornell
    box (exact floats in the CSV) and the images of both rows of panels (quick: small images
    and few rays). Seed of the ray-traced references: ``profile.seed``."""
    from ...groundtruth import ambient_occlusion
    from ...scenes import get as get_scene
    from ...shading import LinearSky, ambient, bent_normal_lookup, multibounce_jimenez, stewart_langer
    from .. import shading as X

    quick, seed = profile.quick, profile.seed
    measured = X.measure("cornell_box", quick=quick, seed=seed)
    rows = X.interreflection_rows(measured)
    scene = get_scene("cornell_box")
    gb = measured.gbuffer
    valid = gb.valid
    colour = _colours(scene, gb)
    k_A = measured.k_A[..., None]

    # bent normals of the same pixels (black occluders), for the sky lookup
    hits = gb.hits
    bent = ambient_occlusion(scene, hits["world_position"], hits["world_normal"], rays=X.RAYS[quick],
                             seed=seed, bent_normals=True).bent_normal
    sky = LinearSky(0.6, 0.4, up=(0.0, 1.0, 0.0))
    lookup = np.full(valid.shape + (3,), np.nan)
    lookup[valid] = bent_normal_lookup(measured.k_A[valid][:, None], colour[valid], bent[:, None, :],
                                       environment=sky)
    k = np.where(valid[..., None], k_A, 0.0)
    c = np.nan_to_num(colour)
    shaded = {
        "no occlusion: c_amb L_A": c,
        "k_A c_amb (Eq. 9.17)": ambient(k, c),
        "Stewart-Langer k'_A (Eq. 9.23)": ambient(stewart_langer(k, c), c),
        "Jimenez et al. 2016 fit": ambient(multibounce_jimenez(k, c), c),
        "bent-normal sky lookup": lookup,
    }
    a = SHOWN_ALBEDO
    ref = measured.reference[a]
    arrays = {"valid": valid, "reference": ref, **{f"shaded|{t}": img for t, img in shaded.items()}}
    for name in _ERRORS:
        err = np.full(valid.shape, np.nan)
        err[valid] = np.asarray(X.CORRECTIONS[name](measured.k_A[valid], a)) - ref[valid]
        arrays[f"error|{name}"] = err
    meta = {"shaded": list(shaded), "bounces": measured.bounces, "rays": measured.rays,
            "corrections": list(X.CORRECTIONS)}
    return Rows(rows, arrays=arrays, meta=meta, digits=None)


def plot(rows, fig) -> None:
    """Top: the ambient terms; bottom: the corrections' errors against path tracing."""
    arrays, meta = rows.arrays, rows.meta
    valid = arrays["valid"].astype(bool)
    shaded = {t: arrays[f"shaded|{t}"] for t in meta["shaded"]}
    axes = fig.subplots(2, 5)
    for ax, (title, img) in zip(axes[0], shaded.items()):
        img = np.where(valid[..., None], img, 1.0)
        ax.imshow(np.clip(img, 0.0, 1.0) ** (1 / 2.2), interpolation="nearest")   # display gamma
        ax.set_title(title, fontsize=9)
        ax.set_axis_off()

    a = SHOWN_ALBEDO
    ref = arrays["reference"]
    im = axes[1, 0].imshow(ref, vmin=0.0, vmax=1.0, cmap="gray", interpolation="nearest")
    axes[1, 0].set_title(f"ray-traced k'_A, albedo {a}, {meta['bounces']} bounces", fontsize=9)
    fig.colorbar(im, ax=axes[1, 0], fraction=0.046)
    for ax, (name, label) in zip(axes[1, 1:4], _ERRORS.items()):
        im = ax.imshow(arrays[f"error|{name}"], vmin=-0.3, vmax=0.3, cmap="RdBu_r", interpolation="nearest")
        row = next(r for r in rows if r["albedo"] == a and r["correction"] == name)
        ax.set_title(f"{label} - reference\nRMSE {row['rmse']:.3f}, bias {row['bias']:+.3f}", fontsize=9)
        ax.set_axis_off()
        fig.colorbar(im, ax=ax, fraction=0.046)
    axes[1, 0].set_axis_off()

    ax = axes[1, 4]
    albedos = sorted({r["albedo"] for r in rows})
    width = 0.25
    for i, name in enumerate(meta["corrections"]):
        rmse = [next(r["rmse"] for r in rows if r["albedo"] == al and r["correction"] == name) for al in albedos]
        ax.bar(np.arange(len(albedos)) + (i - 1) * width, rmse, width, label=name)
    noise = [next(r["ref_stderr"] for r in rows if r["albedo"] == al) for al in albedos]
    ax.plot(np.arange(len(albedos)), noise, "k_", markersize=18, label="reference stderr")
    ax.set_xticks(np.arange(len(albedos)), [str(al) for al in albedos])
    ax.set_xlabel("albedo")
    ax.set_ylabel("RMSE against the reference")
    ax.legend(fontsize=7)
    ax.set_title("per albedo", fontsize=9)
    fig.suptitle(f"Cornell box: ambient terms of RTR 9.2 (top) and interreflection corrections against "
                 f"path tracing (bottom), {valid.shape[1]}x{valid.shape[0]} px, {meta['rays']} rays",
                 fontsize=10)


make = deprecated_make(__name__)
