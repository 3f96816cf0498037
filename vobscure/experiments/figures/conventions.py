"""The conventions figure: spaces, pixels, a real G-buffer and the visibility of the crease.

One PNG, ``conventions.png`` (and the numbers of panel (d), ``conventions.csv``), that a new user
reads beside ``docs/conventions.md``:

(a) world space (right-handed, y up) and view space (x right, y up, z = depth > 0 in
    front of the camera) in a side view of the camera that renders panel (c);
(b) the image convention: row 0 at the top, pixel ``(i, j)`` centred at
    ``(x, y) = (j + 0.5, i + 0.5)``, ``size = (width, height)``;
(c) a G-buffer of :func:`vobscure.scenes.crease` (linear depth, view-space normals) and
    its ray-cast ambient occlusion, background in a colour of its own;
(d) the ball of Volumetric Obscurance around a floor point of the crease and the closed
    forms of DESIGN.md ("Testing"), checked against the ray-cast ground truth.

Regenerate with ``vobscure figures conventions --out docs/img``.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from . import deprecated_make
from ._common import BACKGROUND, Rows

__all__ = ["measure", "plot", "CAMERA", "RADIUS"]

ORDER = 0
FIGSIZE = (13.0, 13.6)
DPI = 110

#: The camera of panels (a) and (c): in the plane z = 0, looking at the crease's edge from
#: the open side, so that the side view (a) is exact. Its ``right`` is world -z.
CAMERA = {"eye": (7.5, 2.6, 0.0), "target": (1.0, 1.2, 0.0), "up": (0.0, 1.0, 0.0), "fov_y": 50.0}

#: AO radius of panel (c) and ball radius R of panel (d), in the crease's units.
RADIUS = 1.0

_SOLID = "#b8b8b8"          # the crease's solid in the sketches
_OCCUPIED = "#5a5a5a"       # the occupied part of the ball
_OPEN = "#cfe3f7"           # the unoccupied part of the ball
_VIEW = "#d62728"           # view-space axes
_WORLD = "#1f3f99"          # world-space axes


def measure(profile) -> Rows:
    """The crease's G-buffer, its ray-cast AO, and the visibility of floor points at c = a / R.

    Quick profile: 60 x 40 pixels, 16 AO rays per pixel, and at c = 0.25, 0.6, 1 64 AO rays
    and 256 points per ball; full: 120 x 80, 64 rays, c at 7 values in [0.1, 1], 1024 rays and
    4096 points. Seed ``profile.seed`` (+1, +2 for the half-ball and the AO check).

    Returns
    -------
    Rows
        One row per c: ``c``, the ray-cast ``ball``, ``half`` (half-ball) VO and ``ao`` with
        their ``*_stderr``, and the closed forms ``*_exact`` (see Notes); arrays ``depth``,
        ``normal``, ``valid`` and ``ao`` (the panel (c) images).

    Notes
    -----
    Panel (c) renders ``vo.scenes.crease()`` (floor top y = 0, wall face x = 0) with
    :data:`CAMERA` and computes ``vo.ground_truth(scene, gb, quantity="ao",
    radius=RADIUS)``. Panel (d) evaluates, for a floor point at distance a from the wall and
    c = a / R, the closed forms of DESIGN.md: ball VO 1/2 - (1 - c)^2 (2 + c) / 8, half-ball
    VO 1 - (1 - c)^2 (2 + c) / 4 and cosine-weighted AO within R,
    1 - (acos c - c sqrt(1 - c^2)) / pi, against :func:`vobscure.volumetric_obscurance` and
    :func:`vobscure.ambient_occlusion` at a few c.

    Examples
    --------
    The closed forms at c = 1 (a point a radius away from the wall: an open floor) and c = 0:

    >>> {k: float(v) for k, v in _closed_forms(1.0).items()}
    {'ball': 0.5, 'half': 1.0, 'ao': 1.0}
    >>> {k: round(float(v), 6) for k, v in _closed_forms(0.0).items()}
    {'ball': 0.25, 'half': 0.5, 'ao': 0.5}
    """
    from ... import scenes
    from ...camera import Camera
    from ...render import render_gbuffer
    from ...groundtruth import ground_truth

    scene = scenes.crease()
    cam = Camera.look_at(CAMERA["eye"], CAMERA["target"], CAMERA["up"], size=profile.pick((60, 40), (120, 80)),
                         fov_y=CAMERA["fov_y"])
    gb = render_gbuffer(scene, cam)
    ao = ground_truth(scene, gb, quantity="ao", radius=RADIUS, rays=profile.pick(16, 64),
                      seed=profile.seed, progress=False)
    check = _crease_check(scene, profile)
    exact = _closed_forms(check["c"])
    rows = [{"c": float(c), **{f"{k}{suffix}": float(v) for k in ("ball", "half", "ao")
                               for suffix, v in (("", getattr(check[k], "value")[i]),
                                                 ("_stderr", check[k].stderr[i]), ("_exact", exact[k][i]))}}
            for i, c in enumerate(check["c"])]
    meta = {"eye": cam.eye[:2].tolist(), "forward": cam.forward[:2].tolist(), "up": cam.up[:2].tolist(),
            "fov_y": float(cam.fov_y), "floor_normal_view": cam.world_to_view_dir(np.array([0.0, 1.0, 0.0])).tolist(),
            "bounds": np.asarray(scene.bounds, dtype=np.float64).tolist(), "ao_samples": int(ao.samples),
            "quick": profile.quick}
    return Rows(rows, arrays={"depth": gb.depth, "normal": gb.normal, "valid": gb.valid, "ao": ao.value},
                meta=meta)


def plot(rows, fig) -> None:
    """Draw panels (a) to (d) from :func:`measure`'s rows."""
    m, a = rows.meta, rows.arrays
    cam = SimpleNamespace(eye=np.array(m["eye"]), forward=np.array(m["forward"]), up=np.array(m["up"]),
                          fov_y=m["fov_y"], floor_normal_view=np.array(m["floor_normal_view"]))
    bounds = tuple(np.array(b) for b in m["bounds"])
    gb = SimpleNamespace(depth=a["depth"], normal=a["normal"], valid=a["valid"].astype(bool),
                         shape=a["depth"].shape)
    ao = SimpleNamespace(value=a["ao"], samples=m["ao_samples"])
    check = {"c": np.array([r["c"] for r in rows], dtype=np.float64)}
    for k in ("ball", "half", "ao"):
        check[k] = SimpleNamespace(value=np.array([r[k] for r in rows], dtype=np.float64),
                                   stderr=np.array([r[f"{k}_stderr"] for r in rows], dtype=np.float64))
    parts = fig.subfigures(3, 1, height_ratios=[1.15, 0.8, 1.0], hspace=0.02)
    top = parts[0].subplots(1, 2, width_ratios=[1.55, 1.0])
    _panel_spaces(top[0], cam, bounds)
    _panel_pixels(top[1])
    _panel_gbuffer(parts[1], gb, ao)
    bottom = parts[2].subplots(1, 2, width_ratios=[1.0, 1.25])
    _panel_ball(bottom[0], bounds)
    _panel_closed_forms(bottom[1], check, m["quick"])


