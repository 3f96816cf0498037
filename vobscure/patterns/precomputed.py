"""The precomputed pattern tables: reading, the defaults they give, building and re-scoring.

One ``.npz`` per family ``{domain}_{method}_{variant}.npz`` in :data:`TABLE_DIR` (package data;
``data/patterns/`` in the repository links to it), with its provenance: generator, version,
parameters, seed and the recorded :func:`~vobscure.patterns.quality` of every entry.
``python -m vobscure.patterns build`` regenerates them, ``rescore`` re-records the quality.
"""

from __future__ import annotations

import contextlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from .._io import save_npz
from .._validate import check_choice, check_int
from . import generators
from ._layout import OPTIMIZATION_CELLS, OPTIMIZATION_GRID
from ._pattern import DOMAIN, SamplePattern, equal_integral_error, exact_pattern, voronoi_regions, weighted_cells, \
    weights_grid
from .generators import GENERATOR, METHODS
from .metric import QUALITY_NOTES, QUALITY_SEED, QUALITY_TRIALS, QUALITY_VERSION, quality

__all__ = ["load_table", "build_tables", "rescore_tables", "TABLE_DIR", "TABLE_N", "TABLE_EXTRA_N", "VARIANTS"]

#: Where the precomputed tables live: inside the package (package data, so that a wheel
#: carries them); the repository's documented path ``data/patterns/`` is a symbolic link here.
TABLE_DIR = Path(__file__).resolve().parent / "tables"
#: Pattern counts of the tables (n = 1..N), per dimension.
TABLE_N = {2: 33, 3: 40}
#: Further counts in the symmetric electrostatic and Lloyd tables (the candidates of the
#: default): the sizes the screen-space estimators and their tests ask for beyond n <= 33.
TABLE_EXTRA_N = (64, 65, 128, 129, 256, 257)
#: The table families per dimension: symmetric (the centre exactly for odd n), plain with the
#: centre forced, plain without.
VARIANTS = {2: ("symmetric", "center", "plain"), 3: ("symmetric", "plain")}
#: The dimension of each domain.
DIM = {"disk": 2, "ball": 3}
#: The command recorded in the provenance of a build.
BUILD_COMMAND = "python -m vobscure.patterns build"


def variant_of(symmetric: bool, center: bool) -> str:
    """The table variant of a pattern: ``"symmetric"``, ``"center"`` or ``"plain"``."""
    return "symmetric" if symmetric else ("center" if center else "plain")


def variant_flags(variant: str, n: int) -> tuple[bool, bool]:
    """(symmetric, center) of a table variant at count n."""
    if variant == "symmetric":
        return True, n % 2 == 1
    return False, variant == "center"


def table_path(dim: int, method: str, variant: str, directory=None) -> Path:
    """The file of one table family in ``directory`` (default :data:`TABLE_DIR`)."""
    return Path(TABLE_DIR if directory is None else directory) / f"{DOMAIN[dim]}_{method}_{variant}.npz"


def table_counts(dim: int, method: str, variant: str, quick: bool = False) -> list[int]:
    """The counts n a table holds (``quick``: the subset ``build --quick`` regenerates)."""
    top = 4 if quick else TABLE_N[dim]
    counts = list(range(1, top + 1))
    if not quick and method in generators.OPTIMIZERS and variant == "symmetric":
        counts += list(TABLE_EXTRA_N)
    return counts


def _jsonable(value):
    """Round-trip through JSON, so that recorded and current parameters compare equal."""
    return json.loads(json.dumps(value))


@lru_cache(maxsize=64)
def read_table(path: str):
    """The table at ``path`` as {n: (points, weights, entry)} plus its provenance; None if
    the file is missing or unreadable."""
    try:
        with np.load(path, allow_pickle=False) as z:
            prov = json.loads(str(z["provenance"]))
            counts, offsets = z["counts"], z["offsets"]
            points, weights = z["points"], z["weights"]
    except (OSError, KeyError, ValueError):
        return None
    entries = {}
    for i, n in enumerate(counts.tolist()):
        p = points[offsets[i]:offsets[i + 1]]
        w = weights[offsets[i]:offsets[i + 1]]
        p.flags.writeable = False
        w.flags.writeable = False
        entries[n] = (p, w, prov["entries"][str(n)])
    return prov, entries


