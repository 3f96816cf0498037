"""The vegetation models per pixel of a G-buffer: what ``vobscure compare --scene tree`` runs
beside the screen-space estimators.

A vegetation scene (:mod:`vobscure.scenes.vegetation`) records its leaf statistics in
``scene.metadata``; from them :func:`canopy_shell` fits the shell of Hegeman et al. (2006,
Sec. 3) and :func:`scene_density` predicts its density alpha*rho (:func:`predict_density`).
:func:`hegeman_gbuffer` then shades every covered pixel as the paper does: points of the tree
(leaves, wood) by the canopy model (Eqs. 4-6), points of the ground by the occluder model of
the canopy's bounding sphere (Eqs. 7-8, or the ``"exact"`` / ``"porous"`` variants of
:func:`occluder_visibility`). Both estimate sky visibility (ambient occlusion with no distance
limit), the ``"sky"`` reference of the experiments. :func:`poisson_gbuffer` shades every
pixel, leaves and ground alike, by the expected visibility of a Poisson leaf cloud in the
same shell (:func:`poisson_visibility`), its extinction from the leaf statistics alone.
"""

from __future__ import annotations

import weakref

import numpy as np

from .canopy import canopy_visibility, predict_density, reeves_blau
from .occluders import occluder_visibility
from .poisson import extinction, poisson_visibility
from .shells import MultiShell, bounding_ellipsoid, bounding_sphere, shells_from_points

__all__ = ["canopy_shell", "scene_density", "scene_extinction", "hegeman_gbuffer", "poisson_gbuffer",
           "reeves_blau_gbuffer", "SHELL_KINDS", "GROUND_MESH"]

#: Shells :func:`canopy_shell` fits: one sphere, one ellipsoid, or k-means spheres.
SHELL_KINDS = ("sphere", "ellipsoid", "multishell")
#: The name of the ground mesh in the vegetation scenes (its pixels get the occluder model).
GROUND_MESH = "ground"


def _canopy_points(scene) -> np.ndarray:
    meta = getattr(scene, "metadata", None) or {}
    if "canopy_points" not in meta:
        raise ValueError(f"scene {getattr(scene, 'name', scene)!r} has no canopy: the vegetation models need a "
                         f"scene of vobscure.scenes.vegetation (leaf_cloud, tree, ...) whose metadata holds "
                         f"'canopy_points'")
    return np.asarray(meta["canopy_points"], dtype=np.float64)


_SHELLS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def canopy_shell(scene, *, kind: str = "sphere", k: int = 3, seed=0):
    """The shell enclosing a vegetation scene's leaves (``metadata["canopy_points"]``).

    Parameters
    ----------
    scene : Scene
        A vegetation scene.
    kind : {"sphere", "ellipsoid", "multishell"}
        The minimal enclosing sphere (Sec. 3), the minimum-volume enclosing ellipsoid (Sec. 3,
        Fig. 8), or ``k`` spheres by k-means (Sec. 5, Fig. 3 left).
    k, seed : int
        For ``"multishell"``.

    Examples
    --------
    >>> from vobscure import scenes
    >>> shell = canopy_shell(scenes.get("leaf_cloud"))
    >>> bool(0.9 < shell.radius <= 1.1)
    True
    """
    if kind not in SHELL_KINDS:
        raise ValueError(f"kind must be one of {', '.join(SHELL_KINDS)}, got {kind!r}")
    # the fit is the paper's precomputation: once per scene, kind and k
    key = (kind, int(k), seed if isinstance(seed, int) else id(seed))
    cached = _SHELLS.setdefault(scene, {})
    if key not in cached:
        points = _canopy_points(scene)
        if kind == "sphere":
            cached[key] = bounding_sphere(points)
        elif kind == "ellipsoid":
            cached[key] = bounding_ellipsoid(points)
        else:
            cached[key] = shells_from_points(points, k, kind="sphere", seed=seed)
    return cached[key]


def _one_shell(scene, shell):
    """``shell``, or for a multishell (whose leaves are not attributed to its shells) the
    bounding sphere of all the leaves."""
    return bounding_sphere(_canopy_points(scene)) if isinstance(shell, MultiShell) else shell


