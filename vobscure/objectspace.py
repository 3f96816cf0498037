r"""Object-space ambient occlusion from oriented disks (Bunnell 2005).

The surface is replaced by one oriented disk per mesh vertex (area a third of the adjacent
triangles' areas, normal the vertex normal), and each disk's occlusion of a receiver is
computed in closed form, without rays (Bunnell 2005; RTR 3rd ed. Sec. 9.2.5). Summing all
disks' shadows double-counts a disk hidden behind another; Bunnell's second pass weights each
emitter by its own first-pass accessibility, which cancels most of that over-darkening.

This module is the O(n^2) form: blocks of receivers against every emitter. The hierarchy of
aggregated disks (O(n log n)) is not implemented.

References
----------
.. [1] M. Bunnell, "Dynamic Ambient Occlusion and Indirect Lighting", GPU Gems 2, ch. 14,
   Addison-Wesley, 2005.
.. [2] T. Akenine-Moeller, E. Haines, N. Hoffman, Real-Time Rendering, 3rd ed., Sec. 9.2.5,
   "Dynamic Computation of Ambient Occlusion: Object-Space Methods", 2008.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_array, as_points, as_unit_vectors, check_int
from .scenes import as_scene

__all__ = ["bunnell", "disk_shadow", "vertex_disks"]

#: Receivers evaluated at once against all emitters (memory: BLOCK * n_emitters * 3 floats).
DEFAULT_BLOCK = 512

#: An emitter closer to the receiver than this fraction of the scene extent is the
#: receiver's own disk and casts no shadow (the term is undefined at zero distance).
SELF_DISTANCE = 1e-9


def disk_shadow(receivers, receiver_normals, emitters, emitter_normals, emitter_areas):
    r"""Bunnell's shadow term of every emitter disk on every receiver point.

    .. math::

        S = \left(1 - \frac{1}{\sqrt{1 + A / (\pi r^2)}}\right)
            \max(0, -\mathbf{e}\cdot\mathbf{n}_E)\,\max(0, \mathbf{e}\cdot\mathbf{n}_R)

    with :math:`\mathbf{e}` the unit vector from the receiver to the emitter, r their
    distance, A the emitter's area. The first factor is the fraction of the hemisphere's
    solid angle that a disk of area A seen on axis at distance r subtends,
    :math:`1 - r/\sqrt{r^2 + a^2}` for :math:`A = \pi a^2`; the cosines tilt it away from
    the axis. The emitter must face the receiver, and lie above the receiver's plane.

    Parameters
    ----------
    receivers : (n, 3) float
    receiver_normals : (n, 3) float
        Unit normals (renormalized).
    emitters : (k, 3) float
        Disk centres.
    emitter_normals : (k, 3) float
        Unit disk normals (renormalized); the disk's front side is the one they point to.
    emitter_areas : (k,) float
        Disk areas, >= 0.

    Returns
    -------
    (n, k) float64
        The shadow of emitter j on receiver i, in [0, 1); 0 where the two coincide.

    Notes
    -----
    On axis this is the hemisphere's solid-angle fraction (the occlusion of *uniformly*
    weighted AO) exactly; the cosine-weighted occlusion of the same disk is its form factor
    :math:`a^2/(r^2 + a^2)`, twice as large for a small disk (see ``docs/objectspace.md``).

    References
    ----------
    Bunnell 2005 (GPU Gems 2, ch. 14), the element-to-element shadow approximation; RTR 3rd
    ed. Sec. 9.2.5.

    Examples
    --------
    >>> import numpy as np
    >>> S = disk_shadow([[0, 0, 0]], [[0, 0, 1]], [[0, 0, 1]], [[0, 0, -1]], [np.pi])
    >>> round(float(S[0, 0]), 6)  # a unit-radius disk at distance 1: 1 - 1/sqrt(2)
    0.292893
    """
    p_R = as_points(receivers, "receivers")
    n_R = as_unit_vectors(receiver_normals, "receiver_normals", count=len(p_R))
    p_E = as_points(emitters, "emitters")
    n_E = as_unit_vectors(emitter_normals, "emitter_normals", count=len(p_E))
    A = _as_areas(emitter_areas, len(p_E))
    return _shadow(p_R, n_R, p_E, n_E, A, _self_distance(p_R, p_E))


def vertex_disks(scene):
    """The disks Bunnell places at the vertices of every mesh of ``scene``.

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts.

    Returns
    -------
    centres : (k, 3) float64
        The vertices, mesh after mesh in the order of ``scene.meshes``.
    normals : (k, 3) float64
        Unit vertex normals (trimesh's face-area weighted means).
    areas : (k,) float64
        A third of the area of the triangles around each vertex (they sum to the surface area).

    Examples
    --------
    >>> import trimesh
    >>> c, n, A = vertex_disks(trimesh.creation.box())
    >>> c.shape, round(float(A.sum()), 6)
    ((8, 3), 6.0)
    """
    scene = as_scene(scene)
    centres, normals, areas = [], [], []
    for mesh in scene.meshes.values():
        faces = np.asarray(mesh.faces)
        A_face = np.asarray(mesh.area_faces, dtype=np.float64)
        centres.append(np.asarray(mesh.vertices, dtype=np.float64))
        normals.append(np.asarray(mesh.vertex_normals, dtype=np.float64))
        # each triangle gives a third of its area to each of its corners
        areas.append(np.bincount(faces.ravel(), weights=np.repeat(A_face / 3.0, 3),
                                 minlength=len(mesh.vertices)))
    return np.concatenate(centres), np.concatenate(normals), np.concatenate(areas)


def bunnell(scene, points=None, normals=None, *, passes: int = 2, hierarchy: bool = False,
            block: int = DEFAULT_BLOCK) -> np.ndarray:
    r"""Ambient visibility from Bunnell's disks (1 = open), O(n^2) in the disks.

    Pass 1 sums the shadows of all disks, double shadowing included:
    :math:`V_1(i) = 1 - \sum_j S_{ij}`. Pass p > 1 weights each emitter by its accessibility
    from the previous pass, :math:`V_p(i) = 1 - \sum_j S_{ij} V_{p-1}(j)` (Bunnell 2005):
    a disk that is itself in shadow is mostly hidden behind the disk that shadows it. Each
    pass is clamped to [0, 1].

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts. Its meshes' vertices are the disks
        (:func:`vertex_disks`).
    points : (n, 3) float, optional
        Receivers. None: the disks' own centres (the per-vertex AO that Bunnell computes).
        Receivers that are not disks get the last pass's sum over the disks, weighted by the
        disks' previous-pass accessibility.
    normals : (n, 3) float, optional
        Receiver normals; required with ``points``, not allowed without.
    passes : int
        Number of passes, >= 1. Bunnell uses 2 (a third averages the second and third
        passes in his chapter; here a third pass is simply one more iteration).
    hierarchy : bool
        The O(n log n) tree of aggregated disks. Not implemented: True raises
        NotImplementedError.
    block : int
        Receivers evaluated at once (memory ``block * k`` floats per array).

    Returns
    -------
    (n,) float64
        Visibility in [0, 1]: per vertex when ``points`` is None, else per point.

    References
    ----------
    Bunnell 2005, GPU Gems 2, ch. 14; RTR 3rd ed. Sec. 9.2.5. The shadow term is
    :func:`disk_shadow`.

    Examples
    --------
    >>> import vobscure as vo
    >>> V = bunnell(vo.scenes.get("crease"))
    >>> V.shape, bool(((0 <= V) & (V <= 1)).all())
    ((12,), True)
    """
    if not isinstance(hierarchy, (bool, np.bool_)):
        raise ValueError(f"hierarchy must be True or False, got {hierarchy!r}")
    if hierarchy:
        raise NotImplementedError(
            "bunnell(hierarchy=True): the O(n log n) tree of aggregated disks (Bunnell 2005) "
            "is not implemented; use hierarchy=False (the exact O(n^2) sum over all disks)"
        )
    passes = check_int(passes, "passes", minimum=1)
    block = check_int(block, "block", minimum=1)
    p_E, n_E, A = vertex_disks(scene)
    if points is None:
        if normals is not None:
            raise ValueError("normals were given without points; pass both, or neither for "
                             "the per-vertex visibility")
        p_R, n_R = p_E, n_E
    else:
        if normals is None:
            raise ValueError("normals is required when points is given")
        p_R = as_points(points, "points")
        n_R = as_unit_vectors(normals, "normals", count=len(p_R))
    eps = _self_distance(p_R, p_E)

    # Pass 1: every emitter at full weight (double shadowing); passes 2..: weighted by the
    # emitters' own accessibility from the pass before (Bunnell 2005).
    V_E = np.ones(len(p_E))
    for _ in range(passes - 1):
        V_E = _gather(p_E, n_E, p_E, n_E, A, V_E, block, eps)
    if points is None:
        return _gather(p_E, n_E, p_E, n_E, A, V_E, block, eps)
    return _gather(p_R, n_R, p_E, n_E, A, V_E, block, eps)


# ----------------------------------------------------------------------------- helpers


def _as_areas(value, count: int) -> np.ndarray:
    A = as_array(value, "emitter_areas", shape=(count,))
    if np.any(A < 0):
        raise ValueError(f"emitter_areas must be >= 0; {int(np.count_nonzero(A < 0))} are negative")
    return A


def _self_distance(p_R: np.ndarray, p_E: np.ndarray) -> float:
    both = np.concatenate([p_R, p_E]) if len(p_R) + len(p_E) else np.zeros((1, 3))
    extent = float(np.linalg.norm(both.max(axis=0) - both.min(axis=0)))
    return SELF_DISTANCE * max(extent, 1.0)


def _shadow(p_R, n_R, p_E, n_E, A, eps) -> np.ndarray:
    """(n, k) shadow terms, float64; see :func:`disk_shadow`."""
    v = p_E[None, :, :] - p_R[:, None, :]           # receiver -> emitter
    r2 = np.einsum("ijk,ijk->ij", v, v)
    coincide = r2 <= eps * eps
    r2 = np.where(coincide, 1.0, r2)
    e = v / np.sqrt(r2)[..., None]
    cos_E = np.clip(-np.einsum("ijk,jk->ij", e, n_E), 0.0, None)   # emitter faces receiver
    cos_R = np.clip(np.einsum("ijk,ik->ij", e, n_R), 0.0, None)    # emitter above the plane
    # Bunnell 2005: on-axis solid-angle fraction of a disk of area A at distance r
    S = (1.0 - 1.0 / np.sqrt(1.0 + A[None, :] / (np.pi * r2))) * cos_E * cos_R
    S[coincide] = 0.0
    return S


def _gather(p_R, n_R, p_E, n_E, A, V_E, block, eps) -> np.ndarray:
    """V(i) = clip(1 - sum_j S_ij V_E(j), 0, 1), receivers in blocks of ``block``."""
    V = np.empty(len(p_R))
    for start in range(0, len(p_R), block):
        sl = slice(start, start + block)
        V[sl] = 1.0 - _shadow(p_R[sl], n_R[sl], p_E, n_E, A, eps) @ V_E
    return np.clip(V, 0.0, 1.0)
