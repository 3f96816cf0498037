"""The camera's pose: where it stands and how it is turned (view -> world), immutable.

View space (the library's convention, ``docs/conventions.md``) has the camera at the origin,
x right, y up and z the depth, positive in front. A pose holds the world-space unit axes
``right``, ``up``, ``forward`` of that frame and the eye; the world -> view rotation has them
as rows, determinant -1 (view space is left-handed in a right-handed world; intended).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_array
from ._checks import EYE_TARGET_RTOL, POSE_ORTHO_TOL, UP_PARALLEL_TOL, vector3
from ._frozen import Frozen, read_only, vector_repr

__all__ = ["Pose"]


def _check_matrix(matrix) -> np.ndarray:
    """A read-only (4, 4) float64 view -> world matrix whose 3x3 part is orthogonal with
    determinant -1."""
    m = as_array(matrix, "pose", shape=(4, 4)).copy()
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"pose must be a rigid 4x4 view-to-world matrix with last row (0, 0, 0, 1), "
                         f"got last row {m[3].tolist()}")
    r = m[:3, :3]
    err = float(np.abs(r.T @ r - np.eye(3)).max())
    if err > POSE_ORTHO_TOL:
        raise ValueError(f"pose's 3x3 part must be a rotation (orthonormal columns: view x, y, z axes in "
                         f"world space), but R^T R differs from I by {err:.3g}")
    det = float(np.linalg.det(r))
    if det > 0:
        raise ValueError("pose's 3x3 part has determinant +1, but vobscure's view space (x right, y up, "
                         "z = depth in front) is left-handed in a right-handed world: its columns are "
                         "(right, up, forward), determinant -1. An OpenGL camera-to-world matrix (camera "
                         "looking down -z) becomes one by negating its third column")
    m += 0.0
    return m


class Pose(Frozen):
    """An immutable camera pose (camera-to-world): the eye and the view axes in world space.

    Build one with :meth:`look_at` (an eye, a target and an up hint) or from a 4x4
    view -> world matrix, ``Pose(matrix)``.

    Parameters
    ----------
    matrix : (4, 4) float
        View -> world matrix in vobscure's view convention: columns
        ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``, its 3x3 part orthogonal (to 1e-6
        per entry of R^T R - I) with determinant -1. (An OpenGL camera-to-world matrix, camera
        looking down -z, becomes one by negating its third column.)

    Attributes
    ----------
    eye : (3,) float64
        The camera's position.
    target : (3,) float64
        The look-at point (``eye + forward`` for a pose from a matrix).
    up_hint : (3,) float64
        The up hint as given to :meth:`look_at` (``up`` for a pose from a matrix).
    forward, right, up : (3,) float64
        Unit view axes z, x, y in world space.
    rotation : (3, 3) float64
        World -> view rotation, rows ``(right, up, forward)``.
    matrix : (4, 4) float64
        View -> world matrix, columns ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``.
    is_look_at : bool
        Built by :meth:`look_at` (its record is eye, target and up) or from a matrix.

    Examples
    --------
    >>> pose = Pose.look_at((0, 0, 5), (0, 0, 0))
    >>> pose.forward.tolist(), pose.world_to_view([0.0, 1.0, 0.0]).tolist()
    ([0.0, 0.0, -1.0], [0.0, 1.0, 5.0])
    >>> Pose(pose.matrix) == Pose.look_at((0, 0, 5), (0, 0, 4))
    False
    """

    __slots__ = ("_eye", "_target", "_up_hint", "_forward", "_right", "_up", "_rotation", "_matrix",
                 "_is_look_at")

    def __init__(self, matrix):
        m = _check_matrix(matrix)
        rotation = np.ascontiguousarray(m[:3, :3].T)
        eye = m[:3, 3].copy()
        right, up, forward = (rotation[a].copy() for a in range(3))
        self._set(eye=eye, target=eye + forward, up_hint=up.copy(), forward=forward, right=right, up=up,
                  rotation=rotation, is_look_at=False)

    def _set(self, *, eye, target, up_hint, forward, right, up, rotation, is_look_at):
        """Set every slot (the one place that does) and make the arrays read-only."""
        matrix = np.zeros((4, 4))
        matrix[:3, :3] = rotation.T
        matrix[:3, 3] = eye
        matrix[3, 3] = 1.0
        arrays = {"_eye": eye, "_target": target, "_up_hint": up_hint, "_forward": forward, "_right": right,
                  "_up": up, "_rotation": rotation, "_matrix": matrix}
        for value in arrays.values():
            value.setflags(write=False)
        self._set_slots(**arrays, _is_look_at=is_look_at)

    @classmethod
    def look_at(cls, eye, target, up=(0.0, 1.0, 0.0)) -> Pose:
        """The pose of a camera at ``eye`` looking at ``target``.

        Parameters
        ----------
        eye, target : (3,) float
            World-space camera position and look-at point; they must differ.
        up : (3,) float, optional
            Up hint, not (nearly) parallel to ``target - eye``; the true ``up`` is its part
            perpendicular to ``forward``. Default ``(0, 1, 0)``.

        Returns
        -------
        Pose
            ``forward = normalize(target - eye)``, ``right = normalize(forward x up)``,
            ``up = right x forward``.

        Examples
        --------
        >>> Pose.look_at((0, 0, 5), (0, 0, 0)).right.tolist()
        [1.0, 0.0, 0.0]
        """
        eye = vector3(eye, "eye")
        target = vector3(target, "target")
        up_hint = vector3(up, "up")
        delta = target - eye
        dist = float(np.linalg.norm(delta))
        scale = max(float(np.linalg.norm(eye)), float(np.linalg.norm(target)))
        if not dist > EYE_TARGET_RTOL * scale or not np.isfinite(dist):
            raise ValueError(f"eye and target must be distinct points, got eye={eye.tolist()} "
                             f"and target={target.tolist()}")
        forward = delta / dist
        up_len = float(np.linalg.norm(up_hint))
        if not up_len > 0.0 or not np.isfinite(up_len):
            raise ValueError(f"up must be a non-zero finite vector, got {up_hint.tolist()}")
        side = np.cross(forward, up_hint / up_len)
        side_len = float(np.linalg.norm(side))
        if side_len < UP_PARALLEL_TOL:
            raise ValueError(f"up {up_hint.tolist()} is (nearly) parallel to the view direction "
                             f"{forward.tolist()}; choose an up vector across it")
        right = side / side_len
        true_up = np.cross(right, forward)
        true_up /= np.linalg.norm(true_up)
        # "+ 0.0" turns the -0.0 components a cross product can produce into +0.0
        forward, right, true_up = forward + 0.0, right + 0.0, true_up + 0.0
        pose = object.__new__(cls)
        pose._set(eye=eye, target=target, up_hint=up_hint, forward=forward, right=right, up=true_up,
                  rotation=np.stack([right, true_up, forward]), is_look_at=True)
        return pose

    # ------------------------------------------------------------------ attributes
    eye, target, up_hint, forward, right, up, rotation, matrix, is_look_at = read_only(
        "eye", "target", "up_hint", "forward", "right", "up", "rotation", "matrix", "is_look_at")

    # ------------------------------------------------------------------ transforms
    def world_to_view(self, points) -> np.ndarray:
        """World-space points ``(..., 3)`` to view space: ``rotation @ (p - eye)`` (float64;
        non-finite entries propagate)."""
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return (p - self._eye) @ self._rotation.T

    def view_to_world(self, points) -> np.ndarray:
        """View-space points ``(..., 3)`` to world space, the inverse of :meth:`world_to_view`."""
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return p @ self._rotation + self._eye

    def world_to_view_dir(self, vectors) -> np.ndarray:
        """World-space directions or normals ``(..., 3)`` to view space (rotation only;
        lengths kept, a normal facing the camera gets ``n_z < 0``)."""
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ self._rotation.T

    def view_to_world_dir(self, vectors) -> np.ndarray:
        """View-space directions or normals ``(..., 3)`` to world space (rotation only)."""
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ self._rotation

    # ------------------------------------------------------------------ derived poses
    def scaled(self, factor: float) -> Pose:
        """The pose in a world scaled by ``factor`` (> 0, checked by the caller) about the
        origin: eye and target scaled, axes kept."""
        if self._is_look_at:
            return Pose.look_at(self._eye * factor, self._target * factor, self._up_hint)
        m = self._matrix.copy()
        m[:3, 3] *= factor
        return Pose(m)

    def as_matrix_pose(self) -> Pose:
        """The same pose recorded as a matrix (``target = eye + forward``, ``up_hint = up``)."""
        return self if not self._is_look_at else Pose(self._matrix)

    # ------------------------------------------------------------------ record, identity
    def to_dict(self) -> dict:
        """``{"eye", "target", "up"}`` (lists of floats) for a look-at pose, ``{"pose": 4 x 4
        lists}`` for a pose from a matrix.

        Examples
        --------
        >>> Pose.look_at((0, 0, 5), (0, 0, 0)).to_dict()
        {'eye': [0.0, 0.0, 5.0], 'target': [0.0, 0.0, 0.0], 'up': [0.0, 1.0, 0.0]}
        """
        if self._is_look_at:
            return {"eye": [float(x) for x in self._eye], "target": [float(x) for x in self._target],
                    "up": [float(x) for x in self._up_hint]}
        return {"pose": [[float(x) for x in row] for row in self._matrix]}

    def __reduce__(self):
        if self._is_look_at:
            return (Pose.look_at, (self._eye, self._target, self._up_hint))
        return (Pose, (self._matrix,))

    def _key(self):
        return tuple((k, tuple(map(tuple, v)) if k == "pose" else tuple(v)) for k, v in self.to_dict().items())

    def __repr__(self) -> str:
        if self._is_look_at:
            return (f"Pose.look_at(eye={vector_repr(self._eye)}, target={vector_repr(self._target)}, "
                    f"up={vector_repr(self._up_hint)})")
        return "Pose((" + ", ".join(vector_repr(r) for r in self._matrix) + "))"
