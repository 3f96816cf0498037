r"""Object-space ambient occlusion from oriented disks (Bunnell 2005).

The surface is replaced by one oriented disk per mesh vertex (area a third of the adjacent
triangles' areas, normal the vertex normal), and each disk's occlusion of a receiver is
computed in closed form, without rays (Bunnell 2005, Sec. 14.1-14.2; RTR 3rd ed. Sec.
9.2.5). Summing all disks' shadows double-counts a disk hidden behind another; Bunnell's
second pass weights each emitter by its own first-pass accessibility, which cancels most of
that over-darkening.

The exact form is O(n^2): blocks of receivers against every emitter. ``hierarchy=True``
(the default) uses a binary tree of aggregated disks instead (RTR 9.2.5): a node far from
the receiver (farther than ``open_ratio`` times its bounding radius) stands for all its
disks, which makes a pass O(n log n).

Three shadow terms are offered (:data:`TERMS`, :func:`disk_shadow`): the on-axis
solid-angle fraction of the disk with clamped cosines, the form of the chapter's Listing
14-1, and the cosine-weighted point-to-disk form factor. ``docs/objectspace.md`` measures
each against ray-cast AO.

References
----------
.. [1] M. Bunnell, "Dynamic Ambient Occlusion and Indirect Lighting", GPU Gems 2, ch. 14,
   Addison-Wesley, 2005.
.. [2] T. Akenine-Moeller, E. Haines, N. Hoffman, Real-Time Rendering, 3rd ed., Sec. 9.2.5,
   "Dynamic Computation of Ambient Occlusion: Object-Space Methods", 2008.
"""

from __future__ import annotations

import math
import warnings
import weakref

import numpy as np
import trimesh
from tqdm.auto import tqdm

from .._validate import as_array, as_points, as_unit_vectors, check_bool, check_choice, check_int, check_positive
from ..scenes import Scene, as_scene

__all__ = ["TERMS", "DEFAULT_TERM", "bunnell", "bunnell_gbuffer", "disk_shadow", "shadow_evaluations",
           "vertex_disks", "CostWarning", "estimated_seconds", "COST_WARN_SECONDS"]

#: The shadow terms of :func:`disk_shadow`.
TERMS = ("solid_angle", "gpugems", "form_factor")

#: The default term of :func:`bunnell` (chosen by the measurements of ``docs/objectspace.md``).
DEFAULT_TERM = "gpugems"

#: Listing 14-1's receiver factor ``saturate(4 dot(receiverNormal, v))``: full weight from
#: 14.5 degrees above the receiver's tangent plane up.
GPUGEMS_RECEIVER_GAIN = 4.0

#: Receivers evaluated at once: against every emitter (the exact sum), or walking the tree.
DEFAULT_BLOCK = 512

#: The exact sum evaluates at most this many (receiver, emitter) pairs at once (fewer
#: receivers than ``block`` per step for large meshes; about 100 bytes per pair).
PAIR_BUDGET = 2 ** 18

#: An emitter closer to the receiver than this fraction of the scene extent is the
#: receiver's own disk and casts no shadow (the term is undefined at zero distance).
SELF_DISTANCE = 1e-9

#: A tree node farther from the receiver than this many times its bounding radius is used
#: as one aggregated disk (``hierarchy=True``).
DEFAULT_OPEN_RATIO = 4.0

#: ``max_edge="auto"``: this fraction of the diagonal of the scene's bounding box.
AUTO_EDGE_FRACTION = 1.0 / 32.0

#: :func:`vertex_disks` refuses a ``max_edge`` that would make more triangles than this.
MAX_SUBDIVIDED_FACES = 2_000_000

#: Seconds per shadow term evaluated, for the up-front estimate of :func:`estimated_seconds`:
#: measured 0.5-1.5 microseconds per term on icospheres of 2.6k to 41k disks (one core, the
#: tree, the default block; ``shadow_evaluations`` counted the terms).
SECONDS_PER_TERM = 1e-6

#: Tree nodes a receiver uses per doubling of the disks (``shadow_evaluations / receivers``
#: was 304, 416 and 522 for 2.6k, 10k and 41k disks of an icosphere: about 35 log2(k)).
TERMS_PER_LOG2 = 35.0

#: :func:`bunnell` and :func:`bunnell_gbuffer` warn (:class:`CostWarning`) before a
#: computation estimated to take longer than this, and say how long.
COST_WARN_SECONDS = 60.0


class CostWarning(UserWarning):
    """A Bunnell computation is estimated to take longer than :data:`COST_WARN_SECONDS`."""


# ----------------------------------------------------------------------------- the term


