"""Experiments: the comparison behind ``vobscure compare``, parameter sweeps, the reference
cache, and the figure modules (``figures/``).

:func:`sweep` runs :class:`SweepConfig` configurations on any executor (module
:mod:`vobscure.experiments.sweeps`). Submodules and these names are imported on first use
(``vobscure.experiments.compare`` etc.), so that ``import vobscure`` stays light.
"""

import importlib

#: The submodules.
_MODULES = ("cache", "claims", "compare", "figures", "sweeps", "temporal")
#: Names of :mod:`vobscure.experiments.sweeps` exported here.
_SWEEPS = ("sweep", "SweepConfig", "SweepResult", "InlineExecutor", "results_to_csv", "results_to_markdown")

__all__ = [*_MODULES, *_SWEEPS]


def __getattr__(name):
    if name in _MODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if name in _SWEEPS:
        return getattr(importlib.import_module(f"{__name__}.sweeps"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
