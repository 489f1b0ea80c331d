"""The shipped scenes' CSVs, bit for bit what they were (issue 43.5): every packaged scene run by the command line
(`prandtl-fmu run NAME --states --energy`: every column) gives the CSV whose SHA-256 and row count
tests/data/shipped_scenes.json holds. That file was written before any change to how the loops are compiled (the
fewer specialisations issue 43 asks for), and is kept: a change of any number of any shipped scene's run fails
here. A scene the command line refuses (hard/massless-collapse) keeps its status and its one line.

Regenerate only for a change meant to move numbers, saying so in the commit:
``python -m tests.scenes.test_shipped_scenes --write``.
"""
import hashlib
import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT

RECORD = ROOT / "tests" / "data" / "shipped_scenes.json"


def packaged():
    from prandtl_fmu.catalog import packaged_scenes

    return list(packaged_scenes())


def run_scene(name, folder) -> dict:
    """The scene's CSV (its digest and rows), or the command line's refusal (exit status and its line)."""
    out = folder / (name.replace("/", "_") + ".csv")
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", name, "--states", "--energy", "--out",
                           str(out)], cwd=ROOT, capture_output=True, text=True, timeout=1800)
    if done.returncode != 0:
        return {"status": done.returncode,  # (its words without the clone's own folder)
                "said": [line.replace(str(ROOT) + "/", "") for line in done.stderr.strip().splitlines()[-1:]]}
    data = out.read_bytes()
    return {"status": 0, "sha256": hashlib.sha256(data).hexdigest(), "rows": data.count(b"\n")}


@pytest.mark.slow  # every packaged scene, whole (a few minutes cold)
@pytest.mark.parametrize("name", packaged())
def test_a_shipped_scene_s_csv_is_what_it_was(name, tmp_path):
    recorded = json.loads(RECORD.read_text())
    assert name in recorded, f"{name}: no recorded CSV (python -m tests.scenes.test_shipped_scenes --write)"
    assert run_scene(name, tmp_path) == recorded[name]


def test_every_shipped_scene_has_its_record():
    assert sorted(json.loads(RECORD.read_text())) == sorted(packaged())


if __name__ == "__main__":
    import pathlib
    import tempfile

    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python -m tests.scenes.test_shipped_scenes --write")
    with tempfile.TemporaryDirectory() as scratch:
        record = {name: run_scene(name, pathlib.Path(scratch)) for name in packaged()}
    RECORD.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
    print(f"{RECORD}: {len(record)} scenes")