def _usable(prov: dict, dim: int, method: str, seed) -> bool:
    """A table is used only when it was written by this generator version with the current
    parameters and the requested seed."""
    return (prov.get("version") == generators.GENERATOR_VERSION and prov.get("seed") == seed
            and prov.get("domain") == DOMAIN[dim] and prov.get("method") == method
            and prov.get("parameters") == _jsonable(generators.GENERATORS[method][1]))


def table_entry(dim, method, symmetric, center, n, seed, directory=None) -> SamplePattern | None:
    """The table's pattern for this count, variant and seed; None when no usable table holds it."""
    if not symmetric and dim == 3 and center:
        return None
    variant = variant_of(symmetric, center)
    path = table_path(dim, method, variant, directory)
    table = read_table(str(path))
    if table is None:
        return None
    prov, entries = table
    if n not in entries or not _usable(prov, dim, method, seed):
        return None
    points, weights, entry = entries[n]
    record = generators.provenance(dim, n, method, symmetric, center, seed, generators.GENERATORS[method][1])
    record.update(source=f"table {path.name}", **entry)
    return exact_pattern(points, weights, method, record)


def load_table(domain: str, method: str = "electrostatic", *, variant: str = "symmetric",
               directory=None) -> dict[int, SamplePattern]:
    """Every pattern of one precomputed table, by count n.

    Parameters
    ----------
    domain : {"disk", "ball"}
    method : str, optional
        One of :data:`METHODS`.
    variant : {"symmetric", "center", "plain"}, optional
        ``"symmetric"``: antipodal pairs (the centre for odd n); ``"center"``: the centre
        forced (disk only); ``"plain"``: no centre forced.
    directory : path-like, optional
        Default :data:`TABLE_DIR` (``data/patterns/`` in the repository).

    Returns
    -------
    dict of int to SamplePattern
        Empty when the table is missing or was written by another generator version or
        with other parameters. Each pattern's ``provenance`` holds the table's record for it
        (seconds, quality and its standard error).

    Examples
    --------
    >>> table = load_table("disk", "electrostatic", variant="symmetric")
    >>> table[9].is_symmetric, table[9].provenance["source"]
    (True, 'table disk_electrostatic_symmetric.npz')
    """
    check_choice(domain, "domain", ("disk", "ball"))
    check_choice(method, "method", METHODS)
    dim = DIM[domain]
    check_choice(variant, "variant", VARIANTS[dim])
    path = table_path(dim, method, variant, directory)
    table = read_table(str(path))
    if table is None:
        return {}
    prov, entries = table
    if not _usable(prov, dim, method, prov.get("seed")):
        return {}
    out = {}
    for n in entries:
        symmetric, center = variant_flags(variant, n)
        out[n] = table_entry(dim, method, symmetric, center, n, prov["seed"], directory)
    return out


def _copy(p: SamplePattern) -> SamplePattern:
    return exact_pattern(p.points.copy(), p.weights, p.method, json.loads(json.dumps(p.provenance)))


@lru_cache(maxsize=256)
def _table_or_generated(dim, n, method, symmetric, center, seed) -> SamplePattern:
    entry = table_entry(dim, method, symmetric, center, n, seed)
    if entry is not None:
        return entry
    return generators.generate(dim, n, method, symmetric, center, seed)


def table_or_generated(dim: int, n: int, method: str, symmetric: bool, center: bool, seed: int) -> SamplePattern:
    """The table's pattern when a table holds it, else a generated one; cached, returned as a copy
    (the caller may change its provenance)."""
    return _copy(_table_or_generated(dim, n, method, symmetric, center, seed))


@lru_cache(maxsize=512)
def recorded_qualities(dim: int, n: int, symmetric: bool, center: bool) -> dict:
    """{method: recorded quality} of the seed-0 table entries for this count and variant, in
    the order of :data:`~vobscure.patterns.METHODS`; cached (do not change it)."""
    scores = {}
    for method in METHODS:
        entry = table_entry(dim, method, symmetric, center, n, 0)
        if entry is not None:
            scores[method] = entry.provenance["quality"]
    return scores


def clear_caches() -> None:
    """Forget every table read and every pattern cached from them (after a table changed)."""
    read_table.cache_clear()
    _table_or_generated.cache_clear()
    recorded_qualities.cache_clear()