# ----------------------------------------------------------------------------- data
def _closed_forms(c):
    """Visibility of a crease floor point at c = a / R (DESIGN.md, "Testing")."""
    c = np.asarray(c, dtype=np.float64)
    cap = (1.0 - c) ** 2 * (2.0 + c)
    return {
        "ball": 0.5 - cap / 8.0,
        "half": 1.0 - cap / 4.0,
        "ao": 1.0 - (np.arccos(c) - c * np.sqrt(1.0 - c * c)) / np.pi,
    }


def _crease_check(scene, profile):
    """Ray-cast values at floor points (a, 0, 0), a = c R, for panel (d)."""
    from ...groundtruth import ambient_occlusion, volumetric_obscurance

    # c > 0: a point exactly on the edge (c = 0) lies on the wall too, where a ray origin offset
    # along the floor normal stays in the wall's plane and every ray is reported blocked.
    c = profile.pick(np.array([0.25, 0.6, 1.0]), np.linspace(0.1, 1.0, 7))
    samples = profile.pick(256, 4096)
    seed = profile.seed
    points = np.stack([c * RADIUS, np.zeros_like(c), np.zeros_like(c)], axis=1)
    normals = np.tile([0.0, 1.0, 0.0], (len(c), 1))
    ball = volumetric_obscurance(scene, points, radius=RADIUS, samples=samples, seed=seed)
    half = volumetric_obscurance(scene, points, normals, radius=RADIUS, normal_clamp=True,
                                 samples=samples, seed=seed + 1)
    ao = ambient_occlusion(scene, points, normals, rays=profile.pick(64, 1024), max_distance=RADIUS,
                           seed=seed + 2)
    return {"c": c, "ball": ball, "half": half, "ao": ao}


