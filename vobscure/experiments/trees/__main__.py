"""``python -m vobscure.experiments.trees [--quick] [--seed N] [--out DIR] [--poisson]``:
:func:`vobscure.experiments.trees.main`.

A package ``__main__`` that only calls ``main`` (defined in the package), so that ``python -m``
runs the one imported package without runpy's double-import warning.
"""

from __future__ import annotations

import sys

from vobscure.experiments.trees import main

if __name__ == "__main__":
    sys.exit(main())
