"""``python -m prandtl_fmu``: the command line (``cli.py``), as the ``prandtl-fmu`` script runs it."""
import sys

from .cli import main

sys.exit(main())
