"""Large occluders (trees seen from the ground) and grass: Hegeman et al. 2006, Sec. 3.

``occluder_visibility`` is the visibility of surface points (the ground, a moving object)
near trees enclosed in spheres: the paper's solid-angle approximation (Eqs. 7-8), the exact
occlusion of an opaque sphere (closed forms, horizon included), and the sphere as a porous
medium (the chord transmittance of the canopy's Poisson leaf cloud, integrated over the
hemisphere by :func:`vobscure.trees.poisson.sphere_transmittance`, the one implementation of
it, shared with the canopy model :func:`vobscure.trees.poisson_visibility`).
``sphere_occlusion`` is the exact opaque-sphere term on its own.
``grass_visibility`` is Eq. 9. See ``docs/trees.md``, "Occluders and grass".
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from .._validate import as_array, as_points, as_unit_vectors, check_choice, check_int, check_positive
from ._arrays import as_raw_points, out_dtype
from .poisson import check_quadrature, sphere_transmittance
from .shells import Sphere

__all__ = [
    "OCCLUDER_MODELS",
    "WEIGHTINGS",
    "DEFAULT_QUADRATURE",
    "POROUS_QUADRATURE_ERROR",
    "DEFAULT_CHUNK",
    "POROUS_CHUNK",
    "COS_THETA_SLACK",
    "occluder_visibility",
    "sphere_occlusion",
    "grass_visibility",
]

#: The models of :func:`occluder_visibility`.
OCCLUDER_MODELS = ("hegeman", "exact", "porous")
#: Angular weightings: "cosine" (the form factor, RTR's k_A) or "uniform" (solid angle / 2 pi).
WEIGHTINGS = ("cosine", "uniform")
#: Gauss-Legendre nodes per piece of the porous model's polar integral (four pieces).
DEFAULT_QUADRATURE = 16
#: Bound on the absolute error of the porous model with ``DEFAULT_QUADRATURE`` nodes per
#: piece, measured against a 512-node evaluation of the same integral (sigma R = 1.3) and
#: against the closed forms at sigma = inf, over random points from the centre to 3 radii,
#: within 1e-3 and 1e-7 of the surface, normals in every direction: largest errors 3.4e-7
#: (cosine) and 2.7e-7 (uniform), at points just inside the surface; 4e-8 outside it
#: (``tests/test_occluders.py::test_porous_quadrature_error`` checks the bound).
POROUS_QUADRATURE_ERROR = 1e-6
#: Points per chunk: temporaries are a few hundred bytes times this, whatever the input size.
DEFAULT_CHUNK = 1 << 15
#: Largest chunk of the porous model (whose quadrature, ``sphere_transmittance``, works in
#: blocks of its own of (m, 4 x quadrature) chords and weights).
POROUS_CHUNK = 1 << 13
#: How far outside [-1, 1] ``grass_visibility`` accepts cos_theta as rounding (clipped);
#: further is an error.
COS_THETA_SLACK = 1e-6


# ----------------------------------------------------------------------------- validation
def _as_spheres(spheres) -> tuple[Sphere, ...]:
    if isinstance(spheres, Sphere):
        return (spheres,)
    if isinstance(spheres, Sequence) and not isinstance(spheres, str):
        out = tuple(spheres)
        for i, s in enumerate(out):
            if not isinstance(s, Sphere):
                raise ValueError(f"spheres[{i}] must be a vobscure.trees.Sphere, got {type(s).__name__}")
        return out
    raise ValueError(f"spheres must be a vobscure.trees.Sphere or a sequence of them, "
                     f"got {type(spheres).__name__}")


def _as_sigmas(sigma, count: int) -> np.ndarray:
    if isinstance(sigma, numbers.Real) and not isinstance(sigma, bool):
        return np.full(count, check_positive(sigma, "sigma", allow_inf=True, allow_zero=True))
    arr = as_array(sigma, "sigma", shape=(count,), finite=False)
    if np.any(np.isnan(arr)) or np.any(arr < 0):
        raise ValueError(f"sigma must be >= 0 (inf allowed) for every sphere, got {arr.tolist()}")
    return arr


# ----------------------------------------------------------------------------- geometry
def _to_center(x: np.ndarray, n: np.ndarray, sphere: Sphere):
    """Distance d to the centre, the vector D to it and cos(theta) = n.D / d (1 where d = 0)."""
    D = sphere.center - x
    d = np.sqrt(np.einsum("ij,ij->i", D, D))
    nD = np.einsum("ij,ij->i", n, D)
    cos_theta = np.clip(np.divide(nD, d, out=np.ones_like(d), where=d > 0), -1.0, 1.0)
    return d, D, cos_theta


def _sin_alpha(d: np.ndarray, r: float) -> np.ndarray:
    """sin of the cap's half-angle, r / d, and 1 on or inside the sphere (d <= r)."""
    outside = d > r
    return np.where(outside, r / np.where(outside, d, 1.0), 1.0)


