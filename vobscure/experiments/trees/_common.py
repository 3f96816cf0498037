"""What every measurement of :mod:`vobscure.experiments.trees` shares: the scenes, the two
references, the sizes of a run, the :class:`Measurements` of a run, the ground truth and the
scores of a model against it."""

from __future__ import annotations

import functools

import numpy as np

from ...metrics import correlation

#: The scenes with a canopy (registered names of :func:`vobscure.scenes.get`): the sparse and
#: dense leaf clouds of Fig. 2 and the two trees (apple-like, poplar-like) of Figs. 3-9.
CANOPY_SCENES = ("leaf_cloud", "leaf_cloud_dense", "tree", "tree_poplar")

#: The scenes with a tree standing on the ground (Fig. 9's ground points).
TREE_SCENES = ("tree", "tree_poplar")

#: The grass field of Fig. 10.
GRASS_SCENE = "grass"

#: The two hemisphere integrals the models are scored against: ``weighting`` of
#: :func:`vobscure.groundtruth.ambient_occlusion`, with ``max_distance=inf``.
REFERENCES = ("cosine", "uniform")

#: Hegeman et al. 2006, Sec. 4: NVShaderPerf throughput of the three fragment shaders on a
#: GeForce 6800 Ultra, megapixels per second.
PAPER_MPS = {"hegeman": 460.0, "reeves_blau": 580.0, "ambient": 2300.0}

#: Sizes of a run (full, quick): points sampled per scene (half fit, half scored), rays of the
#: ground truth, ray counts of the convergence sweep, shells of the multi-shell fits, ring
#: distances (bounding-sphere radii) and points per ring of Fig. 9, grass points, bins,
#: points the models are timed on, and timing repeats.
SETTINGS = {
    False: {"points": 2048, "truth_rays": 1024, "rays": (4, 8, 16, 32, 64, 128, 256),
            "multi_k": (2, 3, 4, 5), "rings": (0.15, 0.3, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5),
            "ring_points": 64, "grass_points": 2048, "height_bins": 10, "cos_bins": 2,
            "timing_points": 65536, "raycast_timing_points": 8192, "repeats": 3},
    True: {"points": 96, "truth_rays": 64, "rays": (4, 8, 16),
           "multi_k": (2, 4), "rings": (0.3, 1.0, 2.0), "ring_points": 8, "grass_points": 96,
           "height_bins": 4, "cos_bins": 2, "timing_points": 4096, "raycast_timing_points": 96,
           "repeats": 1},
}


def setting(quick: bool) -> dict:
    """The sizes of a run (:data:`SETTINGS`), full or ``quick``."""
    return dict(SETTINGS[bool(quick)])


class Measurements:
    """The measurements of one run (``quick``, ``seed``) of this package, each made the first
    time a function asks for it and kept as long as this object lives.

    Every function of :mod:`vobscure.experiments.trees` takes one as its keyword
    ``measurements``; without it, the function makes its own, which is dropped when it returns.
    Pass the same object to several functions (the figures of a run get one from
    :func:`vobscure.experiments.figures.make`) and they share the points, ground truths,
    models and timings instead of measuring them again.

    Parameters
    ----------
    quick : bool, optional
        The sizes of the run (:func:`setting`).
    seed : int, optional
        Seed of every measurement of the run.

    Examples
    --------
    >>> m = Measurements(quick=True)
    >>> m.get("answer", lambda: 42), m.get("answer", lambda: 0)
    (42, 42)
    >>> Measurements(quick=1)
    Traceback (most recent call last):
    ...
    ValueError: quick must be True or False, got 1
    """

    def __init__(self, quick: bool = False, *, seed: int = 0):
        if not isinstance(quick, (bool, np.bool_)):
            raise ValueError(f"quick must be True or False, got {quick!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
        self.quick, self.seed = bool(quick), int(seed)
        self._made = {}

    def __repr__(self) -> str:
        return f"Measurements(quick={self.quick}, seed={self.seed}; {len(self._made)} made)"

    def get(self, key, make):
        """What is kept under ``key``; ``make()`` makes and keeps it the first time."""
        if key not in self._made:
            self._made[key] = make()
        return self._made[key]


def _measurements(quick, seed, given: Measurements | None) -> Measurements:
    """``given``, checked to be of this run (``quick``, ``seed``), or a new :class:`Measurements`."""
    if given is None:
        return Measurements(bool(quick), seed=int(seed))
    if not isinstance(given, Measurements):
        raise ValueError(f"measurements must be a Measurements, got {type(given).__name__}")
    if (given.quick, given.seed) != (bool(quick), int(seed)):
        raise ValueError(f"measurements are of quick={given.quick}, seed={given.seed}, not of "
                         f"quick={bool(quick)}, seed={int(seed)}")
    return given


def kept(fn):
    """``fn(run, *args)`` made once per :class:`Measurements` ``run`` and ``args``, kept in ``run``."""
    key = f"{fn.__module__}.{fn.__qualname__}"

    @functools.wraps(fn)
    def get(run: Measurements, *args):
        return run.get((key, *args), lambda: fn(run, *args))

    return get


@kept
def _scene(run: Measurements, name: str):
    from ... import scenes

    return scenes.get(name)


def _truth(scene, points, normals, reference, rays, seed):
    from ...groundtruth import ambient_occlusion

    return ambient_occlusion(scene, points, normals, rays=rays, weighting=reference,
                             max_distance=np.inf, seed=seed)


def _or_none(value: float) -> float | None:
    return None if np.isnan(value) else value


def _scores(model, truth: "Estimate") -> dict:   # noqa: F821 - Estimate of vobscure.estimate
    """RMSE, bias, MAE, Pearson r (None, an empty cell, where undefined: e.g. a constant
    model, density 0), means and the truth's RMS stderr of ``model`` against it."""
    model = np.asarray(model, dtype=np.float64)
    t = np.asarray(truth.value, dtype=np.float64)
    diff = model - t
    return {"rmse": float(np.sqrt(np.mean(diff ** 2))), "bias": float(np.mean(diff)),
            "mae": float(np.mean(np.abs(diff))), "corr": _or_none(correlation(model, t)),
            "model_mean": float(np.mean(model)), "truth_mean": float(np.mean(t)),
            "truth_stderr": float(np.sqrt(np.mean(np.asarray(truth.stderr, float) ** 2))),
            "points": int(len(t))}


def _sub(estimate, index):
    from ...estimate import Estimate

    return Estimate(value=np.asarray(estimate.value)[index], stderr=np.asarray(estimate.stderr)[index],
                    samples=estimate.samples)
