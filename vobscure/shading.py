"""Applying visibility to light: the shading terms of Real-Time Rendering 3rd ed., Sec. 9.2.

Every estimator and reference of vobscure returns the ambient visibility k_A; this module
turns it into light:

- :func:`ambient`: the ambient term ``k_A c_amb L_A`` (RTR Eq. 9.17 as Eq. 9.19 writes it,
  with ``E_ind = pi L_A``);
- :func:`stewart_langer`: the interreflection correction
  ``k'_A = k_A / (1 - c_amb (1 - k_A))`` (Eqs. 9.22-9.23);
- :func:`multibounce_jimenez`: the cubic multi-bounce fit of Jimenez et al. 2016;
- :func:`iones_indirect`: the indirect term of point and directional lights of Iones et al.
  (Eqs. 9.19-9.20), with :func:`bent_cosine` for the cosines of Eq. 9.20;
- :func:`bent_normal_lookup`: an irradiance environment looked up with the bent normal and
  attenuated by k_A (RTR Sec. 9.2.1), with :class:`LinearSky`, an environment whose
  irradiance is known in closed form.

Arrays broadcast as NumPy does. A visibility is one value per point, a colour has a trailing
axis of C channels: for an (H, W) ``k_A`` and RGB colours of shape (3,) or (H, W, 3), pass
``k_A[..., None]``. The output has the floating dtype of the array inputs (float32 in,
float32 out; Python scalars do not promote), computed in float64. NaN and inf are rejected
with the argument's name, as are visibilities outside [0, 1] and negative colours. The
derivations and the comparison of the two multi-bounce models are on ``docs/shading.md``.

References
----------
.. [1] Akenine-Moller, Haines & Hoffman, Real-Time Rendering, 3rd ed., 2008, Sec. 9.2.
.. [2] Stewart & Langer, "Towards accurate recovery of shape from shading under diffuse
   lighting", IEEE PAMI 19(9), 1997.
.. [3] Jimenez, Wu, Pesce & Jarabo, "Practical Real-Time Strategies for Accurate Indirect
   Occlusion", Activision technical memo ATVI-TR-16-01 and SIGGRAPH 2016 course
   "Physically Based Shading in Theory and Practice".
.. [4] Iones, Krupkin, Sbert & Zhukov, "Fast, realistic lighting for video games", IEEE
   Computer Graphics and Applications 23(3), 2003.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ._validate import as_array

__all__ = [
    "ambient",
    "stewart_langer",
    "multibounce_jimenez",
    "JIMENEZ_2016",
    "iones_indirect",
    "bent_cosine",
    "LinearSky",
    "bent_normal_lookup",
]

#: Coefficients of the multi-bounce fit of Jimenez et al. 2016 [3]: a, b, c are affine in
#: the albedo rho, ``(slope, intercept)`` each: a = 2.0404 rho - 0.3324,
#: b = -4.7951 rho + 0.6417, c = 2.7552 rho + 0.6903. Taken as published in the shader code
#: of the SIGGRAPH 2016 course slides and repeated identically by independent engines
#: (Filament, Bevy, Unreal); not checked against the memo's PDF (docs/shading.md).
JIMENEZ_2016 = {"a": (2.0404, -0.3324), "b": (-4.7951, 0.6417), "c": (2.7552, 0.6903)}

#: Vectors shorter than this are rejected (they have no direction).
ZERO_LENGTH = 1e-12


# ----------------------------------------------------------------------------- validation
def _float(value, name: str) -> tuple[np.ndarray, np.dtype | None]:
    """``value`` as a finite float64 array, and its own float dtype (None for Python scalars
    and integer arrays, which do not decide the output dtype)."""
    own = None
    if isinstance(value, (np.ndarray, np.generic)) and np.asarray(value).dtype.kind == "f":
        own = np.asarray(value).dtype
    elif isinstance(value, bool) or (not isinstance(value, (numbers.Real, np.ndarray, np.generic))
                                     and not hasattr(value, "__len__")):
        raise ValueError(f"{name} must be a number or an array of numbers, got {type(value).__name__}")
    return as_array(value, name), own


def _out_dtype(*owns) -> np.dtype:
    found = [d for d in owns if d is not None]
    return np.result_type(*found) if found else np.dtype(np.float64)


def _in_range(arr: np.ndarray, name: str, lo: float, hi: float | None) -> None:
    bad = (arr < lo) if hi is None else ((arr < lo) | (arr > hi))
    if np.any(bad):
        want = f">= {lo:g}" if hi is None else f"in [{lo:g}, {hi:g}]"
        first = arr[bad].flat[0]
        raise ValueError(f"{name} must be {want}; {int(np.count_nonzero(bad))} value(s) are not "
                         f"(first: {first!r})")


def _visibility(value, name: str = "k_A"):
    arr, own = _float(value, name)
    _in_range(arr, name, 0.0, 1.0)
    return arr, own


def _colour(value, name: str, *, at_most_one: bool = False):
    arr, own = _float(value, name)
    _in_range(arr, name, 0.0, 1.0 if at_most_one else None)
    return arr, own


def _broadcast(*named):
    """Check that the (name, array) pairs broadcast together; name them when they do not."""
    try:
        return np.broadcast_shapes(*(a.shape for _, a in named))
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in named)
        raise ValueError(f"the arguments do not broadcast together: {shapes}. For one k_A per "
                         f"point and RGB colours, pass k_A[..., None].") from None


def _arguments(*named) -> tuple:
    """The arguments of a shading term, each ``(name, value, hi)`` checked in turn as a finite
    float array in [0, hi] (hi None: >= 0), then checked to broadcast together. Returns the
    float64 arrays in order and, last, the output dtype (see :func:`_out_dtype`)."""
    arrays, owns = [], []
    for name, value, hi in named:
        arr, own = _float(value, name)
        _in_range(arr, name, 0.0, hi)
        arrays.append(arr)
        owns.append(own)
    _broadcast(*((name, arr) for (name, _, _), arr in zip(named, arrays)))
    return (*arrays, _out_dtype(*owns))


def _out(value: np.ndarray, dtype: np.dtype) -> np.ndarray:
    return np.asarray(value).astype(dtype, copy=False)


# ----------------------------------------------------------------------------- the terms
def ambient(k_A, c_amb, *, L_A=1.0) -> np.ndarray:
    r"""The ambient term: ambient light attenuated by the ambient occlusion factor.

    .. math:: L_o = k_A \, c_{amb} \otimes L_A

    RTR Eq. 9.17 in the form Eq. 9.19 gives it, :math:`k_A \frac{c_{amb}}{\pi} \otimes
    E_{ind}` with the constant ambient irradiance :math:`E_{ind} = \pi L_A`. For constant
    ambient light this is exact (RTR Sec. 9.2.1): the cosine-weighted integral of the
    visibility is k_A by definition (Eq. 9.14).

    Parameters
    ----------
    k_A : float or (...) array
        Ambient visibility in [0, 1] (1 = open).
    c_amb : float or (..., C) array
        Ambient (diffuse) colour of the surface, >= 0.
    L_A : float or (..., C) array, optional
        Radiance of the ambient light, >= 0 (default 1: the result is k_A c_amb).

    Returns
    -------
    ndarray
        The broadcast shape of the arguments.

    Raises
    ------
    ValueError
        k_A outside [0, 1], a negative colour or radiance, NaN or inf, shapes that do not
        broadcast; the message names the argument.

    References
    ----------
    RTR 3rd ed. [1]_, Sec. 9.2.1, Eqs. 9.17 and 9.19.

    Examples
    --------
    >>> import numpy as np
    >>> from vobscure.shading import ambient
    >>> ambient(np.array([1.0, 0.5])[:, None], [0.8, 0.6, 0.4])
    array([[0.8, 0.6, 0.4],
           [0.4, 0.3, 0.2]])
    """
    k_A, c_amb, L_A, dtype = _arguments(("k_A", k_A, 1.0), ("c_amb", c_amb, None), ("L_A", L_A, None))
    L_o = k_A * c_amb * L_A                                    # RTR Eq. 9.17 (E_ind = pi L_A)
    return _out(L_o, dtype)


def stewart_langer(k_A, c_amb) -> np.ndarray:
    r"""The interreflection-corrected ambient occlusion factor of Stewart and Langer.

    .. math:: k'_A = \frac{k_A}{1 - c_{amb} (1 - k_A)}

    Stewart and Langer assume that the blocked directions see the radiance the shaded
    point itself reflects (a Lambertian enclosure of uniform albedo c_amb under diffuse
    light), which breaks the recursion of the interreflections: the irradiance is
    :math:`E = \pi k_A L_A / (1 - c_{amb}(1 - k_A))` (RTR Eq. 9.22), i.e. k_A is replaced by
    k'_A (Eq. 9.23). It is the sum of the geometric series of bounces
    :math:`k_A \sum_j [c_{amb}(1 - k_A)]^j` (docs/shading.md).

    Parameters
    ----------
    k_A : float or (...) array
        Ambient visibility in [0, 1].
    c_amb : float or (..., C) array
        Albedo (ambient colour) in [0, 1] of the surfaces around the point, taken as uniform.

    Returns
    -------
    ndarray
        k'_A in [k_A, 1], the broadcast shape. k'_A = k_A for c_amb = 0 and 1 for k_A = 1;
        as c_amb -> 1, k'_A -> 1 for every k_A > 0. At k_A = 0 the result is 0 for every
        c_amb, also at c_amb = 1 where the formula reads 0/0 (no light enters the point's
        surroundings).

    Raises
    ------
    ValueError
        k_A or c_amb outside [0, 1], NaN or inf, shapes that do not broadcast.

    References
    ----------
    RTR 3rd ed. [1]_, Sec. 9.2.4, Eqs. 9.22-9.23; Stewart & Langer 1997 [2]_.

    Examples
    --------
    >>> from vobscure.shading import stewart_langer
    >>> float(stewart_langer(0.5, 0.5))
    0.6666666666666666
    """
    k_A, c_amb, dtype = _arguments(("k_A", k_A, 1.0), ("c_amb", c_amb, 1.0))
    denominator = 1.0 - c_amb * (1.0 - k_A)                    # > 0 unless k_A = 0 and c_amb = 1
    with np.errstate(invalid="ignore", divide="ignore"):
        k_A_prime = k_A / denominator                          # RTR Eq. 9.23
    k_A_prime = np.where(k_A == 0.0, 0.0, k_A_prime)
    return _out(k_A_prime, dtype)


def multibounce_jimenez(k_A, albedo) -> np.ndarray:
    r"""Multi-bounce ambient occlusion: the cubic fit of Jimenez et al. 2016.

    .. math:: G(x, \rho) = \max\left(x, ((a x + b) x + c) x\right), \quad
              a = 2.0404 \rho - 0.3324, \;
              b = -4.7951 \rho + 0.6417, \;
              c = 2.7552 \rho + 0.6903

    with x = k_A and rho the albedo. Jimenez et al. fitted this cubic, per albedo, to the
    visibility with interreflections that they computed by ray tracing over a set of scenes;
    it plays the role of :func:`stewart_langer` (both take k_A and an albedo and brighten
    k_A). The coefficients are :data:`JIMENEZ_2016` (see there for their provenance).

    Parameters
    ----------
    k_A : float or (...) array
        Ambient visibility in [0, 1] (single bounce).
    albedo : float or (..., C) array
        Surface albedo rho in [0, 1].

    Returns
    -------
    ndarray
        The multi-bounce visibility, >= k_A, the broadcast shape. It equals k_A for
        albedo 0 and is 0 at k_A = 0; at k_A = 1 the fit gives 0.9996 + 0.0005 rho, so
        the max makes it 1 up to 1e-4.

    Raises
    ------
    ValueError
        k_A or albedo outside [0, 1], NaN or inf, shapes that do not broadcast.

    References
    ----------
    Jimenez et al. 2016 [3]_, the multiple-bounce approximation.

    Examples
    --------
    >>> from vobscure.shading import multibounce_jimenez
    >>> round(float(multibounce_jimenez(0.5, 0.8)), 4)
    0.8111
    """
    x, rho, dtype = _arguments(("k_A", k_A, 1.0), ("albedo", albedo, 1.0))
    a = JIMENEZ_2016["a"][0] * rho + JIMENEZ_2016["a"][1]     # Jimenez et al. 2016, the fit
    b = JIMENEZ_2016["b"][0] * rho + JIMENEZ_2016["b"][1]
    c = JIMENEZ_2016["c"][0] * rho + JIMENEZ_2016["c"][1]
    G = np.maximum(x, ((a * x + b) * x + c) * x)               # Jimenez et al. 2016, max(x, cubic)
    return _out(G, dtype)


def bent_cosine(l, n_bent) -> np.ndarray:
    r"""The clamped cosines :math:`\cos\theta'_{i_k} = \max(0, l_k \cdot n_{bent})` of Eq. 9.20.

    Parameters
    ----------
    l : (n, 3) or (n, ..., 3) float
        Directions towards the n lights (renormalized): one per light (directional lights),
        or one per light and point.
    n_bent : (3,) or (..., 3) float
        Bent normals (renormalized).

    Returns
    -------
    (n, ...) ndarray
        Light k on the first axis, the points' shape after it.

    Raises
    ------
    ValueError
        Zero-length vectors, NaN or inf, a last axis other than 3, shapes that do not
        broadcast.

    Examples
    --------
    >>> from vobscure.shading import bent_cosine
    >>> bent_cosine([[0, 1, 0], [0, -1, 0]], [[0, 1, 0], [1, 0, 0]])
    array([[1., 0.],
           [0., 0.]])
    """
    l_k, d1 = _float(l, "l")
    n_b, d2 = _float(n_bent, "n_bent")
    for name, v in (("l", l_k), ("n_bent", n_b)):
        if v.ndim < 1 or v.shape[-1] != 3:
            raise ValueError(f"{name} must have a last axis of 3 (x, y, z), got shape {v.shape}")
        length = np.linalg.norm(v, axis=-1)
        if np.any(length < ZERO_LENGTH):
            raise ValueError(f"{name} holds {int(np.count_nonzero(length < ZERO_LENGTH))} zero-length "
                             f"vector(s); a direction needs a length")
    if l_k.ndim < 2:
        raise ValueError(f"l must have shape (n, 3) or (n, ..., 3): one direction per light, got {l_k.shape}")
    l_k = l_k / np.linalg.norm(l_k, axis=-1, keepdims=True)
    n_b = n_b / np.linalg.norm(n_b, axis=-1, keepdims=True)
    n = l_k.shape[0]
    pts = _broadcast(("l (per light)", l_k[0]), ("n_bent", n_b))
    l_k = l_k.reshape((n,) + (1,) * (len(pts) - (l_k.ndim - 1)) + l_k.shape[1:])
    cos = np.maximum(np.sum(l_k * n_b, axis=-1), 0.0)          # RTR Eq. 9.20, cos theta'_ik
    return _out(cos, _out_dtype(d1, d2))


def iones_indirect(k_A, c_amb, E_ind, E_L, *, k_ind, cos_theta=None) -> np.ndarray:
    r"""Iones et al.'s indirect term: light sources add to the ambient irradiance.

    Eq. 9.19 (no bent normals) and Eq. 9.20 (``cos_theta`` given):

    .. math::

        L_{o,ind} = k_A \frac{c_{amb}}{\pi} \otimes
            \Big(E_{ind} + k_{ind} \sum_{k=1}^n E_{L_k}\Big)
        \quad\text{or}\quad
        k_A \frac{c_{amb}}{\pi} \otimes
            \Big(E_{ind} + k_{ind} \sum_{k=1}^n E_{L_k} \cos\theta'_{i_k}\Big)

    The full :math:`L_o(v)` of Eqs. 9.19-9.20 adds the direct term
    :math:`\sum_k v(l_k) f(l_k, v) \otimes E_{L_k} \cos\theta_{i_k}`, the lights' shadowed
    direct light through the BRDF, which a renderer computes and is left out here. The
    lights' indirect contribution is attenuated by k_A like the ambient light and, in
    Eq. 9.19, is not weighted by any cosine; in Eq. 9.20, θ'_ik is the angle between l_k and
    the bent normal (:func:`bent_cosine`, clamped at 0). k_ind is empirical: set by eye.

    Parameters
    ----------
    k_A : float or (...) array
        Ambient visibility in [0, 1].
    c_amb : float or (..., C) array
        Ambient (diffuse) colour, >= 0.
    E_ind : float or (..., C) array
        Indirect irradiance (pi L_A for constant ambient light, or an irradiance
        environment map's value), >= 0.
    E_L : (n,) or (n, ...) array
        Irradiance E_Lk of each light (normal incidence), light k on the first axis; the
        other axes broadcast with the points (for RGB lights and (H, W) points:
        (n, 1, 1, 3)). >= 0.
    k_ind : float
        Relative intensity of the lights' indirect contribution, in [0, 1].
    cos_theta : (n, ...) array, optional
        cos θ'_ik in [0, 1] for Eq. 9.20 (:func:`bent_cosine`); None (default) for Eq. 9.19.

    Returns
    -------
    ndarray
        The indirect outgoing radiance, the broadcast shape of k_A, c_amb, E_ind and the
        per-light sum.

    Raises
    ------
    ValueError
        k_A, k_ind or cos_theta outside [0, 1], negative colours or irradiances, NaN or inf,
        shapes that do not broadcast.

    References
    ----------
    RTR 3rd ed. [1]_, Sec. 9.2.2, Eqs. 9.19-9.20; Iones et al. 2003 [4]_.

    Examples
    --------
    >>> import numpy as np
    >>> from vobscure.shading import iones_indirect
    >>> L = iones_indirect(0.5, 0.8, np.pi, [2.0, 1.0], k_ind=0.25)
    >>> round(float(L), 6)      # 0.5 * 0.8 / pi * (pi + 0.25 * 3)
    0.495493
    """
    k_A, d1 = _visibility(k_A)
    c_amb, d2 = _colour(c_amb, "c_amb")
    E_ind, d3 = _colour(E_ind, "E_ind")
    E_L, d4 = _colour(E_L, "E_L")
    if E_L.ndim < 1:
        raise ValueError(f"E_L must have the lights on its first axis, shape (n,) or (n, ...), got {E_L.shape}")
    if isinstance(k_ind, bool) or not isinstance(k_ind, numbers.Real) or not 0.0 <= float(k_ind) <= 1.0:
        raise ValueError(f"k_ind must be a number in [0, 1], got {k_ind!r}")
    d5 = None
    if cos_theta is None:
        per_light = E_L                                        # RTR Eq. 9.19: no cosine
    else:
        cos_theta, d5 = _visibility(cos_theta, "cos_theta")
        if cos_theta.ndim < 1:
            raise ValueError(f"cos_theta must have the lights on its first axis, got shape {cos_theta.shape}")
        _broadcast(("E_L", E_L), ("cos_theta", cos_theta))
        per_light = E_L * cos_theta                            # RTR Eq. 9.20: E_Lk cos theta'_ik
    light_sum = np.sum(per_light, axis=0)
    _broadcast(("k_A", k_A), ("c_amb", c_amb), ("E_ind", E_ind), ("the sum over E_L", light_sum))
    L_o = k_A * c_amb / np.pi * (E_ind + float(k_ind) * light_sum)   # RTR Eqs. 9.19-9.20
    return _out(L_o, _out_dtype(d1, d2, d3, d4, d5))


# ----------------------------------------------------------------------------- bent normals
@dataclass(frozen=True)
class LinearSky:
    r"""A diffuse environment whose radiance is linear in the direction.

    .. math:: L(\omega) = L_0 + L_1 \, (u \cdot \omega)

    L_0 + L_1 at the zenith u, L_0 at the horizon, L_0 - L_1 at the nadir: a sky gradient,
    and any environment's first two spherical-harmonic bands (order 0 and 1). Its
    irradiance on a surface of normal n with the whole hemisphere open is, in closed form,

    .. math:: E_{env}(n) = \int_{\Omega_n} L(\omega) \cos\theta \, d\omega
              = \pi L_0 + \tfrac{2\pi}{3} L_1 \, (u \cdot n)

    (the tangential components of ω integrate to 0 and
    :math:`\int_{\Omega_n} \cos^2\theta \, d\omega = 2\pi/3`).

    Parameters
    ----------
    L_0 : float
        Mean radiance, >= |L_1| (the radiance is never negative).
    L_1 : float
        Gradient along ``up``; negative for a sky darker above.
    up : (3,) float
        The direction u (renormalized).

    Examples
    --------
    >>> from vobscure.shading import LinearSky
    >>> sky = LinearSky(1.0, 0.5)
    >>> round(float(sky.irradiance([0, 1, 0])), 6)     # pi + pi / 3
    4.18879
    """

    L_0: float
    L_1: float
    up: tuple = (0.0, 1.0, 0.0)

    def __post_init__(self):
        for name in ("L_0", "L_1"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not np.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        if self.L_0 < abs(self.L_1):
            raise ValueError(f"L_0 must be >= |L_1| (the radiance L_0 - |L_1| at the darkest "
                             f"direction is negative otherwise), got L_0={self.L_0!r}, L_1={self.L_1!r}")
        u = as_array(self.up, "up", shape=(3,))
        if np.linalg.norm(u) < ZERO_LENGTH:
            raise ValueError("up must have a length")
        object.__setattr__(self, "up", tuple(float(x) for x in u / np.linalg.norm(u)))

    def radiance(self, omega) -> np.ndarray:
        """L(omega) for unit directions ``omega`` (..., 3) (not renormalized): (...)."""
        omega, own = _float(omega, "omega")
        return _out(self.L_0 + self.L_1 * (omega @ np.asarray(self.up)), _out_dtype(own))

    def irradiance(self, n) -> np.ndarray:
        """E_env(n) for normals ``n`` (..., 3) (renormalized), the whole hemisphere open: (...)."""
        n, own = _float(n, "n")
        if n.ndim < 1 or n.shape[-1] != 3:
            raise ValueError(f"n must have a last axis of 3, got shape {n.shape}")
        length = np.linalg.norm(n, axis=-1)
        if np.any(length < ZERO_LENGTH):
            raise ValueError(f"n holds {int(np.count_nonzero(length < ZERO_LENGTH))} zero-length vector(s)")
        u_dot_n = (n @ np.asarray(self.up)) / length
        E_env = np.pi * self.L_0 + 2.0 * np.pi / 3.0 * self.L_1 * u_dot_n
        return _out(E_env, _out_dtype(own))


def bent_normal_lookup(k_A, c_amb, n_bent, *, environment) -> np.ndarray:
    r"""Shading from an irradiance environment map looked up with the bent normal.

    .. math:: L_o = k_A \frac{c_{amb}}{\pi} \otimes E_{env}(n_{bent})

    RTR Sec. 9.2.1: Eq. 9.17 with the environment's irradiance :math:`E_{env}(n_{bent})` in
    place of the ambient irradiance :math:`\pi L_A`. Unlike k_A on constant ambient light,
    this is an approximation: the exact value is
    :math:`\frac{c_{amb}}{\pi}\int_\Omega v(l) L(l) \cos\theta \, d\omega`. Pass the
    geometric normal as ``n_bent`` to get the lookup without bent normals, for comparison.

    Parameters
    ----------
    k_A : float or (...) array
        Ambient visibility in [0, 1].
    c_amb : float or (..., C) array
        Ambient (diffuse) colour, >= 0.
    n_bent : (..., 3) float
        Bent normals, e.g. ``ambient_occlusion(..., bent_normals=True).bent_normal``.
    environment : LinearSky or callable
        Anything with an ``irradiance(n)`` method, or a callable n (..., 3) -> E (...),
        returning the unoccluded irradiance E_env(n) >= 0.

    Returns
    -------
    ndarray
        The broadcast shape of k_A, c_amb and E_env(n_bent).

    Raises
    ------
    ValueError
        k_A outside [0, 1], negative colours or irradiances, NaN or inf, shapes that do
        not broadcast.

    References
    ----------
    RTR 3rd ed. [1]_, Sec. 9.2.1 (Eq. 9.17 with E_env(n_bent)).

    Examples
    --------
    >>> from vobscure.shading import LinearSky, bent_normal_lookup
    >>> sky = LinearSky(1.0, 0.0)                      # constant: the bent normal is irrelevant
    >>> round(float(bent_normal_lookup(0.5, 0.8, [1, 0, 0], environment=sky)), 6)
    0.4
    """
    k_A, d1 = _visibility(k_A)
    c_amb, d2 = _colour(c_amb, "c_amb")
    lookup = getattr(environment, "irradiance", environment)
    if not callable(lookup):
        raise ValueError(f"environment must have an irradiance(n) method or be callable, "
                         f"got {type(environment).__name__}")
    E_env, d3 = _colour(lookup(n_bent), "environment(n_bent)")
    _broadcast(("k_A", k_A), ("c_amb", c_amb), ("environment(n_bent)", E_env))
    L_o = k_A * c_amb / np.pi * E_env                          # RTR Sec. 9.2.1, Eq. 9.17 with E_env(n_bent)
    return _out(L_o, _out_dtype(d1, d2, d3))
