"""The command line of the pattern tables: ``python -m vobscure.patterns build|rescore``.

``build [--quick] [--jobs N] [--methods ...] [--domain disk|ball|both] [--dir DIR]`` regenerates
the tables (:func:`~vobscure.patterns.precomputed.build_tables`); ``rescore [--domain ...]
[--dir DIR]`` re-records the quality of the existing ones
(:func:`~vobscure.patterns.precomputed.rescore_tables`).

A package ``__main__`` (rather than ``if __name__ == "__main__"`` in the package) so that
``python -m`` runs the one imported ``vobscure.patterns`` (which ``import vobscure`` has
already loaded) without runpy's double-import warning, and worker processes see it too.
"""

from __future__ import annotations

import argparse
import sys
import time

from vobscure.patterns.generators import METHODS
from vobscure.patterns.precomputed import TABLE_DIR, build_tables, rescore_tables

#: The dimensions of each ``--domain`` choice.
DOMAINS = {"disk": (2,), "ball": (3,), "both": (2, 3)}


def main(argv=None) -> int:
    """Run ``build`` or ``rescore`` with the arguments ``argv`` (default ``sys.argv[1:]``).

    Parameters
    ----------
    argv : list of str, optional

    Returns
    -------
    int
        The exit status, 0.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     main(["rescore", "--dir", d])      # an empty directory: no table to re-score
    0
    """
    parser = argparse.ArgumentParser(prog="python -m vobscure.patterns",
                                     description="Precomputed sample-pattern tables (data/patterns/).")
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build", help="generate the tables")
    b.add_argument("--quick", action="store_true", help="only n <= 4 of every family")
    b.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    b.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    b.add_argument("--domain", choices=tuple(DOMAINS), default="both")
    b.add_argument("--dir", default=None, help=f"output directory (default {TABLE_DIR})")
    b.add_argument("--no-progress", action="store_true")
    r = sub.add_parser("rescore", help="re-evaluate the recorded quality of the existing tables "
                                       "(points and weights kept)")
    r.add_argument("--domain", choices=tuple(DOMAINS), default="ball")
    r.add_argument("--dir", default=None, help=f"table directory (default {TABLE_DIR})")
    args = parser.parse_args(argv)
    dims = DOMAINS[args.domain]
    t0 = time.perf_counter()
    if args.command == "rescore":
        paths = rescore_tables(args.dir, dims=dims)
    else:
        paths = build_tables(args.dir, quick=args.quick, methods=args.methods, dims=dims, jobs=args.jobs,
                             progress=not args.no_progress)
    for p in paths:
        print(p)
    print(f"{len(paths)} tables in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
