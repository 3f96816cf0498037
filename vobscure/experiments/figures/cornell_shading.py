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

Regenerate with ``python -c "from vobscure.experiments.figures import cornell_shading as f;
f.make('docs/img')"`` (about a minute; ``quick=True`` in seconds).

References
----------
Akenine-Moller, Haines & Hoffman, Real-Time Rendering 3rd ed., Sec. 9.2.1, Eqs. 9.17,
9.22-9.23; Stewart & Langer 1997; Jimenez, Wu, Pesce & Jarabo 2016.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "WALL_COLOURS", "SHOWN_ALBEDO"]

#: Name of the PNG :func:`make` writes.
FILENAME = "cornell_shading.png"
#: Name of the CSV of the lower row's numbers.
CSV_FILENAME = "cornell_shading.csv"
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"albedo": (0.0, 1.0), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0), "max_abs": (0.0, 1.0),
              "ref_mean": (0.0, 1.0), "k_A_mean": (0.0, 1.0), "ref_stderr": (0.0, 0.5),
              "pixels": (1, 10 ** 7), "bounces": (1, 1000), "rays": (2, 10 ** 6)}
#: Display colours (albedos) of the upper row: red left wall, green right wall, white rest.
#: Chosen to look like the Cornell box, not measured reflectances.
WALL_COLOURS = {"left_wall": (0.63, 0.07, 0.05), "right_wall": (0.14, 0.45, 0.09)}
WHITE = (0.73, 0.71, 0.68)
#: The grey albedo of the lower row's images.
SHOWN_ALBEDO = 0.6


def _colours(scene, gbuffer) -> np.ndarray:
    """(H, W, 3) albedo per pixel from the mesh each pixel sees (NaN on background)."""
    names = list(scene.meshes)
    out = np.full(gbuffer.valid.shape + (3,), np.nan)
    mesh = scene.mesh_index[gbuffer.primitive[gbuffer.valid]]
    palette = np.array([WALL_COLOURS.get(name, WHITE) for name in names])
    out[gbuffer.valid] = palette[mesh]
    return out


def make(out_dir, quick: bool = False, *, seed: int = 0) -> list[Path]:
    """Draw ``cornell_shading.png`` and write ``cornell_shading.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        Small images and few rays (seconds), for CI.
    seed : int, optional
        Seed of the ray-traced references.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import cornell_shading
    >>> cornell_shading.FILENAME
    'cornell_shading.png'
    """
    from ...groundtruth import ambient_occlusion
    from ...scenes import get as get_scene
    from ...shading import LinearSky, ambient, bent_normal_lookup, multibounce_jimenez, stewart_langer
    from .. import shading as X
    from ..common import new_figure, save_figure, write_csv

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
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

    fig = new_figure(17.0, 7.2)
    axes = fig.subplots(2, 5)
    for ax, (title, img) in zip(axes[0], shaded.items()):
        img = np.where(valid[..., None], img, 1.0)
        ax.imshow(np.clip(img, 0.0, 1.0) ** (1 / 2.2), interpolation="nearest")   # display gamma
        ax.set_title(title, fontsize=9)
        ax.set_axis_off()

    a = SHOWN_ALBEDO
    ref = measured.reference[a]
    im = axes[1, 0].imshow(ref, vmin=0.0, vmax=1.0, cmap="gray", interpolation="nearest")
    axes[1, 0].set_title(f"ray-traced k'_A, albedo {a}, {measured.bounces} bounces", fontsize=9)
    fig.colorbar(im, ax=axes[1, 0], fraction=0.046)
    for ax, (name, label) in zip(axes[1, 1:4], (("none", "k_A (black occluders)"),
                                                 ("stewart_langer", "Stewart-Langer"),
                                                 ("jimenez", "Jimenez fit"))):
        err = np.full(valid.shape, np.nan)
        err[valid] = np.asarray(X.CORRECTIONS[name](measured.k_A[valid], a)) - ref[valid]
        im = ax.imshow(err, vmin=-0.3, vmax=0.3, cmap="RdBu_r", interpolation="nearest")
        row = next(r for r in rows if r["albedo"] == a and r["correction"] == name)
        ax.set_title(f"{label} - reference\nRMSE {row['rmse']:.3f}, bias {row['bias']:+.3f}", fontsize=9)
        ax.set_axis_off()
        fig.colorbar(im, ax=ax, fraction=0.046)
    axes[1, 0].set_axis_off()

    ax = axes[1, 4]
    albedos = sorted({r["albedo"] for r in rows})
    width = 0.25
    for i, name in enumerate(X.CORRECTIONS):
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
                 f"path tracing (bottom), {gb.valid.shape[1]}x{gb.valid.shape[0]} px, {measured.rays} rays",
                 fontsize=10)
    png = save_figure(fig, out_dir / FILENAME)
    csv = write_csv(out_dir / CSV_FILENAME, rows)
    return [png, csv]
