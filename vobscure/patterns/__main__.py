"""``python -m vobscure.patterns build [--quick] [--jobs N]``: regenerate the pattern tables.

A package ``__main__`` (rather than ``if __name__ == "__main__"`` in the module) so that
``python -m`` runs the one imported ``vobscure.patterns`` (which ``import vobscure`` has
already loaded) without runpy's double-import warning, and worker processes see it too.
"""

import sys

from vobscure.patterns import main

sys.exit(main())
