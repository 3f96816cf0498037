"""The object-space experiment (vobscure.experiments.objectspace): its rows are the errors of
Bunnell's estimates against the ray-cast AO."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.objectspace import bunnell, vertex_disks

#: The rows and this test compute the same float64 sums.
EXACT = 1e-12


def test_experiment_rows_are_the_errors_of_the_estimates():
    from vobscure.experiments.objectspace import VARIANTS, WEIGHTINGS, objectspace_rows

    rows = objectspace_rows(["groove"], terms=["gpugems"], quick=True)
    assert len(rows) == 2 * len(VARIANTS) * len(WEIGHTINGS)
    scene = vo.scenes.get("groove")
    p, n, _ = vertex_disks(scene)          # fewer vertices than the quick subset: all of them
    ref = vo.ambient_occlusion(scene, p, n, rays=64, weighting="uniform", max_distance=np.inf, seed=0)
    err = bunnell(scene, passes=2) - ref.value
    row = next(r for r in rows if (r["where"], r["passes"], r["weighting"]) == ("vertex", "2", "uniform"))
    assert row["rmse"] == pytest.approx(np.sqrt(np.mean(err ** 2)), abs=EXACT)
    assert row["bias"] == pytest.approx(err.mean(), abs=EXACT)
    assert row["ref_stderr"] == pytest.approx(ref.stderr.mean(), abs=EXACT)
    gb = vo.render_gbuffer(scene, scene.camera((32, 32)))
    assert all(r["receivers"] == int(gb.valid.sum()) for r in rows if r["where"] == "pixel")

