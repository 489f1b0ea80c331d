"""``python -m prandtl_fmu.fmu.python.loader``: rebuild the patched loader from its sources (see ``__init__.py``)."""
import subprocess
import sys

from . import build

if not (sys.platform.startswith("linux") and sys.maxsize > 2**32):
    raise SystemExit("the patched loader is built for Linux x86-64 only")
try:
    print(build())
except (OSError, subprocess.CalledProcessError) as exc:
    raise SystemExit(f"compiling the loader failed: {getattr(exc, 'stderr', None) or exc}")