def _from_leaves(model, scene, shell) -> float:
    """``model(n_leaves, leaf_area, shell)`` with the leaf statistics of ``scene.metadata``
    (:func:`predict_density` or :func:`extinction`)."""
    meta = scene.metadata
    return model(meta["n_leaves"], meta["leaf_area"], shell)


def scene_density(scene, shell) -> float:
    """alpha*rho of Eq. 6 predicted from the scene's leaf statistics (``n_leaves``,
    ``leaf_area``) by :func:`predict_density` for ``shell``; for a multishell, the density
    predicted for the bounding sphere of all the leaves is used for every shell (the leaves
    are not attributed to shells).

    Examples
    --------
    The density whose Eq. 6 matches, at the shell's centre, the transmittance exp(-sigma R)
    of :func:`scene_extinction`'s sigma:

    >>> from vobscure import scenes
    >>> scene = scenes.get("leaf_cloud")
    >>> shell = canopy_shell(scene)
    >>> sigma, R = scene_extinction(scene, shell), shell.radius
    >>> bool(np.isclose(scene_density(scene, shell), 3.0 * sigma / (2.0 * np.pi * R ** 2)))
    True
    """
    return _from_leaves(predict_density, scene, _one_shell(scene, shell))


def hegeman_gbuffer(gbuffer, *, scene, shell: str = "sphere", ground: str = "hegeman", density=None,
                    k: int = 3, radius=None, normal_clamp: bool = False, thickness=None,
                    falloff: str = "constant", seed=0) -> np.ndarray:
    """Hegeman et al. (2006) sky visibility at every covered pixel of a G-buffer.

    Parameters
    ----------
    gbuffer : GBuffer
        Of ``scene``.
    scene : Scene
        A vegetation scene (its ``metadata`` and its ``"ground"`` mesh).
    shell : {"sphere", "ellipsoid", "multishell"}
        The canopy shell (:func:`canopy_shell`).
    ground : {"hegeman", "exact", "porous"}
        The occluder model of ground pixels (:func:`occluder_visibility`), the canopy's
        bounding sphere as occluder; ``"porous"`` with the extinction that matches
        ``density`` (``sigma = 2 pi R^2 alpha_rho / 3``).
    density : float, optional
        alpha*rho; default :func:`scene_density` (predicted from the leaves, no fitting).
    k : int
        Shells of ``"multishell"``.
    radius, normal_clamp, thickness, falloff, seed
        Accepted for the estimators' common signature and not used: the model has no radius
        (it estimates visibility of the whole sky) and is deterministic.

    Returns
    -------
    (H, W) float64
        Sky visibility in [0, 1]: Eq. 6 at the tree's pixels, the occluder model at the
        ground's; NaN on background.

    References
    ----------
    Hegeman, Premoze, Ashikhmin & Drettakis, "Approximate Ambient Occlusion For Trees",
    I3D 2006, Sec. 3, Eqs. 4-8.
    """

    def model(x, n):
        canopy = canopy_shell(scene, kind=shell, k=k)
        alpha_rho = scene_density(scene, canopy) if density is None else float(density)
        names = list(scene.meshes)
        mesh = scene.mesh_index[np.asarray(gbuffer.primitive)[gbuffer.valid]]
        on_ground = (mesh == names.index(GROUND_MESH)) if GROUND_MESH in names else np.zeros(len(x), bool)
        v = np.empty(len(x))
        if (~on_ground).any():
            v[~on_ground] = canopy_visibility(x[~on_ground], n[~on_ground], canopy, density=alpha_rho)
        if on_ground.any():
            sphere = bounding_sphere(_canopy_points(scene))
            sigma = 2.0 * np.pi * sphere.radius ** 2 * alpha_rho / 3.0 if ground == "porous" else None
            v[on_ground] = occluder_visibility(x[on_ground], n[on_ground], sphere, model=ground, sigma=sigma)
        return v

    return gbuffer.per_pixel(model)