# ----------------------------------------------------------------------------- the models
def _hegeman(d, r, cos_theta):
    q = _sin_alpha(d, r)                       # r / d, clamped to 1 on and inside the sphere
    A_SA = np.pi * q * q                       # Hegeman 2006, Eq. 7
    V = 1.0 - A_SA / (2.0 * np.pi)             # Hegeman 2006, Eq. 8
    below = (d >= r) & (cos_theta <= -q)        # a sphere wholly below the horizon hides nothing
    return np.where(below, 1.0, V)


def _exact_occlusion(d, r, cos_theta, weighting):
    """Weighted fraction of the hemisphere the opaque sphere covers (1 - visibility)."""
    sin_a = _sin_alpha(d, r)                                   # sin(alpha), alpha the cap's half-angle
    cos_a = np.sqrt(np.maximum((1.0 - sin_a) * (1.0 + sin_a), 0.0))
    sin_t = np.sqrt(np.maximum((1.0 - cos_theta) * (1.0 + cos_theta), 0.0))
    above = cos_theta >= sin_a                                 # the whole cap above the horizon
    partial = np.abs(cos_theta) < sin_a                        # the horizon cuts the cap
    # y = -cot(alpha) cot(theta): acos(y) is the half-angle, about the axis c, of the arc of
    # the cap's rim that lies above the horizon (Snyder 1996; Mazonka 2012, Sec. 4).
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(partial, -cos_a * cos_theta / np.where(partial, sin_a * sin_t, 1.0), 0.0)
    y = np.clip(y, -1.0, 1.0)
    sqrt_1my2 = np.sqrt(np.maximum((1.0 - y) * (1.0 + y), 0.0))
    if weighting == "cosine":
        full = sin_a * sin_a * cos_theta                       # (r/d)^2 cos(theta)
        # the form factor of a sphere partly below the horizon: Snyder 1996 (the same
        # closed form as Lagarde & de Rousiers 2014, Sec. 4.7.2)
        x = cos_a / np.where(partial, sin_a, 1.0)              # cot(alpha) = sqrt((d/r)^2 - 1)
        cut = ((cos_theta * np.arccos(y) - x * sin_t * sqrt_1my2) * sin_a * sin_a
               + np.arctan2(sin_t * sqrt_1my2, x)) / np.pi
    else:
        full = 1.0 - cos_a                                     # 2 pi (1 - sqrt(1 - (r/d)^2)) / 2 pi
        # the cap intersected with the hemisphere (two intersecting caps, one of half-angle
        # pi/2): Mazonka 2012, Sec. 4 (Tovchigrechko & Vakser 2001), divided by 2 pi
        ratio = np.clip(cos_theta / sin_a, -1.0, 1.0)
        cut = (np.pi - np.arccos(ratio) - cos_a * np.arccos(y)) / np.pi
    occluded = np.where(above, full, np.where(partial, cut, 0.0))
    return np.where(d < r, 1.0, np.clip(occluded, 0.0, 1.0))