# ----------------------------------------------------------------------------- drawing helpers
def _arrow(ax, start, vec, color, label=None, label_at=1.12, lw=2.0, fontsize=10, **text_kw):
    start = np.asarray(start, float)
    vec = np.asarray(vec, float)
    ax.annotate("", xy=start + vec, xytext=start,
                arrowprops={"arrowstyle": "-|>", "color": color, "lw": lw, "shrinkA": 0, "shrinkB": 0,
                            "mutation_scale": 14})
    if label:
        pos = start + label_at * vec
        ax.text(pos[0], pos[1], label, color=color, fontsize=fontsize, ha="center", va="center",
                **text_kw)


def _out_of_page(ax, xy, color, label, into=False, offset=(0.0, -0.42), radius=0.13):
    """The symbol of an axis perpendicular to the drawing: a dot (toward the reader) or a cross."""
    from matplotlib.patches import Circle

    x, y = xy
    ax.add_patch(Circle(xy, radius, fill=False, color=color, lw=1.6, zorder=5))
    if into:
        d = radius * 0.7
        ax.plot([x - d, x + d], [y - d, y + d], color=color, lw=1.6, zorder=5)
        ax.plot([x - d, x + d], [y + d, y - d], color=color, lw=1.6, zorder=5)
    else:
        ax.plot([x], [y], "o", color=color, ms=3, zorder=5)
    ax.text(x + offset[0], y + offset[1], label, color=color, fontsize=10, ha="center", va="center")


def _crease_profile(t, L, H):
    """The L-shaped cross-section of :func:`vobscure.scenes.crease` in the xy plane."""
    return np.array([(-t, -t), (L, -t), (L, 0.0), (0.0, 0.0), (0.0, H), (-t, H)])


def _equal_aspect(ax, xlim, ylim):
    """Show at least ``xlim`` x ``ylim`` at equal aspect, widening the limits to fit the axes.

    Widening the data limits (``adjustable="datalim"``) instead of shrinking the axes box keeps
    the constrained layout stable: a shrunk box moves its title after the layout has placed it.
    ``auto=None`` keeps autoscaling on, so matplotlib widens the limits without logging that
    it ignores fixed limits.
    """
    ax.set_xlim(*xlim, auto=None)
    ax.set_ylim(*ylim, auto=None)
    ax.set_aspect("equal", adjustable="datalim")


