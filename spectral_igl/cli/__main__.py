"""``python -m spectral_igl.cli``: the ``spectral-igl`` command."""
import sys

from .command import main

if __name__ == "__main__":
    sys.exit(main())
