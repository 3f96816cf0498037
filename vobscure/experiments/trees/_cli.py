"""The two command lines of :mod:`vobscure.experiments.trees`: every measurement as Markdown
tables (:func:`main`) and the Poisson rows alone (:func:`poisson_main`)."""

from __future__ import annotations

from . import _canopy, _ground, _tradeoff
from ._common import _measurements, setting
from ._poisson import ELLIPSOID_MAP_COLUMNS, POISSON_COLUMNS, ellipsoid_map_rows, poisson_rows

#: The tables of :func:`main`, in order: name -> (function of the rows, their columns).
_TABLES = {"canopy": (_canopy.canopy_rows, _canopy.CANOPY_COLUMNS),
           "ground": (_ground.ground_rows, _ground.GROUND_COLUMNS),
           "grass": (_ground.grass_rows, _ground.GRASS_COLUMNS),
           "weighting": (_tradeoff.weighting_rows, _tradeoff.WEIGHTING_COLUMNS),
           "convergence": (_tradeoff.convergence_rows, _tradeoff.CONVERGENCE_COLUMNS),
           "tradeoff": (_tradeoff.tradeoff_rows, _tradeoff.TRADEOFF_COLUMNS),
           "cost": (_tradeoff.cost_rows, _tradeoff.COST_COLUMNS)}


def all_rows(quick: bool = False, *, seed: int = 0, measurements=None) -> dict:
    """Every measurement, by name (the order of :func:`main`'s tables), all of one
    :class:`Measurements` (``measurements``, default a new one)."""
    run = _measurements(quick, seed, measurements)
    return {name: rows(quick, seed=seed, measurements=run) for name, (rows, _) in _TABLES.items()}


def main(argv=None) -> int:
    """``python -m vobscure.experiments.trees [--quick] [--seed N] [--out DIR] [--poisson]``: run
    every measurement (with ``--poisson`` only :func:`poisson_rows` and
    :func:`ellipsoid_map_rows`, :func:`poisson_main`), print Markdown tables and, with
    ``--out``, write one CSV per table and a ``trees.json`` with the machine record."""
    import argparse
    import time
    from pathlib import Path

    from ..common import machine, markdown_table, write_csv, write_json

    ap = argparse.ArgumentParser(prog="python -m vobscure.experiments.trees")
    ap.add_argument("--quick", action="store_true", help="small and fast (what CI runs)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="directory for the CSV tables and trees.json")
    ap.add_argument("--poisson", action="store_true",
                    help="only the Poisson leaf cloud against Eq. 6 (poisson_rows; trees_poisson.csv)")
    args = ap.parse_args(argv)
    if args.poisson:
        return poisson_main([*(["--quick"] if args.quick else []), "--seed", str(args.seed),
                             *(["--out", args.out] if args.out else [])])
    t0 = time.perf_counter()
    tables = all_rows(args.quick, seed=args.seed)
    elapsed = time.perf_counter() - t0
    for name, rows in tables.items():
        cols = _TABLES[name][1]
        if name == "ground":
            rows = [r for r in rows if r["distance"] is None] + [r for r in rows if r["distance"] is not None]
        print(f"\n## {name}\n")
        print(markdown_table(rows, cols))
    print(f"\n{elapsed:.1f} s, settings {setting(args.quick)}, machine {machine()}")
    if args.out:
        out = Path(args.out)
        for name, rows in tables.items():
            write_csv(out / f"trees_{name}.csv", rows, _TABLES[name][1], digits=6)
        write_json(out / "trees.json", {"quick": args.quick, "seed": args.seed, "seconds": elapsed,
                                        "settings": setting(args.quick), "machine": machine()})
    return 0


def poisson_main(argv=None) -> int:
    """:func:`poisson_rows` and :func:`ellipsoid_map_rows` as Markdown tables (and
    ``trees_poisson.csv``, ``trees_poisson_ellipsoid_map.csv`` with ``--out``): what
    ``python -m vobscure.experiments.trees --poisson [--quick] [--seed N] [--out DIR]`` runs."""
    import argparse
    import time
    from pathlib import Path

    from ..common import machine, markdown_table, write_csv

    ap = argparse.ArgumentParser(prog="python -m vobscure.experiments.trees --poisson")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = poisson_rows(args.quick, seed=args.seed)
    print(markdown_table(rows, POISSON_COLUMNS))
    emap = ellipsoid_map_rows(args.quick, seed=args.seed)
    print("\n## the ellipsoid's affine map against the true ellipsoid\n")
    print(markdown_table(emap, ELLIPSOID_MAP_COLUMNS))
    print(f"\n{time.perf_counter() - t0:.1f} s, machine {machine()}")
    if args.out:
        write_csv(Path(args.out) / "trees_poisson.csv", rows, POISSON_COLUMNS, digits=6)
        write_csv(Path(args.out) / "trees_poisson_ellipsoid_map.csv", emap, ELLIPSOID_MAP_COLUMNS, digits=6)
    return 0