def _build_one(task):
    """Generate one table entry and measure it (runs in a worker process)."""
    dim, method, variant, n, seed = task
    symmetric, center = variant_flags(variant, n)
    p = generators.generate(dim, n, method, symmetric, center, seed)
    q = quality(p)
    _, m, _ = voronoi_regions(p.points, *weighted_cells(dim, weights_grid(dim)))
    return task, p.points, p.weights, {
        "seconds": p.provenance["seconds"], "quality": float(q.value), "quality_stderr": float(q.stderr),
        "equal_integral_error": equal_integral_error(m)}


def _software() -> dict:
    """Versions of Python, NumPy and SciPy, and NumPy's disabled SIMD kernels when any are
    (``NPY_DISABLE_CPU_FEATURES``: they can change the last bits of a result)."""
    import os
    import platform

    import scipy

    out = {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__}
    if os.environ.get("NPY_DISABLE_CPU_FEATURES", "").strip():
        out["NPY_DISABLE_CPU_FEATURES"] = os.environ["NPY_DISABLE_CPU_FEATURES"].strip()
    return out


def _write_table(path: Path, dim: int, method: str, variant: str, seed: int, entries: dict, *,
                 generated: dict | None = None, command: str = BUILD_COMMAND) -> Path:
    """Write one table atomically. ``entries``: {n: (points, weights, record)}.

    ``generated``: the provenance of the table the points come from, when they were not
    generated by this call (:func:`rescore_tables`): its ``command`` and ``software`` are kept
    as the generation's, and the quality record names ``command`` and this software.
    """
    counts = sorted(entries)
    offsets = np.concatenate([[0], np.cumsum([len(entries[n][0]) for n in counts])])
    software = _software()
    prov = {
        "generator": GENERATOR, "version": generators.GENERATOR_VERSION, "domain": DOMAIN[dim],
        "method": method, "variant": variant,
        "symmetric": variant == "symmetric",
        "center": {"symmetric": "exactly for odd n", "center": "forced", "plain": "not forced"}[variant],
        "seed": seed, "parameters": _jsonable(generators.GENERATORS[method][1]),
        "weights_grid": weights_grid(dim),
        "optimization_grid": {"base": OPTIMIZATION_GRID[dim], "cells_per_region": OPTIMIZATION_CELLS},
        "quality": {"function": "vobscure.patterns.quality", "trials": QUALITY_TRIALS,
                    "seed": QUALITY_SEED, "family": "mixed", "version": QUALITY_VERSION,
                    "note": QUALITY_NOTES[QUALITY_VERSION], "command": command, "software": software},
        "command": command if generated is None else generated["command"],
        "software": software if generated is None else generated["software"],
        "entries": {str(n): entries[n][2] for n in counts},
    }
    arrays = {
        "counts": np.array(counts, dtype=np.int64),
        "offsets": offsets.astype(np.int64),
        "points": np.concatenate([entries[n][0] for n in counts], axis=0),
        "weights": np.concatenate([entries[n][1] for n in counts]),
        "quality": np.array([entries[n][2]["quality"] for n in counts]),
        "quality_stderr": np.array([entries[n][2]["quality_stderr"] for n in counts]),
    }
    save_npz(path, prov, **arrays)
    clear_caches()
    return path

def _families(methods, dims) -> list[tuple[int, str, str]]:
    """(dim, method, variant) of every table family of ``methods`` and ``dims``, methods validated."""
    for m in methods:
        check_choice(m, "methods", METHODS)
    return [(dim, m, v) for dim in dims for m in methods for v in VARIANTS[dim]]


