r"""Object-space ambient occlusion from oriented disks (Bunnell 2005).

The surface is replaced by one oriented disk per mesh vertex (area a third of the adjacent
triangles' areas, normal the vertex normal), and each disk's occlusion of a receiver is
computed in closed form, without rays (Bunnell 2005; RTR 3rd ed. Sec. 9.2.5). Summing all
disks' shadows double-counts a disk hidden behind another; Bunnell's second pass weights each
emitter by its own first-pass accessibility, which cancels most of that over-darkening.

The exact form is O(n^2): blocks of receivers against every emitter. ``hierarchy=True``
uses a binary tree of aggregated disks instead (RTR 9.2.5): a node far from the receiver
(farther than ``open_ratio`` times its bounding radius) stands for all its disks.

References
----------
.. [1] M. Bunnell, "Dynamic Ambient Occlusion and Indirect Lighting", GPU Gems 2, ch. 14,
   Addison-Wesley, 2005.
.. [2] T. Akenine-Moeller, E. Haines, N. Hoffman, Real-Time Rendering, 3rd ed., Sec. 9.2.5,
   "Dynamic Computation of Ambient Occlusion: Object-Space Methods", 2008.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_array, as_points, as_unit_vectors, check_int, check_positive
from ..scenes import as_scene

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


#: A tree node farther from the receiver than this many times its bounding radius is used
#: as one aggregated disk (``hierarchy=True``).
DEFAULT_OPEN_RATIO = 4.0


def bunnell(scene, points=None, normals=None, *, passes: int = 2, hierarchy: bool = False,
            block: int = DEFAULT_BLOCK, open_ratio: float = DEFAULT_OPEN_RATIO) -> np.ndarray:
    r"""Ambient visibility from Bunnell's disks (1 = open).

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
        Use the tree of aggregated disks (RTR 9.2.5; Bunnell 2005): a binary tree by median
        splits of the disk centres, each node one disk with the sum of its disks' areas,
        their area-weighted mean centre and normal, and (in passes > 1) their area-weighted
        mean accessibility. False: the exact sum over all disks.
    block : int
        Receivers evaluated at once (memory ``block * k`` floats per array); exact sum only.
    open_ratio : float
        With ``hierarchy``: a node is used as one disk when the receiver is farther from
        its centre than ``open_ratio`` times its bounding radius; else its children are.
        Large values reproduce the exact sum.

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
    passes = check_int(passes, "passes", minimum=1)
    block = check_int(block, "block", minimum=1)
    open_ratio = check_positive(open_ratio, "open_ratio", allow_inf=True)
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
    if hierarchy:
        tree = _Tree(p_E, n_E, A)

        def gather(p, n, V):
            return _gather_tree(p, n, tree, V, open_ratio, eps)
    else:
        def gather(p, n, V):
            return _gather(p, n, p_E, n_E, A, V, block, eps)
    V_E = np.ones(len(p_E))
    for _ in range(passes - 1):
        V_E = gather(p_E, n_E, V_E)
    if points is None:
        return gather(p_E, n_E, V_E)
    return gather(p_R, n_R, V_E)


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


class _Tree:
    """Binary tree of aggregated disks by median splits along the longest axis.

    Leaves are the single disks (node j < k is disk j). ``members[i]`` lists the disks
    under node i; ``children[i]`` is (left, right) or (-1, -1) for a leaf.
    """

    def __init__(self, p_E, n_E, A):
        k = len(p_E)
        self.k = k
        members = [np.array([j]) for j in range(k)]
        children = [(-1, -1)] * k

        def build(idx):
            if len(idx) == 1:
                return int(idx[0])
            pts = p_E[idx]
            axis = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
            order = idx[np.argsort(pts[:, axis], kind="stable")]
            half = len(order) // 2
            left, right = build(order[:half]), build(order[half:])
            members.append(order)
            children.append((left, right))
            return len(members) - 1

        self.root = build(np.arange(k)) if k else -1
        self.members = members
        self.children = np.array(children, dtype=np.intp).reshape(-1, 2)
        m = len(members)
        self.area = np.array([A[mem].sum() for mem in members])
        w = [A[mem] / max(A[mem].sum(), 1e-300) for mem in members]
        self.centre = np.array([w_i @ p_E[mem] for w_i, mem in zip(w, members)]).reshape(m, 3)
        normal = np.array([w_i @ n_E[mem] for w_i, mem in zip(w, members)]).reshape(m, 3)
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        # a node whose disks' normals cancel has no orientation: it casts nothing
        self.normal = np.where(length > 1e-12, normal / np.maximum(length, 1e-300), 0.0)
        self.radius = np.array([
            np.max(np.linalg.norm(p_E[mem] - c, axis=1) + np.sqrt(A[mem] / np.pi))
            for mem, c in zip(members, self.centre)])
        self.weights = w

    def accessibility(self, V_E):
        """Each node's area-weighted mean accessibility of its disks."""
        return np.array([w_i @ V_E[mem] for w_i, mem in zip(self.weights, self.members)])


def _gather_tree(p_R, n_R, tree, V_E, open_ratio, eps) -> np.ndarray:
    """The hierarchical form of :func:`_gather`: frontier of (receiver, node) pairs."""
    total = np.zeros(len(p_R))
    if tree.root < 0 or not len(p_R):
        return np.clip(1.0 - total, 0.0, 1.0)
    V_node = tree.accessibility(V_E)
    r_idx = np.arange(len(p_R))
    node = np.full(len(p_R), tree.root, dtype=np.intp)
    while len(r_idx):
        d = np.linalg.norm(p_R[r_idx] - tree.centre[node], axis=1)
        use = (node < tree.k) | (d > open_ratio * tree.radius[node])
        ri, ni = r_idx[use], node[use]
        S = _shadow_pairs(p_R[ri], n_R[ri], tree.centre[ni], tree.normal[ni], tree.area[ni], eps)
        np.add.at(total, ri, S * V_node[ni])
        r_idx, node = r_idx[~use], node[~use]
        r_idx = np.concatenate([r_idx, r_idx])
        node = np.concatenate([tree.children[node, 0], tree.children[node, 1]])
    return np.clip(1.0 - total, 0.0, 1.0)


def _shadow_pairs(p_R, n_R, p_E, n_E, A, eps) -> np.ndarray:
    """(n,) shadow terms of emitter i on receiver i; see :func:`disk_shadow`."""
    v = p_E - p_R
    r2 = np.einsum("ij,ij->i", v, v)
    coincide = r2 <= eps * eps
    r2 = np.where(coincide, 1.0, r2)
    e = v / np.sqrt(r2)[:, None]
    cos_E = np.clip(-np.einsum("ij,ij->i", e, n_E), 0.0, None)
    cos_R = np.clip(np.einsum("ij,ij->i", e, n_R), 0.0, None)
    S = (1.0 - 1.0 / np.sqrt(1.0 + A / (np.pi * r2))) * cos_E * cos_R   # Bunnell 2005
    return np.where(coincide, 0.0, S)
