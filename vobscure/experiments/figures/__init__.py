"""Figure modules: one module per figure, each with ``make(out_dir, quick=False) -> list[Path]``.

``quick=True`` draws the same figure with fewer samples and smaller images, in seconds; CI
runs every figure that way. Figures are drawn on matplotlib ``Figure`` objects with the Agg
canvas (never ``pyplot``, never a display) and written atomically.
"""

__all__ = ["conventions", "screenspace_claims"]
