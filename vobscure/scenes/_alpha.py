"""Alpha-tested geometry: the texture coordinates, alpha texture and cutoff of one mesh.

A mesh with an :class:`AlphaMask` is solid only where the alpha texture, looked up at the
interpolated texture coordinates, is at least the cutoff; elsewhere it is a hole that rays
pass through in both directions (the alpha test of a rasterizer, MTL ``map_d`` and glTF
``alphaMode: MASK``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["AlphaMask"]


@dataclass(frozen=True, eq=False)
class AlphaMask:
    """The alpha test of one mesh of a :class:`~vobscure.scenes.Scene`.

    Parameters
    ----------
    uv : (f, 3, 2) float
        Texture coordinates of each corner of each face of the mesh, faces in the mesh's
        order. OpenGL / OBJ convention: u to the right, v up, (0, 0) the bottom-left corner
        of the texture; coordinates outside [0, 1] repeat.
    texture : (h, w) float
        Alpha in [0, 1]; row 0 is the top of the image (v = 1).
    cutoff : float
        Texels with alpha below it are holes (glTF ``alphaCutoff``, 0.5 by default).
    source : str
        Where the mask came from (file and material), for messages.

    Examples
    --------
    >>> import numpy as np
    >>> m = AlphaMask(np.zeros((2, 3, 2)), np.ones((4, 4)))
    >>> m.uv.shape, m.texture.dtype, m.cutoff
    ((2, 3, 2), dtype('float32'), 0.5)
    """

    uv: np.ndarray
    texture: np.ndarray
    cutoff: float = 0.5
    source: str = ""

    def __post_init__(self):
        uv = np.asarray(self.uv, dtype=np.float64)
        if uv.ndim != 3 or uv.shape[1:] != (3, 2):
            raise ValueError(f"AlphaMask uv must have shape (faces, 3, 2), got {uv.shape}")
        if not np.all(np.isfinite(uv)):
            raise ValueError(f"AlphaMask uv{self._where()} holds NaN or inf texture coordinates")
        tex = np.asarray(self.texture, dtype=np.float32)
        if tex.ndim != 2 or tex.size == 0:
            raise ValueError(f"AlphaMask texture{self._where()} must be a non-empty (height, width) "
                             f"array, got shape {tex.shape}")
        if not np.all(np.isfinite(tex)) or tex.min() < 0 or tex.max() > 1:
            raise ValueError(f"AlphaMask texture{self._where()} must hold alpha values in [0, 1]")
        cutoff = float(self.cutoff)
        if not 0.0 <= cutoff <= 1.0:
            raise ValueError(f"AlphaMask cutoff must be in [0, 1], got {self.cutoff!r}")
        object.__setattr__(self, "uv", uv)
        object.__setattr__(self, "texture", np.ascontiguousarray(tex))
        object.__setattr__(self, "cutoff", cutoff)
        object.__setattr__(self, "source", str(self.source))

    def _where(self) -> str:
        return f" ({self.source})" if self.source else ""

    @property
    def holes(self) -> np.ndarray:
        """(h, w) bool: the texels that are holes, ``alpha < cutoff`` (compared in float64)."""
        return self.texture.astype(np.float64) < self.cutoff

    @property
    def has_holes(self) -> bool:
        """Whether any texel is a hole (a mask without holes is an opaque mesh)."""
        return bool(np.any(self.holes))

    def __repr__(self) -> str:
        h, w = self.texture.shape
        holes = float(np.mean(self.holes))
        source = f", source={self.source!r}" if self.source else ""
        return (f"AlphaMask(faces={len(self.uv)}, texture={h}x{w}, cutoff={self.cutoff:g}, "
                f"hole_texels={holes:.1%}{source})")

    def lookup(self, uv) -> np.ndarray:
        """Alpha at texture coordinates ``uv`` (..., 2): the texel that contains each one
        (nearest, coordinates repeat), as the tracer's alpha test reads it
        (:func:`vobscure.raytrace.texel_lookup`).

        Examples
        --------
        >>> import numpy as np
        >>> m = AlphaMask(np.zeros((1, 3, 2)), [[0.0, 1.0], [1.0, 1.0]])   # top-left texel a hole
        >>> m.lookup([[0.25, 0.75], [0.75, 0.75], [1.25, -0.25]]).tolist()
        [0.0, 1.0, 0.0]
        >>> m
        AlphaMask(faces=1, texture=2x2, cutoff=0.5, hole_texels=25.0%)
        """
        from ..raytrace import texel_lookup

        return texel_lookup(self.texture, uv)

    def solid(self, uv) -> np.ndarray:
        """(...,) bool: whether the texel at each texture coordinate is solid
        (``alpha >= cutoff``, glTF 2.0 ``alphaCutoff`` semantics)."""
        return self.lookup(uv).astype(np.float64) >= self.cutoff
