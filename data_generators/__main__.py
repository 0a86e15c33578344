"""``python -m data_generators``: the command line of ``spectral_igl.data_generators``."""
import sys

from spectral_igl.data_generators.__main__ import main

if __name__ == "__main__":
    sys.exit(main())
