"""The two command lines of :mod:`vobscure.experiments.trees`: every measurement as Markdown
tables (:func:`main`) and the Poisson rows alone (:func:`poisson_main`)."""

from __future__ import annotations

from ._canopy import CANOPY_COLUMNS, canopy_rows
from ._common import setting
from ._ground import GRASS_COLUMNS, GROUND_COLUMNS, grass_rows, ground_rows
from ._poisson import ELLIPSOID_MAP_COLUMNS, POISSON_COLUMNS, ellipsoid_map_rows, poisson_rows
from ._tradeoff import (
    CONVERGENCE_COLUMNS,
    COST_COLUMNS,
    TRADEOFF_COLUMNS,
    WEIGHTING_COLUMNS,
    convergence_rows,
    cost_rows,
    tradeoff_rows,
    weighting_rows,
)

def all_rows(quick: bool = False, *, seed: int = 0) -> dict:
    """Every measurement, by name (the order of :func:`main`'s tables)."""
    return {"canopy": canopy_rows(quick, seed=seed), "ground": ground_rows(quick, seed=seed),
            "grass": grass_rows(quick, seed=seed), "weighting": weighting_rows(quick, seed=seed),
            "convergence": convergence_rows(quick, seed=seed), "tradeoff": tradeoff_rows(quick, seed=seed),
            "cost": cost_rows(quick, seed=seed)}

_TABLE_COLUMNS = {"canopy": CANOPY_COLUMNS, "ground": GROUND_COLUMNS, "grass": GRASS_COLUMNS,
                  "weighting": WEIGHTING_COLUMNS, "convergence": CONVERGENCE_COLUMNS,
                  "tradeoff": TRADEOFF_COLUMNS, "cost": COST_COLUMNS}

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
        cols = _TABLE_COLUMNS[name]
        if name == "ground":
            rows = [r for r in rows if r["distance"] is None] + [r for r in rows if r["distance"] is not None]
        print(f"\n## {name}\n")
        print(markdown_table(rows, cols))
    print(f"\n{elapsed:.1f} s, settings {setting(args.quick)}, machine {machine()}")
    if args.out:
        out = Path(args.out)
        for name, rows in tables.items():
            write_csv(out / f"trees_{name}.csv", rows, _TABLE_COLUMNS[name], digits=6)
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