def disk_shadow(receivers, receiver_normals, emitters, emitter_normals, emitter_areas, *,
                term: str = DEFAULT_TERM):
    r"""The shadow of every emitter disk on every receiver point.

    With :math:`\mathbf{e}` the unit vector from the receiver to the emitter, :math:`r` their
    distance, :math:`A` the emitter's area, :math:`\cos\theta_E = -\mathbf{e}\cdot\mathbf{n}_E`
    (positive when the emitter's front faces the receiver) and
    :math:`\cos\theta_R = \mathbf{e}\cdot\mathbf{n}_R`:

    ``"solid_angle"``
        :math:`S = \left(1 - 1/\sqrt{1 + A/(\pi r^2)}\right)\max(0, \cos\theta_E)
        \max(0, \cos\theta_R)`. The first factor is the fraction of the hemisphere's solid
        angle that a disk of area :math:`A = \pi a^2` subtends on axis,
        :math:`1 - r/\sqrt{r^2 + a^2}`; it is the on-axis occlusion of *uniformly* weighted
        AO.
    ``"gpugems"``
        :math:`S = \left(1 - 1/\sqrt{1 + A/(\pi r^2)}\right)\max(0, -\cos\theta_E)
        \,\mathrm{clamp}(4\cos\theta_R, 0, 1)`: Bunnell's Listing 14-1 (the same axis
        factor, the area "already divided by pi"). Two differences from ``"solid_angle"``:
        the receiver cosine is strengthened and saturates at 1 from 14.5 degrees up, and
        the emitter casts its shadow *from its back* (Sec. 14.1: "shadows are cast from
        the back"), so on a closed mesh the far side of an occluder shadows the receiver.
    ``"form_factor"``
        :math:`S = A\max(0, \cos\theta_E)\max(0, \cos\theta_R) / (\pi r^2 + A)`: the
        point-to-disk form factor on axis, :math:`a^2/(r^2 + a^2)`, with the cosines; the
        on-axis occlusion of *cosine*-weighted AO (RTR Eq. 9.14). Twice the solid-angle
        term for a small disk.

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
    term : {"solid_angle", "gpugems", "form_factor"}
        The form above.

    Returns
    -------
    (n, k) float64
        The shadow of emitter j on receiver i, in [0, 1); 0 where the two coincide.

    References
    ----------
    Bunnell 2005 (GPU Gems 2, ch. 14), Sec. 14.2, Listing 14-1 (the element-to-element
    shadow); RTR 3rd ed. Sec. 9.2.5; the disk form factor: RTR Eq. 9.14 integrated over a
    disk seen on axis.

    Examples
    --------
    >>> import numpy as np
    >>> S = disk_shadow([[0, 0, 0]], [[0, 0, 1]], [[0, 0, 1]], [[0, 0, -1]], [np.pi],
    ...                 term="solid_angle")
    >>> round(float(S[0, 0]), 6)  # a unit-radius disk at distance 1: 1 - 1/sqrt(2)
    0.292893
    >>> float(disk_shadow([[0, 0, 0]], [[0, 0, 1]], [[0, 0, 1]], [[0, 0, -1]], [np.pi],
    ...                   term="form_factor")[0, 0])  # a^2 / (d^2 + a^2)
    0.5
    >>> S = disk_shadow([[0, 0, 0]], [[0, 0, 1]], [[0, 0, 1], [0, 0, 1]], [[0, 0, 1], [0, 0, -1]], [np.pi] * 2)
    >>> S.round(6).tolist()  # "gpugems": only the disk whose back faces the receiver casts
    [[0.292893, 0.0]]
    """
    term = check_choice(term, "term", TERMS)
    p_R = as_points(receivers, "receivers")
    n_R = as_unit_vectors(receiver_normals, "receiver_normals", count=len(p_R))
    p_E = as_points(emitters, "emitters")
    n_E = as_unit_vectors(emitter_normals, "emitter_normals", count=len(p_E))
    A = _as_areas(emitter_areas, len(p_E))
    return _shadow(p_R, n_R, p_E, n_E, A, _self_distance(p_R, p_E), term)


# ----------------------------------------------------------------------------- the disks


