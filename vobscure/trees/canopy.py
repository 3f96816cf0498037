r"""Ambient visibility inside a tree's canopy: Hegeman et al. 2006, Sec. 3 (Eqs. 4-6).

A point :math:`x` with normal :math:`n` inside a shell of occluders: the plane through
:math:`x` with normal :math:`n` cuts off a spherical cap of height :math:`h` on the normal's
side; the visibility is the probability of seeing no occluder in a Poisson field whose mean
count is the cap's volume times the density, reduced by the off-centre factor :math:`f`:

.. math::

    V_{cap} = \frac{\pi h^2 (3R - h)}{3} \quad \text{(Eq. 4)}, \qquad
    f = \frac{h^2}{h^2 + d^2} \quad \text{(Eq. 5)}, \qquad
    V = e^{-\alpha \rho f V_{cap}} \quad \text{(Eq. 6)}

Ellipsoids are mapped to the unit sphere first (points directly, normals by the inverse
transpose). Also here: the Reeves & Blau 1985 baseline the paper compares with, the density
:math:`\alpha\rho` fitted to a reference visibility (the "one-time preprocessing step" of
Sec. 4), and the density predicted from leaf statistics by the Poisson argument of Sec. 3
(derived in ``docs/trees.md``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from .._validate import as_array, check_int, check_positive
from ._arrays import ZERO_NORMAL, as_raw_points, check_normal_lengths, out_dtype
from .poisson import extinction
from .shells import Ellipsoid, MultiShell, Sphere

__all__ = ["canopy_visibility", "reeves_blau", "fit_density", "fit_reeves_blau", "predict_density",
           "optical_depth"]

#: Points evaluated at once by ``canopy_visibility``: bounds the temporaries (about
#: 30 float64 values per point, 15 MiB) whatever the number of points.
DEFAULT_CHUNK = 1 << 16
#: Range of the fitted density's search, as optical depths alpha*rho*tau: below
#: FIT_TAU_MIN the visibility is 1 to 1e-8 everywhere, above FIT_TAU_MAX it is 0 to
#: exp(-50) at every point that sees the shell at all.
FIT_TAU_MIN = 1e-8
FIT_TAU_MAX = 50.0
#: Gauss-Newton polish of the fitted density: stop once a step is this small relative.
FIT_RTOL = 1e-14
FIT_MAX_STEPS = 50
#: Fewest points of the log-density grid that brackets the fit's search.
FIT_GRID = 241
#: Largest step of that grid in log(density). One point's visibility exp(-density tau) falls
#: from 0.9 to 0.1 while log(density) grows by log(ln 10 / ln(10 / 9)) = 3.1, so every
#: dip of the loss is at least about that wide; a step of 0.25 puts a dozen grid points in
#: it. Optical depths over many decades widen the range (up to ~1500 in log), and a fixed
#: count of FIT_GRID points would step over a dip and pick a worse one.
FIT_GRID_STEP = 0.25
#: Bounds of log(k) in the fit of Reeves-Blau's k (k in 1/length; the scenes are metres-ish),
#: the points of its log-spaced grid and the Brent tolerance in log(k).
LOG_K_BOUNDS = (math.log(1e-4), math.log(1e4))
K_GRID = 33
K_XATOL = 1e-6


# ----------------------------------------------------------------------------- validation
#: How far outside [0, 1] a reference given to the fits may stray: a noisy reference (a
#: Monte Carlo estimate, a reference with measurement noise of a few hundredths) does, and
#: still fits correctly; further out the values are not visibilities (all -1, say).
REFERENCE_SLACK = 0.1


def _check_shell(shell, name: str = "shell", *, multi: bool = True):
    kinds = (Sphere, Ellipsoid, MultiShell) if multi else (Sphere, Ellipsoid)
    if not isinstance(shell, kinds):
        want = "a Sphere, an Ellipsoid or a MultiShell" if multi else "a Sphere or an Ellipsoid"
        raise ValueError(f"{name} must be {want}, got {type(shell).__name__}")
    return shell


# ----------------------------------------------------------------------------- the model
def _cap_optical_depth(x: np.ndarray, m: np.ndarray) -> np.ndarray:
    """f * V_cap in the unit frame (R = 1, c = 0): (k,) float64 in [0, 4 pi / 3].

    ``m`` are the normals in the unit frame, of any non-zero length: with n = m / |m|,
    n.x = (m.x) / |m| and the in-plane distance d^2 = |x|^2 - (n.x)^2, so no unit normals
    are formed (one pass fewer over three components).

    Far points are computed stably: each x is divided by s = max(1, max_i |x_i|) before the
    squares are formed, and f = (h/s)^2 / ((d/s)^2 + (h/s)^2) is the same ratio, so d^2 never
    overflows (s = 1, an exact division, for every point within a few radii of the shell)."""
    if not np.all(np.isfinite(x)):
        raise ValueError(f"points must be finite and not so far from the shell that their coordinates in its "
                         f"unit frame overflow; {int(np.count_nonzero(~np.all(np.isfinite(x), axis=1)))} "
                         f"point(s) do")
    mm = np.einsum("ij,ij->i", m, m)
    check_normal_lengths(mm)
    s = np.max(np.abs(x), axis=1)
    np.maximum(s, 1.0, out=s)
    x = x / s[:, None]                                            # x / s, every coordinate in [-1, 1]
    n_dot_x = np.einsum("ij,ij->i", m, x)
    n_dot_x /= np.sqrt(mm)                                        # n.(x - c) / s, R = 1
    d2 = np.einsum("ij,ij->i", x, x)
    d2 -= n_dot_x * n_dot_x                                       # (d / s)^2, distance to the disk's centre
    np.maximum(d2, 0.0, out=d2)
    n_dot_x *= s
    h = np.subtract(1.0, n_dot_x, out=n_dot_x)
    np.clip(h, 0.0, 2.0, out=h)                                   # h = R - n.(x - c), clamped to [0, 2R]
    h2 = h * h
    V_cap = np.pi / 3.0 * h2 * (3.0 - h)                          # Hegeman 2006, Eq. 4 (R = 1)
    h_s = h / s
    h_s2 = h_s * h_s                                              # (h / s)^2
    den = d2
    den += h_s2
    f = np.divide(h_s2, den, out=np.ones_like(h2), where=den > 0)  # Hegeman 2006, Eq. 5 (f = 1 at h = d = 0)
    V_cap *= f
    return V_cap


def _shell_optical_depth(points: np.ndarray, normals: np.ndarray, shell) -> np.ndarray:
    """f * V_cap in world volume (the unit frame's times ``volume_scale``), float64 (m,)."""
    if isinstance(shell, Sphere):
        with np.errstate(over="ignore"):             # an overflow is reported by _cap_optical_depth
            x = shell.to_unit(points)
        m = np.asarray(normals, dtype=np.float64)    # a sphere's map keeps directions
    else:
        # the ellipsoid's map x -> diag(radii)^-1 Q^T (x - c) and, for normals, its inverse
        # transpose n -> diag(radii) Q^T n (Sec. 3), each as one (3, 3) product; the normals'
        # lengths are left to _cap_optical_depth
        A = shell.rotation / shell.radii
        with np.errstate(over="ignore", invalid="ignore"):   # non-finite results are reported below
            x = np.asarray(points, dtype=np.float64) @ A
            x -= shell.center @ A
        if not np.all(np.isfinite(x)):
            raise ValueError(f"points must be finite; they hold {int(np.count_nonzero(~np.isfinite(x)))} NaN "
                             f"or inf value(s)")
        m = np.asarray(normals, dtype=np.float64) @ (shell.rotation * shell.radii)
    tau = _cap_optical_depth(x, m)
    tau *= shell.volume_scale
    return tau


def _chunk_optical_depth(points: np.ndarray, normals: np.ndarray, shell) -> np.ndarray:
    if not isinstance(shell, MultiShell):
        return _shell_optical_depth(points, normals, shell)
    which = shell.assign(points)
    tau = np.empty(points.shape[0])
    for i, s in enumerate(shell.shells):
        sel = which == i
        if np.any(sel):
            tau[sel] = _shell_optical_depth(points[sel], normals[sel], s)
    return tau


def _checked_inputs(points, normals, shell, chunk):
    _check_shell(shell)
    chunk = check_int(chunk, "chunk")
    P = as_raw_points(points, "points")
    N = as_raw_points(normals, "normals")
    if N.shape[0] != P.shape[0]:
        raise ValueError(f"normals must have one row per point ({P.shape[0]}), got {N.shape[0]}")
    return P, N, chunk


def _chunked_optical_depth(P, N, shell, chunk):
    """Yield (slice, tau) over chunks of at most ``chunk`` points."""
    for i in range(0, P.shape[0], chunk):
        sl = slice(i, min(i + chunk, P.shape[0]))
        yield sl, _chunk_optical_depth(P[sl], N[sl], shell)


def optical_depth(points, normals, shell, *, chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    """(n,) the exponent of Eq. 6 per unit density: ``f V_cap``, in world volume.

    ``canopy_visibility(..., density=a) == exp(-a * optical_depth(...))``; parameters as
    there. Float64 whatever the input dtype.

    Examples
    --------
    >>> tau = optical_depth([[0.0, 0, 0]], [[0, 1.0, 0]], Sphere((0, 0, 0), 1.0))
    >>> bool(np.isclose(tau[0], 2 * np.pi / 3))           # f = 1, V_cap = 2 pi R^3 / 3
    True
    """
    P, N, chunk = _checked_inputs(points, normals, shell, chunk)
    tau = np.empty(P.shape[0])
    for sl, tau_chunk in _chunked_optical_depth(P, N, shell, chunk):
        tau[sl] = tau_chunk
    return tau


def canopy_visibility(points, normals, shell, *, density: float, chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    r"""Ambient visibility at points of a tree's canopy (Hegeman et al. 2006, Eqs. 4-6).

    Parameters
    ----------
    points : (n, 3) float
        Shading points x, world units, finite. A single (3,) point is accepted.
    normals : (n, 3) float
        Their normals n (renormalized; zero-length ones are rejected).
    shell : Sphere, Ellipsoid or MultiShell
        The canopy's shell. With a MultiShell each point uses the shell with the closest
        centre (Sec. 5).
    density : float, keyword-only
        The paper's alpha*rho product, >= 0, per unit *world* volume (see Notes).
    chunk : int, keyword-only
        Points evaluated at once (default ``DEFAULT_CHUNK``); the memory beyond the output is
        O(chunk) whatever n, so 10^7 points are fine.

    Returns
    -------
    (n,) float32 or float64
        V in [0, 1]: float32 when ``points`` and ``normals`` are both float32 (computed in
        float64), float64 otherwise. Never NaN.

    Raises
    ------
    ValueError
        Bad shapes, NaN/inf in ``points`` or ``normals``, a zero normal, a negative or
        non-finite ``density``, or a ``shell`` of another type.

    Notes
    -----
    Computed in the shell's unit frame (the affine map taking the shell to the unit sphere,
    Sec. 3; a sphere's is :math:`(x - c) / R`), with :math:`R = 1` and :math:`c = 0` there:

    - :math:`h = R - n \cdot (x - c)`, clamped to :math:`[0, 2R]`: 0 when the plane leaves
      the shell entirely behind the normal (then :math:`V = 1`), :math:`2R` when the whole
      shell lies on the normal's side.
    - :math:`d` is the distance from :math:`x` to the foot of the centre's projection on the
      plane (the centre of the cutting disk), :math:`\lVert (x - c) - (n \cdot (x - c))\, n
      \rVert`, never clamped; :math:`f = 1` when :math:`h = d = 0`.
    - Points outside the shell follow the same formulas: :math:`V = 1` when the plane misses
      the shell on the normal's side, otherwise the cap (or the whole shell) attenuated by
      :math:`f`, which decreases as :math:`x` moves away sideways. :math:`V` is continuous in
      :math:`x`.

    **Density of an ellipsoid**: :math:`V_{cap}` is computed in the unit frame and multiplied
    by the ellipsoid's volume scale :math:`a b c` (the Jacobian of the map), so
    :math:`V_{cap}` is the cap's true world volume and ``density`` is always per unit world
    volume; an Ellipsoid with three equal radii gives the Sphere's result. :math:`f` is the
    unit frame's (a ratio, unitless).

    Stability: :math:`V_{cap}` is in :math:`[0, 4\pi/3]` in the unit frame, so the exponent
    never overflows for finite shells and densities; ``exp`` of a huge exponent underflows
    quietly to 0, and ``density = 0`` gives exactly 1.

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3, Eqs. 4, 5 and 6, Fig. 1 (the cap), Fig. 3 (several shells, ellipsoid).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> V = canopy_visibility([[0, 0, 0], [0, 1, 0], [0, 1, 0]], [[0, 1, 0], [0, 1, 0], [0, -1, 0]],
    ...                       s, density=1.5)
    >>> V.round(6)                      # centre: exp(-1.5 * 2 pi / 3); top facing out: 1; facing in
    array([0.043214, 1.      , 0.001867])
    """
    density = check_positive(density, "density", allow_zero=True)
    P, N, chunk = _checked_inputs(points, normals, shell, chunk)
    out = np.empty(P.shape[0], dtype=out_dtype(P, N))
    for sl, tau in _chunked_optical_depth(P, N, shell, chunk):  # tau = f V_cap, world volume
        with np.errstate(over="ignore", under="ignore"):
            out[sl] = np.exp(-density * tau)                     # Hegeman 2006, Eq. 6: V = exp(-alpha rho f V_cap)
    return out


def reeves_blau(points, shell, *, k: float) -> np.ndarray:
    r"""The baseline: ambient attenuated exponentially with the depth inside the tree.

    Parameters
    ----------
    points : (n, 3) float
        Shading points, finite.
    shell : Sphere, Ellipsoid or MultiShell
        The tree's envelope (with a MultiShell: the shell with the closest centre).
    k : float, keyword-only
        Attenuation per unit depth, >= 0 (an ad hoc parameter, unrelated to alpha*rho).

    Returns
    -------
    (n,) float32 or float64
        ``V = exp(-k depth)``; float32 for float32 points.

    Notes
    -----
    For a sphere, :math:`\text{depth} = \max(R - \lVert x - c \rVert, 0)`: the distance
    from :math:`x` to the surface inside, 0 outside. For an ellipsoid, depth is measured in the
    frame where the ellipsoid is the sphere of the same volume (the affine map the canopy
    model uses, scaled by the equivalent radius :math:`R_{eq} = (a b c)^{1/3}`):
    :math:`\text{depth} = R_{eq} \max(1 - \lVert x' \rVert, 0)` with :math:`x'` the
    unit-frame coordinates. It equals the Euclidean depth for a sphere, is continuous and 0
    on the surface; it is not the Euclidean distance to an elongated ellipsoid's surface.
    Reeves & Blau's own depth was likewise a modelling choice (their parameters "are ad hoc",
    Hegeman 2006, Fig. 4).

    References
    ----------
    Reeves & Blau 1985, "Approximate and probabilistic algorithms for shading and rendering
    structured particle systems", SIGGRAPH 85 (Computer Graphics 19(3)), the ambient term of
    their tree shading. Hegeman et al. 2006, Sec. 2 and Fig. 4 (the comparison).

    Examples
    --------
    >>> reeves_blau([[0, 0, 0], [0, 0.5, 0], [0, 3, 0]], Sphere((0, 0, 0), 1.0), k=2.0).round(6)
    array([0.135335, 0.367879, 1.      ])
    """
    _check_shell(shell)
    k = check_positive(k, "k", allow_zero=True)
    P_raw = as_raw_points(points, "points")
    P = as_array(P_raw, "points")
    depth = np.zeros(P.shape[0])
    if isinstance(shell, MultiShell):
        which, shells = shell.assign(P), shell.shells
    else:
        which, shells = np.zeros(P.shape[0], dtype=int), (shell,)
    for i, s in enumerate(shells):
        sel = which == i
        if np.any(sel):
            x = s.to_unit(P[sel])
            depth[sel] = s.equivalent_radius * np.maximum(1.0 - np.linalg.norm(x, axis=1), 0.0)
    out = np.empty(P.shape[0], dtype=out_dtype(P_raw))
    with np.errstate(over="ignore", under="ignore"):
        out[:] = np.exp(-k * depth)                              # Reeves & Blau 1985: exp(-k depth)
    return out


# ----------------------------------------------------------------------------- fitting
def _grid_then_brent(loss, grid: np.ndarray, *, xatol: float) -> tuple[float, float]:
    """Minimize ``loss(s)`` over ``grid`` (increasing), then by a bounded Brent search between
    the best grid point's neighbours; the grid point stays when Brent does not improve on it.
    Returns (s, loss(s))."""
    losses = [loss(g) for g in grid]
    best = int(np.argmin(losses))
    bracket = (grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)])
    res = minimize_scalar(loss, bounds=bracket, method="bounded", options={"xatol": xatol})
    if res.fun <= losses[best]:
        return float(res.x), float(res.fun)
    return float(grid[best]), float(losses[best])


def _fit_weights(weights, like: np.ndarray) -> np.ndarray:
    """The weights of a least-squares fit: ``weights`` checked non-negative with the shape of
    ``like``, or ones like ``like`` (its dtype too) for None."""
    if weights is None:
        return np.ones_like(like)
    w = as_array(weights, "weights", shape=(like.shape[0],))
    if np.any(w < 0):
        raise ValueError("weights must be non-negative")
    return w


def _check_reference_range(v: np.ndarray) -> None:
    """A reference is a visibility: values further than :data:`REFERENCE_SLACK` outside
    [0, 1] (NaN aside) are an error, since no density fits them and the least squares would
    run off to an extreme one."""
    bad = (v < -REFERENCE_SLACK) | (v > 1.0 + REFERENCE_SLACK)
    if np.any(bad):
        raise ValueError(f"reference must be visibilities in [0, 1] (within {REFERENCE_SLACK} for noise; NaN "
                         f"entries are ignored); {int(np.count_nonzero(bad))} value(s) lie outside, e.g. "
                         f"{float(v[bad][0])!r}")


def fit_density(points, normals, shell, reference, *, weights=None) -> float:
    r"""The alpha*rho whose Eq. 6 visibility best fits a reference (least squares).

    Parameters
    ----------
    points, normals, shell
        As in ``canopy_visibility``.
    reference : (n,) float
        The reference visibility at each point (a ray-traced AO, say), in [0, 1]. NaN
        entries are ignored; inf and values further than ``REFERENCE_SLACK`` outside
        [0, 1] are rejected.
    weights : (n,) float or None, keyword-only
        Non-negative weights of the squared residuals (1 each by default); e.g. 1/stderr^2.

    Returns
    -------
    float
        The density minimizing :math:`\sum w \, (e^{-\text{density}\,\tau} -
        \text{reference})^2`, >= 0, with ``tau = optical_depth(points, normals, shell)``.

    Raises
    ------
    ValueError
        Shapes that disagree, inf in ``reference`` or values outside [0, 1] by more than
        ``REFERENCE_SLACK``, negative or
        non-finite ``weights``, or nothing to fit (no point with a finite reference, a positive weight and tau > 0).

    Notes
    -----
    One parameter, so it is searched directly over ``log(density)``, across the range where
    the optical depths run from ``FIT_TAU_MIN`` (everything open) to ``FIT_TAU_MAX``
    (everything closed), which keeps the search well-scaled where visibility is near 0.
    The loss need not be unimodal there (points whose optical depths lie decades apart each
    pull towards their own density, and the loss has a dip for each): a grid of at least
    ``FIT_GRID`` points and at most ``FIT_GRID_STEP`` apart finds the deepest dip, a bounded
    Brent search between the best grid point's neighbours its bottom; density 0 is compared
    as a candidate; then Gauss-Newton steps polish the minimum (quadratic convergence on
    noise-free data). This is the "simple one-time preprocessing step" that Sec. 4 of the
    paper leaves as future work.

    References
    ----------
    Hegeman et al. 2006, Sec. 4 (alpha*rho chosen by hand; an automatic preprocessing step
    suggested), Eq. 6.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> x = rng.uniform(-0.5, 0.5, (200, 3)); n = rng.normal(size=(200, 3))
    >>> V = canopy_visibility(x, n, s, density=0.8)
    >>> round(fit_density(x, n, s, V), 10)
    0.8
    """
    tau = optical_depth(points, normals, shell)
    v = as_array(reference, "reference", shape=(tau.shape[0],), finite=False)
    if np.any(np.isinf(v)):
        raise ValueError("reference must not hold inf (NaN entries are ignored)")
    _check_reference_range(v)
    w = _fit_weights(weights, tau)
    use = np.isfinite(v) & (w > 0) & (tau > 0)
    if not np.any(use):
        raise ValueError("nothing to fit: no point has a finite reference, a positive weight and a "
                         "nonzero optical depth (a point whose plane misses the shell has V = 1 whatever the density)")
    tau, v, w = tau[use], v[use], w[use]

    def loss(a: float) -> float:
        with np.errstate(under="ignore"):
            r = np.exp(-a * tau) - v
        return float(np.sum(w * r * r))

    lo = math.log(FIT_TAU_MIN / tau.max())
    hi = math.log(FIT_TAU_MAX / tau.min())
    # the loss has plateaus (all open, all closed) and, with optical depths spread over many
    # decades, need not be unimodal in log(density): a grid fine enough to see every dip
    # first, then a bounded search in the bracket around the grid's best point
    grid = np.linspace(lo, hi, max(FIT_GRID, math.ceil((hi - lo) / FIT_GRID_STEP) + 1))
    a = math.exp(_grid_then_brent(lambda s: loss(math.exp(s)), grid, xatol=1e-10)[0])
    if loss(0.0) < loss(a):
        a = 0.0
    for _ in range(FIT_MAX_STEPS):                                # Gauss-Newton on r(a) = exp(-a tau) - v
        with np.errstate(under="ignore"):
            e = np.exp(-a * tau)
        J = -tau * e
        JJ = float(np.sum(w * J * J))
        if JJ == 0:
            break
        step = -float(np.sum(w * J * (e - v))) / JJ
        a_new = max(a + step, 0.0)
        if loss(a_new) > loss(a):
            break
        done = abs(a_new - a) <= FIT_RTOL * max(a, a_new)
        a = a_new
        if done:
            break
    return a



def fit_reeves_blau(points, shell, reference, *, weights=None) -> float:
    r"""The k of ``reeves_blau`` that best fits a reference (least squares), the counterpart
    of ``fit_density`` for the Reeves-Blau baseline.

    Parameters
    ----------
    points : (n, 3) float
        Shading points, finite.
    shell : Sphere, Ellipsoid or MultiShell
        As in ``reeves_blau``.
    reference : (n,) float
        The reference visibility at each point (a ground truth's ``value``), finite.
    weights : (n,) float or None, keyword-only
        Non-negative weights of the squared residuals (1 each by default).

    Returns
    -------
    float
        The k > 0 minimizing :math:`\sum w \, (e^{-k\,\text{depth}} -
        \text{reference})^2`.

    Raises
    ------
    ValueError
        Shapes that disagree, NaN or inf in ``reference`` or ``weights``, ``reference``
        values outside [0, 1] by more than ``REFERENCE_SLACK``, negative ``weights``, or a
        ``shell`` of another type.

    Notes
    -----
    A 1-D least-squares fit of ``log k`` over ``LOG_K_BOUNDS`` (1e-4 to 1e4 per unit
    length): the loss need not be unimodal over eight decades, so a grid of ``K_GRID``
    log-spaced points first, then a bounded Brent search (tolerance ``K_XATOL`` in log k)
    between the best grid point's neighbours. Reeves & Blau chose k by hand ("ad hoc",
    Hegeman 2006, Fig. 4); fitting it gives the baseline its best chance.

    References
    ----------
    Reeves & Blau 1985 (the attenuation ``exp(-k depth)``); Hegeman et al. 2006, Sec. 2 and
    Fig. 4 (the comparison).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> x = np.array([[0, 0, 0], [0, 0.5, 0], [0.2, 0.1, 0], [0, 0, 0.9]])
    >>> round(fit_reeves_blau(x, s, reeves_blau(x, s, k=2.5)), 5)
    2.5
    """
    _check_shell(shell)
    P = as_array(as_raw_points(points, "points"), "points")
    ref = as_array(reference, "reference", shape=(P.shape[0],))
    _check_reference_range(ref)
    w = _fit_weights(weights, ref)

    def loss(log_k):
        return float(np.sum(w * (reeves_blau(points, shell, k=math.exp(log_k)) - ref) ** 2))

    grid = np.linspace(*LOG_K_BOUNDS, K_GRID)
    return float(math.exp(_grid_then_brent(loss, grid, xatol=K_XATOL)[0]))

def predict_density(n_leaves: float, leaf_area: float, shell) -> float:
    r"""The alpha*rho predicted from leaf statistics by the Poisson argument of Sec. 3.

    Parameters
    ----------
    n_leaves : float
        Number of leaves (expected number), > 0, uniformly distributed in the shell.
    leaf_area : float
        One-sided area A of one flat leaf, > 0, world units squared.
    shell : Sphere or Ellipsoid
        The shell; an ellipsoid is treated as its volume-equivalent sphere,
        ``R = (a b c)^(1/3)``.

    Returns
    -------
    float
        :math:`\alpha \rho = \frac{3 \sigma}{2 \pi R^2}` with :math:`\sigma = n A / 2`,
        :math:`n` = ``n_leaves / volume``.

    Notes
    -----
    Randomly oriented flat leaves of one-sided area :math:`A` have a mean projected area
    :math:`A / 2` (Cauchy's projection formula: a convex body's mean shadow is a quarter of
    its surface area, here :math:`2A`), so the number of leaves crossed along a segment of
    length :math:`L` is Poisson with mean :math:`\sigma L`. At the sphere's centre every
    chord has length :math:`R`, so the exact transmittance is :math:`e^{-\sigma R}` in every
    direction (for any angular weighting); there Eq. 6 has :math:`f = 1` and
    :math:`V_{cap} = 2 \pi R^3 / 3`. Equating the exponents gives the formula.
    See ``docs/trees.md`` for the derivation.

    References
    ----------
    Hegeman et al. 2006, Sec. 3 (Eq. 6 as a Poisson zero-count probability).
    Cauchy 1841 (the projection formula; e.g. Santalo 1976, "Integral geometry and geometric
    probability", Sec. 13.6).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 2.0)
    >>> a = predict_density(1000, 0.01, s)
    >>> sigma = 1000 / s.volume * 0.01 / 2
    >>> bool(np.isclose(canopy_visibility([0, 0, 0], [0, 0, 1], s, density=a)[0], np.exp(-sigma * 2.0)))
    True
    """
    _check_shell(shell, multi=False)
    n_leaves = check_positive(n_leaves, "n_leaves")
    A = check_positive(leaf_area, "leaf_area")
    sigma = extinction(n_leaves, A, shell)                      # sigma = n A / 2 (mean projected area A / 2)
    R = shell.equivalent_radius
    return 3.0 * sigma / (2.0 * math.pi * R * R)                # sigma R = alpha rho * 2 pi R^3 / 3 (Eq. 6, f = 1)
