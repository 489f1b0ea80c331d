"""Where things are, for every test wherever its folder: the repository's root, the tests' folder, their data."""
from pathlib import Path

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DATA = TESTS / "data"