# ----------------------------------------------------------------------------- panels
def _panel_spaces(ax, cam, bounds):
    """(a) Side view (the plane z = 0) of the crease, the camera and both frames."""
    from matplotlib.patches import Polygon

    (lo, hi) = bounds  # the crease's profile: x in [-t, L], y in [-t, H]
    profile = _crease_profile(t=-lo[0], L=hi[0], H=hi[1])
    ax.add_patch(Polygon(profile, closed=True, fc=_SOLID, ec="k", lw=1.0, zorder=1))
    ax.text(-1.0, 2.2, "wall\n(face x = 0)", ha="center", va="center", fontsize=9)
    ax.text(2.6, -1.0, "floor (top y = 0)", ha="center", va="center", fontsize=9)

    # world frame at the origin: x right, y up, z toward the reader
    _arrow(ax, (0, 0), (1.3, 0), _WORLD)
    ax.text(1.3, 0.22, "$x_w$", color=_WORLD, fontsize=10, ha="center", va="center")
    _arrow(ax, (0, 0), (0, 1.3), _WORLD, "$y_w$", label_at=1.18)
    _out_of_page(ax, (0.0, 0.0), _WORLD, "", radius=0.11)
    ax.text(-0.2, 0.3, "$z_w$ (out of\nthe page)", color=_WORLD, fontsize=9, ha="right", va="center")

    # the camera: frustum in the drawing plane, view axes at the eye
    eye = cam.eye[:2]
    fwd = cam.forward[:2]
    up = cam.up[:2]
    half = np.radians(cam.fov_y) / 2.0
    far = 9.2
    for s in (-1.0, 1.0):
        d = np.cos(half) * fwd + s * np.sin(half) * up
        ax.plot([eye[0], eye[0] + far * d[0]], [eye[1], eye[1] + far * d[1]], color="0.55", lw=0.9,
                ls="--", zorder=2)
    body = np.array([eye - 0.2 * fwd + 0.22 * up, eye - 0.2 * fwd - 0.22 * up,
                     eye - 0.8 * fwd - 0.22 * up, eye - 0.8 * fwd + 0.22 * up])
    lens = np.array([eye - 0.2 * fwd + 0.12 * up, eye - 0.2 * fwd - 0.12 * up, eye - 0.16 * up,
                     eye + 0.16 * up])
    ax.add_patch(Polygon(body, closed=True, fc="0.35", ec="k", zorder=4))
    ax.add_patch(Polygon(lens, closed=True, fc="0.6", ec="k", zorder=4))
    ax.plot(*eye, "o", color=_VIEW, ms=4, zorder=6)
    _arrow(ax, eye, 1.5 * fwd, _VIEW)
    ax.text(*(eye + 1.2 * fwd + np.array([0.0, 0.3])), "$z_v$", color=_VIEW, fontsize=11, ha="center",
            va="center")
    _arrow(ax, eye, 1.3 * up, _VIEW, "$y_v$", label_at=1.2, fontsize=11)
    _out_of_page(ax, eye + np.array([0.55, -0.45]), _VIEW, "$x_v = -z_w$,\ninto the page",
                 into=True, offset=(0.15, -0.62))
    ax.text(eye[0] + 0.75, eye[1] + 0.55, "eye\n(view origin)", fontsize=9, ha="center", va="bottom")

    # a floor point P: depth z (along forward) versus the ray distance |P - eye|
    P = np.array([2.2, 0.0])
    foot = eye + np.dot(P - eye, fwd) * fwd
    ax.plot([eye[0], foot[0]], [eye[1], foot[1]], color=_VIEW, lw=1.0, zorder=2)
    ax.plot([P[0], foot[0]], [P[1], foot[1]], color=_VIEW, lw=0.8, ls=":", zorder=2)
    ax.plot([eye[0], P[0]], [eye[1], P[1]], color="k", lw=0.9, ls="-.", zorder=2)
    z = float(np.dot(P - eye, fwd))
    dist = float(np.linalg.norm(P - eye))
    ax.plot(*P, "ko", ms=4, zorder=6)
    ax.text(P[0] - 0.05, P[1] - 0.35, "P", fontsize=10, ha="center", va="center", zorder=6)
    mid = 0.55 * eye + 0.45 * foot
    ax.text(mid[0] - 0.7, mid[1] + 0.2, f"depth z = {z:.2f} (gb.depth)", color=_VIEW, fontsize=9,
            ha="center", va="bottom", rotation=np.degrees(np.arctan2(fwd[1], fwd[0])) + 180.0,
            rotation_mode="anchor")
    midr = 0.55 * eye + 0.45 * P
    ax.text(midr[0] + 0.1, midr[1] - 0.45, f"ray distance {dist:.2f}", fontsize=9, ha="center",
            va="top")

    # the floor normal at P faces the camera: n_z = n . forward < 0
    n_view = cam.floor_normal_view
    _arrow(ax, P, (0.0, 1.1), "k", lw=1.6)
    ax.text(P[0] + 0.1, P[1] + 0.75, "n", fontsize=10, ha="left", va="center")
    ax.annotate(f"floor normal n = (0, 1, 0) in world space,\n"
                f"({n_view[0]:+.2f}, {n_view[1]:+.2f}, {n_view[2]:+.2f}) in view space:\n"
                "$n_z < 0$ since it faces the camera",
                xy=P + np.array([0.0, 1.05]), xytext=(1.9, 3.05), fontsize=9, ha="center", va="bottom",
                arrowprops={"arrowstyle": "-", "color": "0.4", "lw": 0.8, "shrinkB": 3},
                bbox={"fc": "white", "ec": "0.8", "alpha": 0.9, "pad": 2})

    _equal_aspect(ax, (-2.6, 9.2), (-2.4, 4.9))
    ax.set_xlabel("world x")
    ax.set_ylabel("world y")
    ax.set_title("(a) world space (right-handed, y up) and view space\n"
                 "(camera at origin, x right, y up, z = depth > 0 in front)", fontsize=11)
    rows = ["view axes: x_v = right, y_v = up, z_v = forward",
            "world -> view:  p_v = R (p_w - eye),",
            "R rows = (right, up, forward),  det R = -1"]
    ax.text(0.985, 0.025, "\n".join(rows), transform=ax.transAxes, ha="right", va="bottom", fontsize=9,
            multialignment="left", family="monospace", bbox={"fc": "white", "ec": "0.7", "pad": 3})