# ----------------------------------------------------------------------------- public API
def sphere_occlusion(distance, radius, cos_theta, *, weighting: str = "cosine") -> np.ndarray:
    r"""Exact fraction of a point's hemisphere hidden by an opaque sphere.

    Parameters
    ----------
    distance : (...) float
        Distance d from the point to the sphere's centre, >= 0.
    radius : (...) float
        The sphere's radius r > 0 (broadcast with ``distance``).
    cos_theta : (...) float
        Cosine of the angle theta between the point's normal and the direction to the
        centre, in [-1, 1].
    weighting : {"cosine", "uniform"}
        "cosine": the form factor from the point to the sphere, (1/pi) int cos; "uniform":
        the solid angle above the horizon over 2 pi.

    Returns
    -------
    (...) float64
        The occluded fraction in [0, 1]; the visibility is one minus it. 1 for a point inside
        the sphere (d < r). On the surface (d = r) the limit from outside:
        (1 + cos theta) / 2 (cosine) or 1 - theta / pi (uniform).

    Notes
    -----
    With :math:`\sin\alpha = r / d` the sine of the cap's half-angle, three cases:

    - the cap wholly above the horizon (:math:`\cos\theta \ge r/d`): the form factor
      :math:`(r/d)^2 \cos\theta`, the solid angle :math:`2\pi \left(1 - \sqrt{1 - (r/d)^2}\right)`;
    - wholly below (:math:`\cos\theta \le -r/d`): 0;
    - cut by the horizon: with :math:`x = \cot\alpha` and :math:`y = -x \cot\theta`, the form
      factor

      .. math::

          \frac{1}{\pi} \left[\left(\cos\theta \arccos y - x \sin\theta \sqrt{1 - y^2}\right)
          \left(\frac{r}{d}\right)^2 + \arctan\frac{\sin\theta \sqrt{1 - y^2}}{x}\right]

      (Snyder 1996; Lagarde & de Rousiers 2014, Sec. 4.7.2, give the same expression for
      a spherical light partly below the horizon) and the solid angle
      :math:`2 \left[\pi - \arccos\frac{\cos\theta}{\sin\alpha} - \cos\alpha \arccos y\right]`:
      the intersection of the cap with the hemisphere, two caps of half-angles :math:`\alpha`
      and :math:`\pi/2` at angle :math:`\theta` (Mazonka 2012, Sec. 4; Tovchigrechko & Vakser
      2001).

    Both partial forms are checked in ``tests/test_occluders.py`` against an independent
    adaptive quadrature over the hemisphere (to 1e-9) and against ray casting of an
    icosphere with the Embree ground truth (z-tests).

    References
    ----------
    Snyder, J. M. 1996, "Area light sources for real-time graphics", Microsoft Research
    MSR-TR-96-11 (form factor of a sphere partly below the horizon).
    Lagarde, S. and de Rousiers, C. 2014, "Moving Frostbite to physically based rendering",
    SIGGRAPH course notes, Sec. 4.7.2 (sphere area lights, the same closed form).
    Mazonka, O. 2012, "Solid angle of conical surfaces, polyhedral cones, and intersecting
    spherical caps", arXiv:1205.1396, Sec. 4.
    Hegeman et al. 2006, Sec. 3, "Interaction with Objects" (Eq. 7 approximates the solid
    angle of this sphere).

    Examples
    --------
    >>> float(sphere_occlusion(2.0, 1.0, 1.0))          # (r/d)^2 cos(theta)
    0.25
    >>> round(float(sphere_occlusion(2.0, 1.0, 0.0)), 6)   # half the cap below the horizon
    0.028834
    >>> float(sphere_occlusion(2.0, 1.0, -1.0, weighting="uniform"))
    0.0
    """
    check_choice(weighting, "weighting", WEIGHTINGS)
    d = as_array(distance, "distance")
    r = as_array(radius, "radius")
    ct = as_array(cos_theta, "cos_theta")
    if np.any(d < 0):
        raise ValueError("distance must be >= 0")
    if np.any(r <= 0):
        raise ValueError("radius must be > 0")
    if np.any(np.abs(ct) > 1.0 + COS_THETA_SLACK):
        raise ValueError("cos_theta must lie in [-1, 1]")
    d, r, ct = np.broadcast_arrays(d, r, np.clip(ct, -1.0, 1.0))
    shape = d.shape
    d, r, ct = (np.ravel(a) for a in (d, r, ct))
    # the result depends on d / r only: scaled distances and a unit radius
    return _exact_occlusion(d / r, 1.0, ct, weighting).reshape(shape)