def vertex_disks(scene, *, max_edge=None):
    """The disks Bunnell places at the vertices of every mesh of ``scene``.

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts.
    max_edge : float, "auto" or None
        Subdivide every mesh first until no edge is longer than this (in the scene's units;
        ``trimesh.remesh.subdivide_to_size``, each long triangle split in four), so that a
        coarse mesh (a box wall of 8 vertices) becomes a surface of many disks. ``"auto"``:
        :data:`AUTO_EDGE_FRACTION` of the diagonal of the scene's bounding box. None: the
        meshes as they are.

    Returns
    -------
    centres : (k, 3) float64
        The vertices, mesh after mesh in the order of ``scene.meshes``.
    normals : (k, 3) float64
        Unit vertex normals (trimesh's face-area weighted means).
    areas : (k,) float64
        A third of the area of the triangles around each vertex (Bunnell 2005, Sec. 14.1;
        they sum to the surface area).

    Examples
    --------
    >>> import trimesh
    >>> c, n, A = vertex_disks(trimesh.creation.box())
    >>> c.shape, round(float(A.sum()), 6)
    ((8, 3), 6.0)
    >>> c, n, A = vertex_disks(trimesh.creation.box(), max_edge=0.3)
    >>> len(c) > 8, round(float(A.sum()), 6)
    (True, 6.0)
    """
    scene = as_scene(scene)
    max_edge = _resolve_max_edge(scene, max_edge)
    centres, normals, areas = [], [], []
    for mesh in scene.meshes.values():
        if max_edge is not None:
            mesh = _subdivided(mesh, max_edge)
        faces = np.asarray(mesh.faces)
        A_face = np.asarray(mesh.area_faces, dtype=np.float64)
        centres.append(np.asarray(mesh.vertices, dtype=np.float64))
        normals.append(np.asarray(mesh.vertex_normals, dtype=np.float64))
        # Bunnell 2005, Sec. 14.1: each triangle gives a third of its area to each corner
        areas.append(np.bincount(faces.ravel(), weights=np.repeat(A_face / 3.0, 3),
                                 minlength=len(mesh.vertices)))
    if not centres:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(centres), np.concatenate(normals), np.concatenate(areas)


# ----------------------------------------------------------------------------- the passes


def bunnell(scene, points=None, normals=None, *, passes: int = 2, term: str = DEFAULT_TERM,
            average: bool = False, hierarchy: bool = True, max_edge=None, block: int = DEFAULT_BLOCK,
            open_ratio: float = DEFAULT_OPEN_RATIO, progress: bool = False) -> np.ndarray:
    r"""Ambient visibility from Bunnell's disks (1 = open).

    Pass 1 sums the shadows of all disks, double shadowing included:
    :math:`V_1(i) = 1 - \sum_j S_{ij}`. Pass :math:`p > 1` weights each emitter by its accessibility
    from the previous pass, :math:`V_p(i) = 1 - \sum_j S_{ij} V_{p-1}(j)` (Bunnell 2005,
    Sec. 14.2): a disk that is itself in shadow is mostly hidden behind the disk that
    shadows it. Each pass is clamped to :math:`[0, 1]`. With ``average``, the result is the mean of
    the last two passes, :math:`(V_{p-1} + V_p)/2`.

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
        Number of passes, >= 1 (Bunnell: 2).
    term : {"solid_angle", "gpugems", "form_factor"}
        The shadow term (:func:`disk_shadow`); default :data:`DEFAULT_TERM`.
    average : bool
        Return the mean of the last two passes (needs ``passes >= 2``): a pass over-darkens
        where the one after under-darkens, and the mean of two consecutive passes is
        closer to the fixed point than either (the remedy that ports of the chapter apply
        after the second pass).
    hierarchy : bool
        Use the tree of aggregated disks (RTR 9.2.5; Bunnell 2005): a binary tree by median
        splits of the disk centres, each node one disk with the sum of its disks' areas,
        their area-weighted mean centre and normal, and (in passes > 1) their area-weighted
        mean accessibility. False: the exact O(n^2) sum over all disks.
    max_edge : float, "auto" or None
        Subdivide the meshes first (:func:`vertex_disks`).
    block : int
        Receivers evaluated at once: against all k disks (at most :data:`PAIR_BUDGET` pairs
        at once, fewer receivers for a large k), or walking the tree.
    open_ratio : float
        With ``hierarchy``: a node is used as one disk when the receiver is farther from
        its centre than ``open_ratio`` times its bounding radius; else its children are.
        ``np.inf`` reproduces the exact sum.
    progress : bool
        A tqdm progress bar over the receivers of every pass (default False, as everywhere
        in vobscure).

    Returns
    -------
    (n,) float64
        Visibility in [0, 1]: per vertex (of the subdivided meshes with ``max_edge``) when
        ``points`` is None, else per point.

    Warns
    -----
    CostWarning
        Before a computation estimated (as :func:`estimated_seconds`) to take longer than
        :data:`COST_WARN_SECONDS`, with the estimate.

    Notes
    -----
    **Cost**: k disks (the vertices). A pass over n receivers evaluates n k shadow terms
    with ``hierarchy=False`` and about :data:`TERMS_PER_LOG2` n log2(k) with the tree;
    ``passes - 1`` per-vertex passes (n = k) come first, so the whole is O(passes k log k)
    (O(passes k^2) exact) plus the receivers' own gather, at about :data:`SECONDS_PER_TERM`
    per term: a 2M-triangle mesh (10^6 disks) takes about 12 minutes for two passes on one
    core. :func:`estimated_seconds` gives the estimate, :func:`shadow_evaluations` the count.

    With a :class:`~vobscure.scenes.Scene` object, the disks, the tree and the per-vertex
    passes are kept while the scene lives (per ``max_edge``, term and tree options) and
    shared with :func:`bunnell_gbuffer`: calls with other receivers or more passes reuse
    them. A mesh or a path is converted afresh on every call and nothing is kept.

    References
    ----------
    Bunnell 2005, GPU Gems 2, ch. 14, Sec. 14.2; RTR 3rd ed. Sec. 9.2.5. The shadow terms
    are :func:`disk_shadow`'s.

    Examples
    --------
    >>> import vobscure as vo
    >>> V = bunnell(vo.scenes.get("crease"))
    >>> V.shape, bool(((0 <= V) & (V <= 1)).all())
    ((12,), True)
    """
    opts = _options(passes, term, average, hierarchy, block, open_ratio)
    progress = check_bool(progress, "progress")
    cache = isinstance(scene, Scene)
    scene = as_scene(scene)
    if points is None:
        if normals is not None:
            raise ValueError("normals were given without points; pass both, or neither for "
                             "the per-vertex visibility")
    else:
        if normals is None:
            raise ValueError("normals is required when points is given")
        points = as_points(points, "points")
        normals = as_unit_vectors(normals, "normals", count=len(points))
    state = _state(scene, max_edge, opts, cache)
    work = _warn_cost(state, 0 if points is None else len(points), opts[0])
    with tqdm(total=work, desc="Bunnell disks", unit="receiver", disable=not progress, leave=False) as bar:
        return state.evaluate(points, normals, passes=opts[0], bar=bar)