def _panel_pixels(ax):
    """(b) A 6 x 4 pixel grid with the continuous pixel coordinates."""
    from matplotlib.patches import Rectangle

    W, H = 6, 4
    i, j = 3, 4
    for r in range(H):
        for col in range(W):
            fc = "#fde9a9" if (r, col) == (i, j) else "white"
            ax.add_patch(Rectangle((col, r), 1, 1, fc=fc, ec="0.4", lw=1.0))
    for r in range(H):
        ax.text(-0.35, r + 0.5, f"{r}", ha="center", va="center", fontsize=10)
    for col in range(W):
        ax.text(col + 0.5, -0.3, f"{col}", ha="center", va="center", fontsize=10)
    ax.text(-0.85, H / 2, "row i", rotation=90, ha="center", va="center", fontsize=10)
    ax.text(W / 2, -0.75, "column j", ha="center", va="center", fontsize=10)

    ax.plot([j + 0.5], [i + 0.5], "o", color=_VIEW, ms=6)
    ax.annotate(f"pixel (i, j) = ({i}, {j}): centre (x, y) = ({j + 0.5}, {i + 0.5})",
                xy=(j + 0.5, i + 0.5), xytext=(W / 2 + 0.4, H + 0.45), ha="center", va="top",
                fontsize=9, color=_VIEW,
                arrowprops={"arrowstyle": "-", "color": _VIEW, "lw": 0.8, "shrinkB": 4})
    # continuous axes from the top-left corner of pixel (0, 0)
    ax.plot([0], [0], "ks", ms=5)
    ax.annotate("", xy=(W + 0.7, 0), xytext=(0, 0),
                arrowprops={"arrowstyle": "-|>", "color": _WORLD, "lw": 1.8, "shrinkA": 0, "shrinkB": 0})
    ax.annotate("", xy=(0, H + 0.7), xytext=(0, 0),
                arrowprops={"arrowstyle": "-|>", "color": _WORLD, "lw": 1.8, "shrinkA": 0, "shrinkB": 0})
    ax.text(W + 0.85, -0.05, "x", color=_WORLD, fontsize=11, ha="left", va="center")
    ax.text(0.0, H + 0.95, "y", color=_WORLD, fontsize=11, ha="center", va="center")
    # the principal point, where the optical axis meets the image
    ax.plot([W / 2], [H / 2], "+", color="k", ms=12, mew=1.6)
    ax.text(W / 2 + 0.12, H / 2 + 0.12, "(W/2, H/2)", fontsize=8.5, ha="left", va="top")

    ax.text(W / 2, H + 1.2,
            "image array shape (H, W) = (4, 6); camera size = (width, height) = (6, 4)\n"
            "row 0 is the top; y grows down; image up = view +y",
            ha="center", va="top", fontsize=9)
    _equal_aspect(ax, (-1.1, W + 1.3), (H + 2.05, -1.05))  # y inverted: row 0 at the top
    ax.axis("off")
    ax.set_title("(b) images: row 0 at the top,\npixel (i, j) centred at (x, y) = (j + 0.5, i + 0.5)",
                 fontsize=11)


