"""Blue-noise dither arrays by Ulichney's void-and-cluster method, and the stored 64 x 64 pair.

The ``"blue"`` noise schedule (:mod:`vobscure.screenspace.noise`) reads two 64 x 64 arrays of
ranks made here once and stored as package data (``data/bluenoise64.npz``, its provenance in
``data/README.md``); :func:`void_and_cluster` regenerates them.

The method ranks the cells of a toroidal grid so that, for every k, the k cells of lowest rank
form a homogeneous ("blue noise") binary pattern: no clusters, no voids. A cell's *energy* is
the sum, over the pattern's minority cells, of a Gaussian of the toroidal distance; the
minority cell of highest energy is the *tightest cluster*, the majority cell of lowest energy
the *largest void*. Every step moves one cell between the two classes, so the energy is
updated by adding or subtracting one copy of the kernel centred there (O(N) per step, N the
number of cells).

References
----------
.. [1] R. Ulichney, "The void-and-cluster method for dither array generation", Proc. SPIE
   1913, Human Vision, Visual Processing, and Digital Display IV (1993): the Gaussian filter
   (sigma = 1.5) applied with wrap-around, the initial binary pattern and phases 1-3.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

from .._validate import as_rng, check_int, check_positive

__all__ = ["SIGMA", "BLUE_TILE", "BLUE_SEEDS", "void_and_cluster", "ranks_to_uniforms", "blue_ranks"]

#: Ulichney's filter width (cells): the Gaussian exp(-r^2 / (2 sigma^2)).
SIGMA = 1.5
#: Edge of the stored arrays.
BLUE_TILE = 64
#: The seeds of the initial random patterns of the stored (u1, u2) arrays.
BLUE_SEEDS = (1, 2)
#: The fraction of minority cells in the initial random pattern.
INITIAL_FRACTION = 0.1
_DATA = Path(__file__).with_name("data") / "bluenoise64.npz"


def _kernel(size: int, sigma: float) -> np.ndarray:
    """(2 size, 2 size) the toroidal Gaussian centred on cell (0, 0), tiled twice in each
    direction, so that ``k[size - i:2 size - i, size - j:2 size - j]`` is it centred on
    (i, j) (np.roll of it by (i, j), without a copy)."""
    d = np.arange(size)
    d = np.minimum(d, size - d).astype(np.float64)          # toroidal distance to 0
    g = np.exp(-(d[:, None] ** 2 + d[None, :] ** 2) / (2.0 * sigma ** 2))
    return np.tile(g, (2, 2))


class _Energy:
    """The energy of the cells of a toroidal binary pattern, kept in step with the pattern."""

    def __init__(self, pattern: np.ndarray, kernel: np.ndarray):
        self.size = pattern.shape[0]
        self.kernel = kernel
        self.pattern = pattern.copy()
        g = kernel[:self.size, :self.size]
        # circular convolution of the pattern with the kernel, by FFT once
        self.energy = np.real(np.fft.ifft2(np.fft.fft2(self.pattern) * np.fft.fft2(g)))

    def flip(self, flat: int) -> None:
        """Turn cell ``flat`` from majority to minority or back; update the energy in O(N)."""
        i, j = divmod(flat, self.size)
        n = self.size
        sign = -1.0 if self.pattern[i, j] else 1.0
        self.pattern[i, j] = not self.pattern[i, j]
        self.energy += sign * self.kernel[n - i:2 * n - i, n - j:2 * n - j]

    def tightest_cluster(self) -> int:
        """The minority cell of highest energy (the first in row-major order on a tie)."""
        return int(np.argmax(np.where(self.pattern, self.energy, -np.inf)))

    def largest_void(self) -> int:
        """The majority cell of lowest energy (the first in row-major order on a tie)."""
        return int(np.argmin(np.where(self.pattern, np.inf, self.energy)))


def void_and_cluster(size: int = BLUE_TILE, *, sigma: float = SIGMA, initial_fraction: float = INITIAL_FRACTION,
                     seed=0) -> np.ndarray:
    """A (size, size) blue-noise dither array: the ranks 0 .. size^2 - 1 by void and cluster.

    Parameters
    ----------
    size : int, optional
        Edge of the toroidal array (>= 2, default 64).
    sigma : float, optional
        Width of the Gaussian energy filter, in cells (> 0; default 1.5, the paper's).
    initial_fraction : float, optional
        Fraction of cells set in the initial random pattern, in (0, 0.5] (default 0.1); at
        least one cell is set.
    seed : int, numpy.random.Generator or None, optional
        Seed of the initial random pattern (default 0); the rest is deterministic.

    Returns
    -------
    (size, size) ndarray of int64
        A permutation of 0 .. size^2 - 1: for every k, the cells of rank < k form a binary
        pattern with few low frequencies.

    Raises
    ------
    ValueError
        If an argument is out of range (the message names it).

    Notes
    -----
    The steps of Ulichney 1993 [1]_: the energy of a cell is the sum of
    exp(-r^2 / (2 sigma^2)) over the minority cells, r the toroidal distance (the
    filter with wrap-around). Initial binary pattern: ``initial_fraction`` of the cells set
    at random, then the tightest cluster moved to the largest void until the void found is
    the cell just removed (at most size^2 moves). Phase 1: from that prototype, the tightest cluster is
    removed and ranked, from the number of set cells - 1 down to 0. Phase 2: from the
    prototype, the largest void is set and ranked, up to half the cells. Phase 3: the unset
    cells are now the minority; the tightest cluster of *unset* cells (their own energy) is
    set and ranked, up to size^2 - 1. Ties go to the first cell in row-major order.
    Each step adds or subtracts one copy of the kernel (:class:`_Energy`), O(size^2).

    References
    ----------
    .. [1] R. Ulichney, "The void-and-cluster method for dither array generation", Proc. SPIE
       1913 (1993).

    Examples
    --------
    >>> r = void_and_cluster(8, seed=0)
    >>> r.shape, sorted(r.ravel().tolist()) == list(range(64))
    ((8, 8), True)
    """
    size = check_int(size, "size", minimum=2)
    sigma = check_positive(sigma, "sigma")
    initial_fraction = float(check_positive(initial_fraction, "initial_fraction"))
    if initial_fraction > 0.5:
        raise ValueError(f"initial_fraction must be in (0, 0.5], got {initial_fraction!r}")
    rng = as_rng(seed)
    n = size * size
    kernel = _kernel(size, float(sigma))

    # initial binary pattern: random minority cells
    ones = max(1, int(round(initial_fraction * n)))
    pattern = np.zeros((size, size), dtype=bool)
    pattern.flat[rng.choice(n, size=ones, replace=False)] = True
    # ... made homogeneous: the tightest cluster moves to the largest void until it stays
    e = _Energy(pattern, kernel)
    for _ in range(n):           # a bound against a cycle of moves; each move is O(N)
        cluster = e.tightest_cluster()
        e.flip(cluster)
        void = e.largest_void()
        if void == cluster:
            e.flip(cluster)
            break
        e.flip(void)
    prototype = e.pattern.copy()
    ranks = np.full(n, -1, dtype=np.int64)

    # Phase 1: remove the tightest clusters, ranks ones - 1 .. 0
    e = _Energy(prototype, kernel)
    for rank in range(ones - 1, -1, -1):
        cluster = e.tightest_cluster()
        e.flip(cluster)
        ranks[cluster] = rank

    # Phase 2: fill the largest voids, ranks ones .. n/2 - 1
    e = _Energy(prototype, kernel)
    half = n // 2
    for rank in range(ones, half):
        void = e.largest_void()
        e.flip(void)
        ranks[void] = rank

    # Phase 3: the unset cells are the minority; set the tightest cluster of them, ranks n/2 .. n - 1
    e = _Energy(~e.pattern, kernel)
    for rank in range(half, n):
        cluster = e.tightest_cluster()
        e.flip(cluster)
        ranks[cluster] = rank
    return ranks.reshape(size, size)


def ranks_to_uniforms(ranks) -> np.ndarray:
    """The values (rank + 0.5) / N in (0, 1) of a dither array of N cells: the centres of N
    equal bins, one per cell.

    Examples
    --------
    >>> ranks_to_uniforms(np.array([[0, 3], [1, 2]])).tolist()
    [[0.125, 0.875], [0.375, 0.625]]
    """
    ranks = np.asarray(ranks)
    return (ranks + 0.5) / ranks.size


def _generate() -> dict:
    """The arrays and provenance of ``data/bluenoise64.npz``."""
    u1 = void_and_cluster(BLUE_TILE, sigma=SIGMA, initial_fraction=INITIAL_FRACTION, seed=BLUE_SEEDS[0])
    u2 = void_and_cluster(BLUE_TILE, sigma=SIGMA, initial_fraction=INITIAL_FRACTION, seed=BLUE_SEEDS[1])
    provenance = dict(generator="vobscure.screenspace.bluenoise.void_and_cluster", method="Ulichney 1993",
                      size=BLUE_TILE, sigma=SIGMA, initial_fraction=INITIAL_FRACTION,
                      seeds=dict(u1=BLUE_SEEDS[0], u2=BLUE_SEEDS[1]), numpy=np.__version__,
                      command="python -m vobscure.screenspace.bluenoise")
    return dict(u1=u1.astype(np.uint16), u2=u2.astype(np.uint16), provenance=np.array(json.dumps(provenance)))


@functools.lru_cache(maxsize=1)
def blue_ranks() -> np.ndarray:
    """(64, 64, 2) the stored ranks of the ``"blue"`` schedule's u1 and u2 arrays (int64, read
    once and cached; do not modify the returned array)."""
    with np.load(_DATA) as f:
        out = np.stack([f["u1"], f["u2"]], axis=-1).astype(np.int64)
    out.flags.writeable = False
    return out


if __name__ == "__main__":       # regenerate the stored arrays
    _DATA.parent.mkdir(exist_ok=True)
    np.savez_compressed(_DATA, **_generate())
    print(f"wrote {_DATA}")
