"""Experiments: parameter sweeps, reference caches and the figure modules (``figures/``)."""