def occluder_visibility(points, normals, spheres, *, model: str = "hegeman", sigma=None,
                        weighting: str = "cosine", quadrature: int = DEFAULT_QUADRATURE,
                        chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    r"""Visibility of surface points near large occluders (trees) enclosed in spheres.

    Parameters
    ----------
    points : (n, 3) float
        Surface points (the ground, an object near the trees), world space; a single (3,)
        point is one row.
    normals : (n, 3) float
        Their normals (renormalized; zero vectors are an error).
    spheres : Sphere or sequence of Sphere
        The occluders (``vobscure.trees.Sphere``). An empty sequence gives visibility 1.
    model : {"hegeman", "exact", "porous"}
        "hegeman": the paper's approximation, Eqs. 7-8, per sphere. "exact": the true
        visibility past an opaque sphere (:func:`sphere_occlusion`). "porous": the sphere as
        a homogeneous absorbing medium of extinction ``sigma`` (a leaf cloud).
    sigma : float or (k,) float, optional
        Extinction coefficient per unit length (>= 0, ``inf`` = opaque) of each sphere's
        medium, or one for all; required by ``model="porous"`` and an error otherwise.
        From the canopy model's density alpha*rho (Eq. 6) of a sphere of radius R:
        ``sigma = 2 pi R^2 alpha_rho / 3`` (see Notes).
    weighting : {"cosine", "uniform"}
        Angular weight of the "exact" and "porous" models: "cosine" gives ambient occlusion
        k_A (the form factor), "uniform" the hemisphere average (solid angle / 2 pi), as
        :func:`vobscure.ambient_occlusion`. The "hegeman" model does not use it: Eq. 8 is
        the solid-angle fraction.
    quadrature : int
        Gauss-Legendre nodes per piece of the porous model's polar integral (four pieces,
        so 4 x ``quadrature`` chord lengths per point and sphere), at most
        ``MAX_QUADRATURE`` = 1024 (:mod:`vobscure.trees.poisson`).
    chunk : int
        Points processed at once (at most ``POROUS_CHUNK`` = 8192 for "porous"); the
        temporaries are a few hundred bytes times that, whatever n.

    Returns
    -------
    (n,) float
        Visibility in [0, 1] (1 = open sky), float32 when ``points`` and ``normals`` are
        both float32, float64 otherwise.

    Raises
    ------
    ValueError
        Bad shapes, non-finite points or normals (NaN is not propagated: mask those rows
        first), zero normals, an unknown ``model`` or ``weighting``, ``sigma`` missing for
        "porous" or given for another model, or spheres that are not ``Sphere``.

    Notes
    -----
    **Several spheres** combine as the product of the per-sphere visibilities, which assumes
    independent occluders: exact for the porous transmittance along one direction, not
    after the angular integration, and for opaque spheres the product counts the overlap of
    two caps as :math:`F_1 F_2` instead of its true weight. ``docs/trees.md`` ("Occluders and
    grass") measures what this costs against ray casting of the union.

    **hegeman** (Eqs. 7-8): :math:`A_{SA} = \pi (r/d)^2`, :math:`V = 1 - A_{SA} / (2\pi)`.
    :math:`r/d` is clamped to 1 on and inside the sphere (:math:`d \le r`), so
    :math:`A_{SA} \to \pi` and :math:`V \to 1/2` as :math:`d \to r` and :math:`V = 1/2`
    inside (the paper's formula, continued as a constant; no NaN at :math:`d = 0`). Eq. 7
    ignores the normal; the one addition here is that a sphere wholly below the point's
    horizon (:math:`\cos\theta \le -r/d`) hides nothing (:math:`V = 1`). Everywhere else this
    is Eqs. 7-8 exactly. Eq. 7 is the small-angle limit of the solid angle
    :math:`2\pi \left(1 - \sqrt{1 - (r/d)^2}\right)`, which it underestimates (by half at
    :math:`d = r`).

    **exact**: :math:`V = 1 -` :func:`sphere_occlusion`, closed forms including a sphere cut
    by the horizon. A point inside the sphere (:math:`d < r`) has :math:`V = 0`; on the
    surface (:math:`d = r`) the limit from outside, e.g. :math:`(1 - \cos\theta) / 2` with
    the cosine weight (0 for a normal facing the centre, 1 facing away).

    **porous**:

    .. math::

        V = 1 - \int_{\Omega} w(\omega) \left(1 - e^{-\sigma L(\omega)}\right) d\omega

    over the hemisphere, :math:`L` the chord of the ray in the sphere (from the point to the
    exit when the point is inside), evaluated by
    :func:`vobscure.trees.poisson.sphere_transmittance`. The integral is over the cap of
    directions that meet the sphere, in the angle :math:`\psi` from the direction to the
    centre (the chord depends on :math:`\psi` only) and the azimuth about it, whose integral
    over the arc above the horizon is done in closed form; the remaining integral in
    :math:`\psi` is split at the two angles where the arc meets the horizon and each piece is
    integrated by ``quadrature``-point Gauss-Legendre after the substitution
    :math:`\psi = a + (b - a)(1 - \cos t)/2`, which removes the square-root behaviour of the
    chord at the cap's edge and of the arc at the splits (a third split at
    :math:`\psi = \pi/2` for a point inside the sphere). Its error with the default 16 nodes
    is below ``POROUS_QUADRATURE_ERROR`` = 1e-6 (measured; 4e-8 outside the sphere).
    :math:`\sigma = 0` gives 1, :math:`\sigma = \infty` the "exact" model. The density of
    Eq. 6, :math:`\alpha\rho`, converts as :math:`\sigma = 2\pi R^2 \alpha\rho / 3`: the
    inverse of ``vobscure.trees.predict_density``'s :math:`\alpha\rho = 3\sigma / (2\pi R^2)`,
    which equates Eq. 6 at the centre of the sphere (:math:`f = 1`,
    :math:`V_{cap} = 2\pi R^3 / 3`) with the transmittance :math:`e^{-\sigma R}` of a radius.

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3, "Interaction with Objects", Eqs. 7-8 and Fig. 5.
    Snyder 1996 and Mazonka 2012 for the exact partly hidden sphere
    (:func:`sphere_occlusion`).

    Examples
    --------
    >>> import numpy as np
    >>> from vobscure.trees import Sphere
    >>> tree = Sphere((0.0, 3.0, 0.0), 1.0)          # crown 3 units above the ground, y up
    >>> ground = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    >>> up = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    >>> occluder_visibility(ground, up, tree).round(4)                     # Eqs. 7-8
    array([0.9444, 0.98  ])
    >>> occluder_visibility(ground, up, tree, model="exact").round(4)      # 1 - (r/d)^2 cos(theta)
    array([0.8889, 0.976 ])
    >>> occluder_visibility(ground, up, tree, model="porous", sigma=1.0).round(4)
    array([0.9219, 0.9831])
    """
    check_choice(model, "model", OCCLUDER_MODELS)
    check_choice(weighting, "weighting", WEIGHTINGS)
    chunk = check_int(chunk, "chunk", minimum=1)
    raw_points = as_raw_points(points, "points")
    raw_normals = as_raw_points(normals, "normals")
    if raw_normals.shape[0] != raw_points.shape[0]:
        raise ValueError(f"normals must have one row per point ({raw_points.shape[0]}), "
                         f"got {raw_normals.shape[0]}")
    spheres = _as_spheres(spheres)
    if model == "porous":
        if sigma is None:
            raise ValueError("model='porous' needs sigma, the extinction per unit length "
                             "(sigma = 2 pi R^2 alpha_rho / 3 from the canopy density alpha_rho)")
        sigmas = _as_sigmas(sigma, len(spheres))
        quadrature = check_quadrature(quadrature, "quadrature")
    elif sigma is not None:
        raise ValueError(f"sigma is used by model='porous' only, not by model={model!r}")
    if model == "porous":
        chunk = min(chunk, POROUS_CHUNK)
    n = raw_points.shape[0]
    out = np.empty(n, dtype=out_dtype(raw_points, raw_normals))
    for start in range(0, n, chunk):
        s = slice(start, min(start + chunk, n))
        x = as_points(raw_points[s], "points")
        nrm = as_unit_vectors(raw_normals[s], "normals")
        V = np.ones(len(x))
        for k, sphere in enumerate(spheres):
            if model == "porous":
                V *= sphere_transmittance(x, nrm, sphere, extinction=float(sigmas[k]), weighting=weighting,
                                          quadrature=quadrature)
                continue
            d, _, cos_theta = _to_center(x, nrm, sphere)
            if model == "hegeman":
                V *= _hegeman(d, sphere.radius, cos_theta)
            else:
                V *= 1.0 - _exact_occlusion(d, sphere.radius, cos_theta, weighting)
        out[s] = V
    return out


def grass_visibility(height, blade_height, cos_theta) -> np.ndarray:
    r"""Visibility of a point on a grass blade, Hegeman 2006 Eq. 9.

    .. math:: V = \frac{P_z}{2h} (1 + \cos\theta)

    Parameters
    ----------
    height : (...) float
        P_z, the height of the point on the blade above the ground (the blade's root).
        Clamped to [0, h]: below the ground is 0, above the tip is h.
    blade_height : (...) float
        h, the blade's total height, > 0 (broadcast with ``height``).
    cos_theta : (...) float
        Cosine of theta, the angle between the surface normal at the point and the vertical
        (up): 1 for a normal facing the sky, 0 for a horizontal normal (a vertical blade),
        -1 facing the ground. Values further than ``COS_THETA_SLACK`` outside [-1, 1] are
        an error; within it they are clipped (rounding of a dot product of unit vectors).

    Returns
    -------
    ndarray
        The broadcast shape of the three inputs, visibility in [0, 1]; float32 when every
        array input is float32, float64 otherwise. Empty inputs give an empty array, as
        the other models do.

    Notes
    -----
    The paper says only ":math:`P_z` the height of the hit point on the grass blade and
    :math:`h` the total height" (Fig. 6 is a sketch). :math:`\theta` is read here as the
    angle of the normal from the vertical because that is what makes the two factors
    meaningful: :math:`P_z / h` darkens linearly with depth in the field (0 at the ground,
    where the blades hide the sky, 1 at the tips), and :math:`(1 + \cos\theta) / 2` is the
    sky view factor of a plane tilted by :math:`\theta` in an open field (1 facing up, 1/2
    for a vertical surface, 0 facing down). So the tip of a blade whose normal faces up is
    fully visible, :math:`V = 1`; a point on the ground :math:`V = 0`; a horizontal normal
    halves the value.

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3, "Visibility approximation for grass", Eq. 9 and Fig. 6.

    Examples
    --------
    >>> grass_visibility([0.0, 0.5, 1.0, 1.0], 1.0, [1.0, 1.0, 1.0, 0.0])
    array([0. , 0.5, 1. , 0.5])
    """
    P_z = as_array(height, "height", finite=False)
    h = as_array(blade_height, "blade_height", finite=False)
    ct = as_array(cos_theta, "cos_theta", finite=False)
    try:
        P_z, h, ct = np.broadcast_arrays(P_z, h, ct)
    except ValueError:
        raise ValueError(f"height {P_z.shape}, blade_height {h.shape} and cos_theta {ct.shape} must "
                         "broadcast to one shape") from None
    V = np.empty(P_z.shape, dtype=out_dtype(height, blade_height, cos_theta))
    if V.size == 0:
        return V
    if V.ndim == 0:
        V[()] = _grass(P_z, h, ct)
        return V
    # row blocks of about DEFAULT_CHUNK elements: the temporaries stay in cache
    rows = max(1, DEFAULT_CHUNK // max(1, V.size // V.shape[0]))
    for start in range(0, V.shape[0], rows):
        s = slice(start, start + rows)
        V[s] = _grass(P_z[s], h[s], ct[s])
    return V


def _grass(P_z, h, ct):
    for name, value in (("height", P_z), ("blade_height", h), ("cos_theta", ct)):
        if not np.all(np.isfinite(value)):
            raise ValueError(f"{name} must be finite; it holds NaN or inf value(s). "
                             "Remove or mask those entries before the call.")
    if np.any(h <= 0):
        raise ValueError(f"blade_height must be > 0; got {float(np.min(h))!r}")
    if np.any(np.abs(ct) > 1.0 + COS_THETA_SLACK):
        raise ValueError(f"cos_theta must lie in [-1, 1]; got {float(ct[np.abs(ct) > 1.0 + COS_THETA_SLACK].flat[0])!r}")
    V = np.clip(P_z, 0.0, h)                               # P_z below the root or above the tip
    V /= h                                                 # P_z / h in [0, 1]: h itself is never doubled,
    V *= 0.5                                               # so an h near the float maximum cannot overflow
    V *= 1.0 + np.clip(ct, -1.0, 1.0)                      # Hegeman 2006, Eq. 9: P_z / (2h) (1 + cos theta)
    return V
