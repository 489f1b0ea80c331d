"""Build the FMI 2.0 co-simulation FMU of a scene: ``prandtl-fmu build`` as a top-level script.

    python build_fmu.py [SCENE] [-o OUT.fmu]

SCENE: a scene file or a packaged scene's name (default: paper-section-8);
default output: <scene name>.fmu in the current folder. Prints the path of
the FMU. A bad scene exits with status 2 and one line naming the file, the
key and the rule.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # runs from a checkout without an install

from prandtl_fmu.cli import main  # noqa: E402

if __name__ == "__main__":
    arguments = sys.argv[1:]
    if not arguments or arguments[0].startswith("-") and arguments[0] not in ("-h", "--help"):
        arguments = ["paper-section-8"] + arguments
    sys.exit(main(["build"] + arguments))