def bunnell_gbuffer(gbuffer, *, scene, passes: int = 2, term: str = DEFAULT_TERM, average: bool = False,
                    hierarchy: bool = True, max_edge=None, open_ratio: float = DEFAULT_OPEN_RATIO,
                    block: int = DEFAULT_BLOCK, radius=None, normal_clamp: bool = False, thickness=None,
                    falloff: str = "constant", seed=0, progress: bool = False) -> np.ndarray:
    """Bunnell's disk AO at every covered pixel of a G-buffer.

    The receivers are the pixels' world positions and normals (``gbuffer.world_position``,
    ``gbuffer.world_normal`` where ``gbuffer.valid``); the emitters are the scene's disks
    with their accessibilities from the per-vertex passes. Those passes depend only on the
    scene and the options, so they are computed once per scene object and options and kept
    while the scene lives (a sample sweep calls this many times for one scene).

    Parameters
    ----------
    gbuffer : GBuffer
        Of ``scene``.
    scene : Scene
        The scene the G-buffer shows.
    passes, term, average, hierarchy, max_edge, open_ratio, block
        As for :func:`bunnell`.
    radius, normal_clamp, thickness, falloff, seed
        Accepted for the estimators' common signature and not used: the disks' AO has no
        radius (it estimates the visibility of the whole sky) and is deterministic.
    progress : bool
        A tqdm progress bar over the receivers of every pass, the per-vertex passes
        included (default False).

    Returns
    -------
    (H, W) float64
        Visibility in [0, 1], NaN on background.

    Warns
    -----
    CostWarning
        Before a computation estimated to take longer than :data:`COST_WARN_SECONDS`.

    Notes
    -----
    The cost is :func:`bunnell`'s: the per-vertex passes, O(passes k log k) for k disks
    with the tree (O(passes k^2) exact), dominate; the pixels add about
    :data:`TERMS_PER_LOG2` log2(k) terms each. A 64 x 64 frame of a 2M-triangle mesh
    (10^6 disks) is estimated at about 12 minutes (:func:`estimated_seconds`); the warning
    says so before the work starts, and the passes are then kept for later frames.

    References
    ----------
    Bunnell 2005, GPU Gems 2, ch. 14; RTR 3rd ed. Sec. 9.2.5.

    Examples
    --------
    >>> import vobscure as vo
    >>> scene = vo.scenes.get("crease")
    >>> cam = vo.Camera.look_at((1, 1, 2), (0, 0, 0), size=(8, 6), fov_y=50.0)
    >>> V = bunnell_gbuffer(vo.render_gbuffer(scene, cam), scene=scene)
    >>> V.shape, bool((V[~np.isnan(V)] <= 1).all())
    ((6, 8), True)
    """
    opts = _options(passes, term, average, hierarchy, block, open_ratio)
    progress = check_bool(progress, "progress")
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a vobscure Scene (the one the G-buffer shows), got "
                         f"{type(scene).__name__}")

    def disks(x, n):
        x = as_points(x, "gbuffer.world_position")
        n = as_unit_vectors(n, "gbuffer.world_normal", count=len(x))
        state = _state(scene, max_edge, opts, True)
        work = _warn_cost(state, len(x), opts[0])
        with tqdm(total=work, desc="Bunnell disks", unit="receiver", disable=not progress, leave=False) as bar:
            return state.evaluate(x, n, passes=opts[0], bar=bar)

    return gbuffer.per_pixel(disks)


