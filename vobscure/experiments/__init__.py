"""Experiments: the comparison behind ``vobscure compare``, parameter sweeps, the reference
cache, and the figure modules (``figures/``).

Submodules are imported on first use (``vobscure.experiments.compare`` etc.), so that
``import vobscure`` stays light.
"""

import importlib

__all__ = ["cache", "claims", "compare", "figures", "sweep"]


def __getattr__(name):
    if name in __all__:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
