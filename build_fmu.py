"""Build the FMI 2.0 co-simulation FMU of a scene.

    python build_fmu.py [SCENE.toml] [-o OUT.fmu]

Default scene: scenes/paper-section-8.toml; default output: <scene name>.fmu
in the current folder. Prints the path of the FMU. A bad scene exits with
status 2 and one line naming the file, the key and the rule.
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from prandtl_fmu.fmu.build import build_fmu  # noqa: E402
from prandtl_fmu.scene import SceneError  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="Build the FMU of a scene (PythonFMU, FMI 2.0 co-simulation).")
    parser.add_argument("scene", nargs="?", default=os.path.join(HERE, "scenes", "paper-section-8.toml"),
                        help="scene file (default: scenes/paper-section-8.toml)")
    parser.add_argument("-o", "--out", help="FMU file to write (default: ./<scene name>.fmu)")
    args = parser.parse_args(argv)
    try:
        path = build_fmu(args.scene, args.out)
    except (SceneError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