def shadow_evaluations(scene, points=None, normals=None, *, hierarchy: bool = True, max_edge=None,
                       open_ratio: float = DEFAULT_OPEN_RATIO) -> int:
    """The number of shadow terms one pass of :func:`bunnell` evaluates (its cost).

    The exact sum evaluates every (receiver, disk) pair; the tree evaluates one term per
    (receiver, node) pair it uses, leaves included.

    Parameters
    ----------
    scene, points, normals, hierarchy, max_edge, open_ratio
        As for :func:`bunnell`.

    Returns
    -------
    int

    Examples
    --------
    >>> import trimesh
    >>> sphere = trimesh.creation.icosphere(subdivisions=2)
    >>> shadow_evaluations(sphere, hierarchy=False) == len(sphere.vertices) ** 2
    True
    >>> shadow_evaluations(sphere) < len(sphere.vertices) ** 2
    True
    """
    hierarchy = check_bool(hierarchy, "hierarchy")
    open_ratio = check_positive(open_ratio, "open_ratio", allow_inf=True)
    scene = as_scene(scene)
    p_E, n_E, A = vertex_disks(scene, max_edge=max_edge)
    if points is None:
        p_R = p_E
    else:
        p_R = as_points(points, "points")
        if normals is None:
            raise ValueError("normals is required when points is given")
        as_unit_vectors(normals, "normals", count=len(p_R))
    if not hierarchy:
        return len(p_R) * len(p_E)
    return _traverse(p_R, _Tree(p_E, n_E, A), open_ratio, None)[0]


def _terms_per_receiver(k: int, hierarchy: bool) -> float:
    """Shadow terms one receiver costs against k disks: k exactly, or the tree's estimate."""
    if not hierarchy:
        return float(k)
    return float(min(k, TERMS_PER_LOG2 * max(1.0, math.log2(max(k, 2)))))


def estimated_seconds(disks: int, receivers: int, *, passes: int = 2, hierarchy: bool = True,
                      average: bool = False) -> float:
    """The up-front estimate of a :func:`bunnell_gbuffer` (or :func:`bunnell`) computation.

    Parameters
    ----------
    disks : int
        k, the disks (the meshes' vertices, after ``max_edge``).
    receivers : int
        The points (a G-buffer's covered pixels); the disks themselves are the receivers of
        the per-vertex passes.
    passes, hierarchy, average
        As for :func:`bunnell`.

    Returns
    -------
    float
        Seconds: terms x :data:`SECONDS_PER_TERM`; the terms are those of ``passes - 1``
        per-vertex passes (k receivers each) and of the receivers' own gather (two with
        ``average``), each receiver costing k terms (exact sum) or about
        :data:`TERMS_PER_LOG2` log2(k) (the tree). An estimate within a factor of a few: the
        tree's cost depends on the geometry, the time per term on the machine.

    Examples
    --------
    >>> round(estimated_seconds(1_000_000, 4096))     # a 2M-triangle mesh: about 700 terms per receiver
    700
    """
    k, n = check_int(disks, "disks", minimum=0), check_int(receivers, "receivers", minimum=0)
    per = _terms_per_receiver(k, check_bool(hierarchy, "hierarchy"))
    vertex_passes = max(0, check_int(passes, "passes") - 1)
    gathers = 2 if check_bool(average, "average") else 1
    return (vertex_passes * k + gathers * n) * per * SECONDS_PER_TERM


def _warn_cost(state, receivers: int, passes: int) -> float:
    """Warn (:class:`CostWarning`) when the passes still to compute are estimated to take
    longer than :data:`COST_WARN_SECONDS`; return the receivers the bar will count."""
    k = len(state.p_E)
    needed = passes if receivers == 0 else passes - 1       # per-vertex passes the result needs
    missing = max(0, needed - (len(state.W) - 1))
    work = missing * k + (0 if receivers == 0 else (2 if state.average else 1) * receivers)
    seconds = work * _terms_per_receiver(k, state.hierarchy) * SECONDS_PER_TERM
    if seconds > COST_WARN_SECONDS:
        warnings.warn(f"Bunnell's disks: {k} disks, {missing} per-vertex pass(es) of {k} receivers and "
                      f"{receivers} other receivers, about {seconds / 60:.1f} minutes (estimated at "
                      f"{SECONDS_PER_TERM:g} s per shadow term, hierarchy={state.hierarchy}); pass progress=True "
                      f"for a progress bar, or coarsen the mesh", CostWarning, stacklevel=3)
    return work


# ----------------------------------------------------------------------------- helpers