def build_tables(directory=None, *, quick: bool = False, methods=METHODS, dims=(2, 3), jobs: int = 1,
                 seed: int = 0, progress: bool = False) -> list[Path]:
    """Generate the pattern tables and write one ``.npz`` per family (atomically).

    Parameters
    ----------
    directory : path-like, optional
        Default :data:`TABLE_DIR`.
    quick : bool, optional
        Regenerate only n <= 4 of every family (seconds to a minute). Entries already in a
        table that was written by this generator version with the same parameters and seed
        are kept; the regenerated ones replace theirs.
    methods : sequence of str, optional
    dims : sequence of {2, 3}, optional
        2: the disk tables, 3: the ball tables.
    jobs : int, optional
        Worker processes.
    seed : int, optional
        Seed of every generator call (the tables of :func:`disk` / :func:`ball` use 0).
    progress : bool, optional
        A tqdm bar over the patterns.

    Returns
    -------
    list of Path
        The files written.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     paths = build_tables(d, quick=True, methods=("spiral",), dims=(2,), progress=False)
    ...     sorted(load_table("disk", "spiral", variant="plain", directory=d))
    [1, 2, 3, 4]
    >>> [p.name for p in paths]
    ['disk_spiral_symmetric.npz', 'disk_spiral_center.npz', 'disk_spiral_plain.npz']
    """
    from tqdm.auto import tqdm

    families = _families(methods, dims)
    jobs = check_int(jobs, "jobs")
    seed = check_int(seed, "seed", minimum=0)
    tasks = [(dim, m, v, n, seed) for dim, m, v in families for n in table_counts(dim, m, v, quick)]
    # the expensive ones first, so that the workers finish together
    tasks.sort(key=lambda t: (t[1] not in generators.OPTIMIZERS, -t[3] * (1 + (t[0] == 3))))
    results: dict = {f: {} for f in families}
    with contextlib.ExitStack() as stack:
        bar = stack.enter_context(tqdm(total=len(tasks), desc="patterns", unit="pattern", disable=not progress))
        if jobs == 1:
            mapper = map
        else:
            from concurrent.futures import ProcessPoolExecutor

            mapper = stack.enter_context(ProcessPoolExecutor(max_workers=jobs)).map
        for task, pts, w, entry in mapper(_build_one, tasks):
            results[task[:3]][task[3]] = (pts, w, entry)
            bar.update(1)
    written = []
    for (dim, method, variant), new in results.items():
        path = table_path(dim, method, variant, directory)
        entries = {}
        table = read_table(str(path))
        if table is not None and _usable(table[0], dim, method, seed):
            entries = {n: (p, w, e) for n, (p, w, e) in table[1].items() if n not in new}
            if table[0].get("quality", {}).get("version", 1) != QUALITY_VERSION:
                entries = _rescored(entries, method)         # kept entries, current metric
        entries.update(new)
        written.append(_write_table(path, dim, method, variant, seed, entries))
    return written


def rescore_tables(directory=None, *, methods=METHODS, dims=(3,)) -> list[Path]:
    """Re-evaluate the recorded quality of every entry of the existing tables with the current
    :func:`quality` and rewrite them (atomically), points and weights bit for bit.

    For a change of the metric alone (:data:`QUALITY_VERSION`): the generation's command and
    software stay in the provenance, the quality record names the re-evaluation. A missing
    table, or one written by another generator version or with other parameters, is skipped.

    Parameters
    ----------
    directory : path-like, optional
        Default :data:`TABLE_DIR`.
    methods : sequence of str, optional
    dims : sequence of {2, 3}, optional
        2: the disk tables, 3: the ball tables (default: the ball, the tables the centre
        sample of :data:`QUALITY_VERSION` 2 changes).

    Returns
    -------
    list of Path
        The files rewritten.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = build_tables(d, quick=True, methods=("spiral",), dims=(3,), progress=False)
    ...     [p.name for p in rescore_tables(d, methods=("spiral",))]
    ['ball_spiral_symmetric.npz', 'ball_spiral_plain.npz']
    """
    written = []
    for dim, method, variant in _families(methods, dims):
        path = table_path(dim, method, variant, directory)
        table = read_table(str(path))
        if table is None or not _usable(table[0], dim, method, table[0].get("seed")):
            continue
        prov, entries = table
        written.append(_write_table(path, dim, method, variant, prov["seed"], _rescored(entries, method),
                                    generated=prov,
                                    command=f"python -m vobscure.patterns rescore --domain {DOMAIN[dim]}"))
    return written


def _rescored(entries: dict, method: str) -> dict:
    """Table entries {n: (points, weights, record)} with the record's quality and its standard
    error evaluated afresh by :func:`quality`."""
    out = {}
    for n, (points, weights, record) in entries.items():
        q = quality(exact_pattern(points, weights, method, {}))
        out[n] = (points, weights, dict(record, quality=float(q.value), quality_stderr=float(q.stderr)))
    return out