def _panel_gbuffer(subfig, gb, ao):
    """(c) depth, view-space normals and ray-cast AO of the crease."""
    import matplotlib as mpl
    from matplotlib.patches import Patch

    axes = subfig.subplots(1, 3)
    H, W = gb.shape
    extent = (0, W, H, 0)  # pixel edges: pixel (i, j) covers [j, j+1) x [i, i+1)
    valid = gb.valid

    depth = np.ma.masked_invalid(np.where(valid, gb.depth, np.nan))
    cmap = mpl.colormaps["viridis"].with_extremes(bad=BACKGROUND)
    im = axes[0].imshow(depth, cmap=cmap, extent=extent, interpolation="nearest")
    subfig.colorbar(im, ax=axes[0], shrink=0.8, label="depth z (view space)")
    axes[0].set_title("gb.depth: linear view z\n(+inf on background)", fontsize=10)

    rgb = np.empty((H, W, 3))
    rgb[...] = 0.5 * (gb.normal + 1.0)
    rgb[~valid] = mpl.colors.to_rgb(BACKGROUND)
    axes[1].imshow(rgb, extent=extent, interpolation="nearest")
    axes[1].set_title("gb.normal: view space, RGB = (n + 1) / 2\n(0 on background)", fontsize=10)
    # the two faces' normals, read from the buffer
    for name, (r, cc) in {"wall": (int(0.3 * H), W // 2), "floor": (int(0.85 * H), W // 2)}.items():
        n = gb.normal[r, cc]
        axes[1].text(cc + 0.5, r + 0.5, f"{name}: n = ({n[0]:+.2f}, {n[1]:+.2f}, {n[2]:+.2f})",
                     ha="center", va="center", fontsize=8.5,
                     bbox={"fc": "white", "ec": "none", "alpha": 0.85, "pad": 1.5})

    gray = mpl.colormaps["gray"].with_extremes(bad=BACKGROUND)
    im = axes[2].imshow(np.ma.masked_invalid(ao.value), cmap=gray, vmin=0.0, vmax=1.0, extent=extent,
                        interpolation="nearest")
    subfig.colorbar(im, ax=axes[2], shrink=0.8, label="visibility (1 = open)")
    axes[2].set_title(f"vo.ground_truth(quantity=\"ao\", radius={RADIUS:g},\n"
                      f"rays={ao.samples}): NaN on background", fontsize=10)

    for ax in axes:
        ax.set_xlabel("column j (x)")
        ax.set_ylabel("row i (y)")
    subfig.legend(handles=[Patch(fc=BACKGROUND, ec="none", label="background (no hit)")],
                  loc="outside lower center", fontsize=9, frameon=False)
    subfig.suptitle(f"(c) a G-buffer of vo.scenes.crease() through the camera of (a), "
                    f"{W} x {H} pixels: images are (H, W) arrays, row 0 at the top",
                    fontsize=11)


def _panel_ball(ax, bounds):
    """(d, left) Cross-section z = 0 of the ball around a floor point at distance a from the wall."""
    from matplotlib.patches import Circle, Polygon

    R = RADIUS
    a = 0.4 * R
    P = np.array([a, 0.0])
    (lo, hi) = bounds
    profile = _crease_profile(t=-lo[0], L=hi[0], H=hi[1])
    ax.add_patch(Polygon(profile, closed=True, fc=_SOLID, ec="k", lw=1.0, zorder=1))
    # the ball: its open part, then the solid again, clipped to the ball: the occupied part
    ax.add_patch(Circle(P, R, fc=_OPEN, ec="none", zorder=2))
    occupied = Polygon(profile, closed=True, fc=_OCCUPIED, ec="none", zorder=3)
    ax.add_patch(occupied)
    occupied.set_clip_path(Circle(P, R, transform=ax.transData))
    ax.add_patch(Circle(P, R, fill=False, ec="k", lw=1.4, zorder=4))
    ax.plot([P[0] - R, P[0] + R], [0, 0], color="k", lw=1.0, ls="--", zorder=4)

    ax.plot(*P, "ko", ms=5, zorder=6)
    ax.text(P[0] + 0.06, P[1] - 0.12, "P", fontsize=11, ha="left", va="top", color="white", zorder=6)
    # a: from the wall to P
    ax.annotate("", xy=(0.0, 0.12), xytext=(a, 0.12),
                arrowprops={"arrowstyle": "<->", "color": "k", "lw": 1.1, "shrinkA": 0, "shrinkB": 0},
                zorder=6)
    ax.text(a / 2, 0.2, "a", fontsize=11, ha="center", va="bottom", zorder=6)
    # R: a radius up and to the right
    d = np.array([np.cos(np.radians(40)), np.sin(np.radians(40))])
    ax.plot([P[0], P[0] + R * d[0]], [P[1], P[1] + R * d[1]], color="k", lw=1.0, zorder=6)
    ax.text(P[0] + 0.55 * R * d[0] + 0.03, P[1] + 0.55 * R * d[1] - 0.1, "R", fontsize=11, zorder=6)
    _arrow(ax, P, (0.0, 0.55), _VIEW, "n", label_at=1.18)

    ax.text(1.75, 0.9, "open:\nvisible", fontsize=9, ha="center", va="center", color="#2b5d8a")
    ax.text(0.9, -0.55, "occupied\n(inside the solid)", fontsize=9, ha="center", va="center",
            color="white", zorder=6)
    ax.text(-0.75, 1.45, "wall", fontsize=9, ha="center")
    ax.text(1.85, -1.3, "floor", fontsize=9, ha="center")
    ax.text(P[0] + 1.08, 0.05, "half-ball\nboundary", fontsize=8, ha="left", va="bottom")
    _equal_aspect(ax, (-1.5, 2.4), (-1.5, 1.7))
    ax.set_xlabel("world x")
    ax.set_ylabel("world y")
    ax.set_title("(d) visibility, not occlusion: VO = the open fraction\n"
                 "of the ball of radius R around P (c = a / R)", fontsize=11)


def _panel_closed_forms(ax, check, quick):
    """(d, right) The closed forms against c, with the ray-cast ground truth at a few c."""
    c = np.linspace(0.0, 1.0, 201)
    exact = _closed_forms(c)
    styles = {
        "half": ("tab:blue", r"half-ball VO (normal_clamp): $1 - (1-c)^2(2+c)/4$"),
        "ao": ("tab:green", r"cosine AO within R: $1 - (\arccos c - c\sqrt{1-c^2})/\pi$"),
        "ball": ("tab:orange", r"ball VO: $\frac{1}{2} - (1-c)^2(2+c)/8$"),
    }
    for key, (color, label) in styles.items():
        ax.plot(c, exact[key], color=color, lw=2.0, label=label)
        e = check[key]
        ax.errorbar(check["c"], e.value, yerr=2.0 * e.stderr, fmt="o", color=color, ms=5, capsize=3,
                    mfc="white", mew=1.5)
    ax.plot([], [], "o", color="0.3", mfc="white", mew=1.5,
            label=f"ray-cast ground truth ({'quick' if quick else 'full'}), $\\pm$2 stderr")
    ax.axhline(0.5, color="0.6", lw=0.8, ls=":")
    ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    ax.text(0.5, 0.515, "flat open surface: ball VO = 0.5", ha="center", va="bottom", fontsize=8.5,
            color="0.35")
    ax.text(0.01, 0.985, "flat open surface: half-ball VO = AO = 1", ha="left", va="top", fontsize=8.5,
            color="0.35")
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel("c = a / R  (distance from the wall over the radius)")
    ax.set_ylabel("visibility (1 = open)")
    ax.legend(loc="lower right", fontsize=8.5, framealpha=0.95)
    ax.set_title("closed forms for the crease floor (DESIGN.md, Testing)", fontsize=11)


make = deprecated_make(__name__)