_STATES: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _options(passes, term, average, hierarchy, block, open_ratio) -> tuple:
    """Validated (passes, term, average, hierarchy, block, open_ratio)."""
    passes = check_int(passes, "passes", minimum=1)
    term = check_choice(term, "term", TERMS)
    average, hierarchy = check_bool(average, "average"), check_bool(hierarchy, "hierarchy")
    if average and passes < 2:
        raise ValueError("average needs passes >= 2 (it is the mean of the last two passes)")
    block = check_int(block, "block", minimum=1)
    open_ratio = check_positive(open_ratio, "open_ratio", allow_inf=True)
    return passes, term, bool(average), bool(hierarchy), block, open_ratio


def _state(scene, max_edge, opts, cache: bool) -> "_State":
    """The scene's disks, tree and passes for these options; with ``cache``, made once per
    Scene object and options and kept while the scene lives (the method's precomputation)."""
    max_edge = _resolve_max_edge(scene, max_edge)
    if not cache:
        return _State(scene, max_edge, opts)
    per_scene = _STATES.setdefault(scene, {})
    key = (max_edge,) + opts[1:]           # every option but the number of passes
    if key not in per_scene:
        per_scene[key] = _State(scene, max_edge, opts)
    return per_scene[key]


class _State:
    """A scene's disks, their tree and their accessibility after each pass (grown on demand)."""

    def __init__(self, scene, max_edge, opts):
        self.passes, self.term, self.average, self.hierarchy, self.block, self.open_ratio = opts
        self.p_E, self.n_E, self.A = vertex_disks(scene, max_edge=max_edge)
        self.eps = _self_distance(self.p_E, self.p_E)
        self.tree = _Tree(self.p_E, self.n_E, self.A) if self.hierarchy else None
        # W[p]: the disks' accessibility after pass p (W[0] = 1: pass 1 weights every disk fully)
        self.W = [np.ones(len(self.p_E))]

    def _gather(self, p, n, V_E, eps, bar=None):
        if self.tree is not None:
            return _gather_tree(p, n, self.tree, V_E, self.open_ratio, eps, self.term, self.block, bar)
        return _gather(p, n, self.p_E, self.n_E, self.A, V_E, self.block, eps, self.term, bar)

    def weights(self, p: int, bar=None) -> np.ndarray:
        """The disks' accessibility after pass p (computed once)."""
        while len(self.W) <= p:
            # Bunnell 2005, Sec. 14.2: the next pass weights each emitter by its accessibility
            self.W.append(self._gather(self.p_E, self.n_E, self.W[-1], self.eps, bar))
        return self.W[p]

    def evaluate(self, points, normals, passes=None, bar=None) -> np.ndarray:
        P = self.passes if passes is None else passes
        if points is None:
            V = self.weights(P, bar)
            return 0.5 * (V + self.weights(P - 1, bar)) if self.average else V.copy()
        eps = _self_distance(points, self.p_E)
        V = self._gather(points, normals, self.weights(P - 1, bar), eps, bar)
        if self.average:
            V = 0.5 * (V + self._gather(points, normals, self.weights(P - 2, bar), eps, bar))
        return V


def _resolve_max_edge(scene, max_edge):
    if max_edge is None:
        return None
    if isinstance(max_edge, str):
        if max_edge != "auto":
            raise ValueError(f"max_edge must be a positive length, 'auto' or None, got {max_edge!r}")
        lo, hi = np.asarray(scene.bounds, dtype=np.float64)
        return AUTO_EDGE_FRACTION * float(np.linalg.norm(hi - lo))
    return check_positive(max_edge, "max_edge")


def _subdivided(mesh, max_edge: float):
    """``mesh`` with every edge at most ``max_edge`` long (triangles split in four)."""
    edges = np.asarray(mesh.edges_unique_length, dtype=np.float64)
    longest = float(edges.max()) if len(edges) else 0.0
    if longest <= max_edge:
        return mesh
    halvings = int(np.ceil(np.log2(longest / max_edge)))
    # at most 4 triangles per face and halving; refuse what would not fit in memory
    if len(mesh.faces) * 4.0 ** halvings > MAX_SUBDIVIDED_FACES:
        raise ValueError(f"max_edge={max_edge:g} would split the mesh's {len(mesh.faces)} triangles "
                         f"(longest edge {longest:g}) into up to {len(mesh.faces) * 4 ** halvings} > "
                         f"{MAX_SUBDIVIDED_FACES}; choose a larger max_edge")
    v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge, max_iter=halvings + 1)
    return trimesh.Trimesh(v, f, process=True)


def _as_areas(value, count: int) -> np.ndarray:
    A = as_array(value, "emitter_areas", shape=(count,))
    if np.any(A < 0):
        raise ValueError(f"emitter_areas must be >= 0; {int(np.count_nonzero(A < 0))} are negative")
    return A