def scene_extinction(scene, shell) -> float:
    """sigma = n A / 2: the expected number of leaves crossed per unit length in a uniform
    leaf cloud of the scene's leaves in ``shell`` (n = n_leaves / shell volume, A the mean
    one-sided leaf area, A / 2 the mean projected area of a randomly oriented leaf, Cauchy's
    formula; the Poisson argument of :func:`predict_density`).

    Examples
    --------
    >>> from vobscure import scenes
    >>> scene = scenes.get("leaf_cloud")
    >>> shell, meta = canopy_shell(scene), scene.metadata
    >>> n = meta["n_leaves"] / shell.volume
    >>> bool(np.isclose(scene_extinction(scene, shell), n * meta["leaf_area"] / 2.0))
    True
    """
    return _from_leaves(extinction, scene, _one_shell(scene, shell))


def poisson_gbuffer(gbuffer, *, scene, shell: str = "sphere", weighting: str = "cosine", k: int = 3,
                    radius=None, normal_clamp: bool = False, thickness=None, falloff: str = "constant",
                    seed=0) -> np.ndarray:
    """The Poisson leaf cloud's expected sky visibility at every covered pixel of a G-buffer.

    Parameters
    ----------
    gbuffer : GBuffer
        Of ``scene``.
    scene : Scene
        A vegetation scene (its ``metadata`` holds ``n_leaves``, ``leaf_area`` and
        ``canopy_points``).
    shell : {"sphere", "ellipsoid", "multishell"}
        The canopy shell (:func:`canopy_shell`) that the leaves are taken to fill uniformly.
    weighting : {"cosine", "uniform"}
        The hemisphere weight (:func:`poisson_visibility`); "cosine" is the ``"sky"``
        reference.
    k : int
        Shells of ``"multishell"``.
    radius, normal_clamp, thickness, falloff, seed
        Accepted for the estimators' common signature and not used: the model has no radius
        and is deterministic.

    Returns
    -------
    (H, W) float64
        Expected sky visibility in [0, 1] (the leaf cloud's transmittance, averaged over
        the hemisphere with ``weighting``), NaN on background.

    Notes
    -----
    Nothing is fitted: the extinction is ``sigma = n A / 2`` with ``n = n_leaves / volume``
    of the shell (:func:`extinction`; a multishell's volume is the sum of its shells'). Every
    covered pixel -- leaves, wood and ground -- gets :func:`poisson_visibility` at its point
    and normal: points inside the shell see the cloud around them, points outside it (the
    ground) the same chord transmittance from outside. The wood is not an occluder of the
    model.

    References
    ----------
    Hegeman, Premoze, Ashikhmin & Drettakis, "Approximate Ambient Occlusion For Trees",
    I3D 2006, Sec. 3 (the Poisson argument, whose expectation this evaluates exactly).
    """

    def model(x, n):
        canopy = canopy_shell(scene, kind=shell, k=k)
        sigma = _from_leaves(extinction, scene, canopy)
        return poisson_visibility(x, n, canopy, extinction=sigma, weighting=weighting)

    return gbuffer.per_pixel(model)


def reeves_blau_gbuffer(gbuffer, *, scene, k=None, radius=None, normal_clamp: bool = False, thickness=None,
                        falloff: str = "constant", seed=0) -> np.ndarray:
    """The Reeves & Blau (1985) baseline at every covered pixel: ``exp(-k depth)`` with the depth
    inside the canopy's bounding sphere (1 outside it, on the ground too: the baseline has no
    interaction with other objects).

    Parameters
    ----------
    gbuffer : GBuffer
    scene : Scene
        A vegetation scene.
    k : float, optional
        Attenuation per unit depth; default the scene's leaf extinction sigma
        (:func:`scene_extinction`): the transmittance along the shortest way out of the
        canopy, the Poisson argument of Hegeman et al. applied to the baseline (Reeves & Blau
        set it by hand; the experiments also fit it).
    radius, normal_clamp, thickness, falloff, seed
        Accepted for the common signature and not used.

    Returns
    -------
    (H, W) float64
        ``exp(-k depth)`` in [0, 1], NaN on background.

    References
    ----------
    Reeves & Blau, "Approximate and probabilistic algorithms for shading and rendering
    structured particle systems", SIGGRAPH 1985; compared in Hegeman et al. 2006, Figs. 4, 12.
    """

    def model(x, n):
        shell = canopy_shell(scene)
        return reeves_blau(x, shell, k=scene_extinction(scene, shell) if k is None else float(k))

    return gbuffer.per_pixel(model)
