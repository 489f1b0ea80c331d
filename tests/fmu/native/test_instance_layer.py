"""The native FMU's one instance layer (issue 46) changed no number and no word: the native FMUs of the shipped
scenes, one of each kind (element, element with a white noise, connector, network, network connector), FMI 2.0
and 3.0, driven by the sanitized trust host (tests/c_host/trust_host.c) through a run with steps of uneven sizes,
every output read after each, a state saved, serialized, restored and forged, and calls that must be refused (out
of sequence, NULL pointers, unknown value references, a non-finite input, a bad parameter): every status, every
logged message (its status, category and words) and every value read, to the bit, equal the reference recorded
in tests/data/native_core/ with the C layer as it was before the rebuild (commit a89c252 plus issue 44.2/44.3).

The references are data, not a hard-coded result: ``python -m tests.fmu.native.test_instance_layer record`` writes them from
the FMUs built by the C in the working tree (run it only with a C layer known good)."""
from __future__ import annotations

import json
import os
import shutil
import struct
import sys
from pathlib import Path

import pytest

from tests.native_host import Native, compile_trust_host, run_trust, sanitizers
from tests.paths import DATA, ROOT

if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

pytestmark = pytest.mark.slow  # ten native builds

CORE_DATA = DATA / "native_core"
# kind -> (scene, causality)
KINDS = {
    "element": (ROOT / "scenes" / "paper-section-8.toml", None),
    "noise": (ROOT / "scenes" / "white-noise.toml", None),
    "connector": (ROOT / "examples" / "cosim" / "connector" / "bushing.toml", "displacement"),
    "network": (ROOT / "scenes" / "networks" / "two-masses-slider.toml", None),
    "network_connector": (ROOT / "scenes" / "networks" / "chain-massless.toml", "displacement"),
}
SIZES = [0.013, 0.05, 0.1, 0.0371, 7e-12, 0.2, 0.001, 0.05]


def build(kind: str, fmi: int, folder: Path) -> Native:
    """The kind's native FMU for ``fmi``, built with the sanitizers where they run, unpacked."""
    from prandtl_fmu.fmu.build import build_fmu

    scene, causality = KINDS[kind]
    saved = os.environ.get("PRANDTL_NATIVE_CFLAGS")
    os.environ["PRANDTL_NATIVE_CFLAGS"] = " ".join(sanitizers())
    try:
        fmu = build_fmu(scene, folder / f"{kind}-{fmi}.fmu", runtime="native", fmi=fmi, causality=causality)
    finally:
        if saved is None:
            del os.environ["PRANDTL_NATIVE_CFLAGS"]
        else:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = saved
    return Native(fmu, folder / f"{kind}-{fmi}", fmi)


def read(fmu: Native) -> list:
    """The outputs read after each step: all, the elongations u_i of the first three branches only."""
    return [name for name in fmu.outputs if not (name[:2] == "u_" and name[2:].isdigit() and int(name[2:]) > 3)]


def script(fmu: Native, folder: Path, forged: Path | None) -> list:
    """The commands of the run: ``forged`` the state blob of a first run with a byte changed (None: the first
    run, which dumps its state into folder / "state.bin")."""
    connector = "x" in fmu.vr and "F" not in fmu.vr
    start = ["term", "step:0:0.1", "setup:0", "enter", "enter"]
    if "scene_load" in fmu.vr:
        start.append("setb:scene_load:1")
    start += ["exit", "exit"]
    commands = start + ["setr:999999:1", "getr:999999", "nulla:" + str(fmu.vr[fmu.outputs[0]])]
    t = 0.0
    for j, size in enumerate(SIZES):
        if connector:
            commands += [f"setr:x:{0.01 * (j + 1) * (-1) ** j!r}", f"setr:v:{0.05 * j!r}"]
        else:
            commands.append(f"setr:F:{0.3 * (-1) ** j!r}")
        if j == 3:
            commands += ["save", f"dump:{folder / 'state.bin'}"] if forged is None else ["save"]
        if j == 5:
            commands += ["setr:F:nan" if not connector else "setr:x:inf", f"step:{t!r}:0.1"]
            commands += ["setr:F:0.1" if not connector else "setr:x:0.02"]
        commands.append(f"step:{t!r}:{size!r}")
        t += size
        commands += [f"getr:{name}" for name in read(fmu)]
    commands += ["status", "restore"]
    if forged is not None:
        commands += [f"load:{forged}", f"load:{folder / 'short.bin'}"]
    parameter = next((name for name in ("k0", "c", "m_a", "k_spring", "alpha") if name in fmu.vr), None)
    if parameter is not None:
        commands += [f"setr:{parameter}:-1", f"step:{t!r}:0.1"]
    commands += ["term", "setr:F:1" if not connector else "setr:x:1", f"step:{t!r}:0.1", "reset", "setup:0", "enter",
                 "exit", "nullc", "free"]
    return commands


def record_of(run, folder: Path) -> dict:
    """What a run did, compactly: "command status" per call (the scratch folder written <folder>), each logged
    [status, category, message], each value read as its 8 bytes (hex: to the bit)."""
    return {"calls": [f"{command.replace(str(folder), '<folder>')} {status}" for command, status in run.calls],
            "logs": [list(log) for log in run.logs],
            "values": [struct.pack(">d", value).hex() for _, value in run.values]}


def drive(kind: str, fmi: int, folder: Path) -> dict:
    """Two runs of the script on the kind's FMU: the second loads the first's state with a byte changed."""
    folder.mkdir(parents=True, exist_ok=True)
    host = compile_trust_host(folder, fmi)
    fmu = build(kind, fmi, folder)
    first = run_trust(host, fmu, script(fmu, folder, None), timeout=600)
    assert first.code == 0 and first.ended, first.out[-3000:]
    blob = bytearray((folder / "state.bin").read_bytes())
    blob[len(blob) // 2] ^= 0x01  # a changed byte: the checksum no longer matches
    forged = folder / "forged.bin"
    forged.write_bytes(bytes(blob))
    (folder / "short.bin").write_bytes(bytes(100))
    second = run_trust(host, fmu, script(fmu, folder, forged), timeout=600)
    assert second.code == 0 and second.ended, second.out[-3000:]
    return {"first": record_of(first, folder), "second": record_of(second, folder)}


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", list(KINDS))
def test_the_native_core_says_and_computes_what_it_did(kind, fmi, tmp_path):
    expected = json.loads((CORE_DATA / f"{kind}-{fmi}.json").read_text())
    got = drive(kind, fmi, tmp_path)
    for run in ("first", "second"):
        for what in ("calls", "logs", "values"):
            assert got[run][what] == expected[run][what], (kind, fmi, run, what)


if __name__ == "__main__" and sys.argv[1:] == ["record"]:
    import tempfile

    CORE_DATA.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        for kind in KINDS:
            for fmi in (2, 3):
                record = drive(kind, fmi, Path(scratch) / f"{kind}-{fmi}")
                (CORE_DATA / f"{kind}-{fmi}.json").write_text(json.dumps(record, separators=(",", ":")) + "\n")
                print(kind, fmi, len(record["first"]["values"]), file=sys.stderr)