def _self_distance(p_R: np.ndarray, p_E: np.ndarray) -> float:
    both = np.concatenate([p_R, p_E]) if len(p_R) + len(p_E) else np.zeros((1, 3))
    extent = float(np.linalg.norm(both.max(axis=0) - both.min(axis=0)))
    return SELF_DISTANCE * max(extent, 1.0)


def _term(cos_E, cos_R, r2, A, term):
    """The shadow term from cos_E = -e.n_E, cos_R = e.n_R, r^2 and A (same shapes)."""
    if term == "form_factor":
        # the point-to-disk form factor on axis, a^2 / (r^2 + a^2), times the two cosines
        return A * np.clip(cos_E, 0.0, None) * np.clip(cos_R, 0.0, None) / (np.pi * r2 + A)
    # on-axis solid-angle fraction of a disk of area A at distance r (Bunnell 2005, Listing 14-1)
    omega = 1.0 - 1.0 / np.sqrt(1.0 + A / (np.pi * r2))
    if term == "gpugems":
        # Listing 14-1: saturate(dot(n_E, v)) casts from the back; saturate(4 dot(n_R, v))
        return omega * np.clip(-cos_E, 0.0, None) * np.clip(GPUGEMS_RECEIVER_GAIN * cos_R, 0.0, 1.0)
    return omega * np.clip(cos_E, 0.0, None) * np.clip(cos_R, 0.0, None)


def _shadow(p_R, n_R, p_E, n_E, A, eps, term) -> np.ndarray:
    """(n, k) shadow terms, float64; see :func:`disk_shadow`."""
    v = p_E[None, :, :] - p_R[:, None, :]           # receiver -> emitter
    r2 = np.einsum("ijk,ijk->ij", v, v)
    coincide = r2 <= eps * eps
    r2 = np.where(coincide, 1.0, r2)
    e = v / np.sqrt(r2)[..., None]
    S = _term(-np.einsum("ijk,jk->ij", e, n_E), np.einsum("ijk,ik->ij", e, n_R), r2, A[None, :], term)
    S[coincide] = 0.0
    return S


def _gather(p_R, n_R, p_E, n_E, A, V_E, block, eps, term, bar=None) -> np.ndarray:
    """V(i) = clip(1 - sum_j S_ij V_E(j), 0, 1), receivers in blocks of ``block``; ``bar``
    (a tqdm bar or None) counts the receivers done."""
    V = np.empty(len(p_R))
    block = min(block, max(1, PAIR_BUDGET // max(len(p_E), 1)))
    for start in range(0, len(p_R), block):
        sl = slice(start, start + block)
        V[sl] = 1.0 - _shadow(p_R[sl], n_R[sl], p_E, n_E, A, eps, term) @ V_E
        if bar is not None:
            bar.update(len(V[sl]))
    return np.clip(V, 0.0, 1.0)


class _Tree:
    """Binary tree of aggregated disks: one subtree per group of normals (the axis and sign of
    their largest component), each by median splits along its longest axis.

    Nodes 0..k-1 are the disks themselves; internal nodes follow, each after its two
    children. ``children[i]`` is (left, right), (-1, -1) for a disk. Each node is one disk:
    the sum of its disks' areas, their area-weighted mean centre and unit mean normal (zero
    when the normals cancel: such a node casts nothing), and a bounding radius that holds
    every disk under it (centre distance plus the disk's own radius).
    """

    def __init__(self, p_E, n_E, A):
        k = len(p_E)
        self.k = k
        left, right, height = [], [], []

        def build(idx):
            if len(idx) == 1:
                return int(idx[0]), 0
            pts = p_E[idx]
            axis = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
            order = idx[np.argsort(pts[:, axis], kind="stable")]
            half = len(order) // 2
            (l, hl), (r, hr) = build(order[:half]), build(order[half:])
            left.append(l)
            right.append(r)
            height.append(1 + max(hl, hr))
            return k + len(left) - 1, height[-1]

        def join(a, b):
            left.append(a[0])
            right.append(b[0])
            height.append(1 + max(a[1], b[1]))
            return k + len(left) - 1, height[-1]

        # Disks facing opposite ways (the two sides of a thin wall) must not share a node:
        # their mean normal cancels and the node would cast nothing. So the disks are first
        # grouped by the axis and sign of their normal's largest component, one subtree each,
        # and the groups are joined only at the top, where no receiver in the scene is far
        # enough to use a node as one disk.
        axis = np.argmax(np.abs(n_E), axis=1) if k else np.zeros(0, dtype=np.intp)
        group = 2 * axis + (n_E[np.arange(k), axis] < 0)
        subtrees = [build(np.flatnonzero(group == g)) for g in range(6) if np.any(group == g)]
        while len(subtrees) > 1:
            subtrees = [join(*subtrees[i:i + 2]) if i + 1 < len(subtrees) else subtrees[i]
                        for i in range(0, len(subtrees), 2)]
        self.root = subtrees[0][0] if k else -1
        m = k + len(left)
        self.children = np.full((m, 2), -1, dtype=np.intp)
        self.children[k:, 0], self.children[k:, 1] = left, right
        self.height = np.concatenate([np.zeros(k, dtype=np.intp), np.asarray(height, dtype=np.intp)])
        self.area = np.zeros(m)
        self.area[:k] = A
        self.centre = np.zeros((m, 3))
        self.centre[:k] = p_E
        normal_sum = np.zeros((m, 3))
        normal_sum[:k] = A[:, None] * n_E
        self.radius = np.zeros(m)
        self.radius[:k] = np.sqrt(A / np.pi)
        self.levels = [np.flatnonzero(self.height == h) for h in range(1, int(self.height.max(initial=0)) + 1)]
        for nodes in self.levels:       # children before parents, one vectorized level at a time
            l, r = self.children[nodes, 0], self.children[nodes, 1]
            self.area[nodes] = self.area[l] + self.area[r]
            w_l = np.where(self.area[nodes] > 0, self.area[l] / np.maximum(self.area[nodes], 1e-300), 0.5)
            self.centre[nodes] = w_l[:, None] * self.centre[l] + (1.0 - w_l)[:, None] * self.centre[r]
            normal_sum[nodes] = normal_sum[l] + normal_sum[r]
            self.radius[nodes] = np.maximum(
                np.linalg.norm(self.centre[l] - self.centre[nodes], axis=1) + self.radius[l],
                np.linalg.norm(self.centre[r] - self.centre[nodes], axis=1) + self.radius[r])
        length = np.linalg.norm(normal_sum, axis=1, keepdims=True)
        self.normal = np.where(length > 1e-12 * np.maximum(self.area, 1e-300)[:, None],
                               normal_sum / np.maximum(length, 1e-300), 0.0)

    def accessibility(self, V_E):
        """Each node's area-weighted mean accessibility of its disks (1 for a node of no area)."""
        weighted = np.zeros(len(self.area))
        weighted[:self.k] = self.area[:self.k] * V_E
        for nodes in self.levels:
            weighted[nodes] = weighted[self.children[nodes, 0]] + weighted[self.children[nodes, 1]]
        return np.where(self.area > 0, weighted / np.maximum(self.area, 1e-300), 1.0)


def _traverse(p_R, tree, open_ratio, visit, block=DEFAULT_BLOCK, bar=None):
    """Walk the tree for every receiver as a vectorized frontier of (receiver, node) pairs;
    ``visit(receivers, nodes)`` is called on the pairs used as one disk. Returns their count.
    ``bar`` (a tqdm bar or None) counts the receivers done."""
    count = 0
    if tree.root < 0 or not len(p_R):
        return count, None
    # receivers in blocks, so that the frontier's memory does not grow with the receivers
    for start in range(0, len(p_R), block):
        r_idx = np.arange(start, min(start + block, len(p_R)))
        node = np.full(len(r_idx), tree.root, dtype=np.intp)
        while len(r_idx):
            d = np.linalg.norm(p_R[r_idx] - tree.centre[node], axis=1)
            use = (node < tree.k) | (d > open_ratio * tree.radius[node])
            count += int(np.count_nonzero(use))
            if visit is not None:
                visit(r_idx[use], node[use])
            r_idx, node = r_idx[~use], node[~use]
            r_idx = np.concatenate([r_idx, r_idx])
            node = np.concatenate([tree.children[node, 0], tree.children[node, 1]])
        if bar is not None:
            bar.update(min(block, len(p_R) - start))
    return count, None


def _gather_tree(p_R, n_R, tree, V_E, open_ratio, eps, term, block, bar=None) -> np.ndarray:
    """The hierarchical form of :func:`_gather`."""
    total = np.zeros(len(p_R))
    V_node = tree.accessibility(V_E)

    def visit(ri, ni):
        S = _shadow_pairs(p_R[ri], n_R[ri], tree.centre[ni], tree.normal[ni], tree.area[ni], eps, term)
        total[:] += np.bincount(ri, weights=S * V_node[ni], minlength=len(p_R))

    _traverse(p_R, tree, open_ratio, visit, block, bar)
    return np.clip(1.0 - total, 0.0, 1.0)


def _shadow_pairs(p_R, n_R, p_E, n_E, A, eps, term) -> np.ndarray:
    """(n,) shadow terms of emitter i on receiver i; see :func:`disk_shadow`."""
    v = p_E - p_R
    r2 = np.einsum("ij,ij->i", v, v)
    coincide = r2 <= eps * eps
    r2 = np.where(coincide, 1.0, r2)
    e = v / np.sqrt(r2)[:, None]
    S = _term(-np.einsum("ij,ij->i", e, n_E), np.einsum("ij,ij->i", e, n_R), r2, A, term)
    return np.where(coincide, 0.0, S)
