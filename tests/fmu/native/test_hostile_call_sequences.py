"""Random FMI call sequences through the native FMU (issue 31): seeded, reproducible, bounded (a few seconds per
FMU once it is built; the FMUs are those of test_hostile_host.py, built once per process).

Each sequence runs in its own process, the C host of tests/c_host/trust_host.c built with the sanitizers where
they run (the FMU too): calls in any order, NULL instances and pointers, NaN, inf, huge and subnormal values for
every Real variable, communication points and steps, stepper names that are NULL, unknown or too long, and FMU
state blobs that are valid, truncated, bit-flipped, forged with a recomputed checksum or garbage, loaded by
fmi2/3DeSerializeFMUState or written over a state's memory before fmi2/3SetFMUState, input derivatives set and output
derivatives asked for with any reference and order (FMI 2.0). Every call must return (the
process ends by itself within its time limit, no crash, no sanitizer report), every message has a declared
category, and every value a getter hands out with an OK status is finite."""
import math

import numpy as np
import pytest

from tests.fmu.native.test_hostile_host import DECLARED, SCENES, START, forged
from tests.native_host import built_native, compile_trust_host, run_trust

# seeded random call sequences in child processes (a minute or two with their builds): run by .ci/run after
# the quick suite, as `pytest -m slow`
pytestmark = pytest.mark.slow

SEQUENCES = 120  # per FMU: about 3 s each once it is built
LENGTH = 80
REALS = [math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, 1e-60, 1e60, 0.0, -0.0, 1.0, -1.0, 0.3, 1e-3, 2.0]
POINTS = [0.0, 0.1, 0.3, -1.0, 1e6, math.nan, math.inf, 1e308]
STEPS = [0.1, 0.01, 1e-3, 0.0, -0.1, math.nan, math.inf, 1e7, 1e12, 1e-160, 1e308]
INTERNAL_STEPS = [1e-3, 1e-2, 1e-6, 1e-200, 0.0, -1.0, math.nan]  # never more than 1e5 internal steps a doStep
NAMES = ["NULL", "implicit", "verlet", "projected", "symplectic", "exact", "nonsense", "x" * 100, ""]


def blobs(host, fmu, folder, rng):
    """A pool of state files: valid (after some steps), truncated, bit-flipped, forged with a recomputed checksum
    (random doubles at random aligned offsets, or random bytes), empty, garbage."""
    valid = folder / "valid.bin"
    run = run_trust(host, fmu, by_f(fmu, START) + ["setr:" + ("F:0.4" if "F" in fmu.vr else "x:0.05"), "step:0:0.3",
                                                   "save", f"dump:{valid}"])
    assert run.code == 0 and run.ended, run.out
    blob = valid.read_bytes()
    pool = {"valid": blob, "empty": b"", "garbage": bytes(rng.integers(0, 256, 64, dtype=np.uint8)),
            "truncated": blob[:len(blob) // 2], "longer": blob + b"\0" * 8}
    for i in range(4):
        flipped = bytearray(blob)
        flipped[int(rng.integers(len(blob)))] ^= 1 << int(rng.integers(8))
        pool[f"flipped{i}"] = bytes(flipped)
    specials = [math.nan, math.inf, -1.0, 1e9, 1e300, -5.0, 0.5, 2.0, 0.0]
    for i in range(16):
        offset = 8 * int(rng.integers(13, (len(blob) - 8) // 8))  # past the head, before the checksum
        pool[f"forged{i}"] = forged(blob, {offset: specials[int(rng.integers(len(specials)))]})
    for i in range(4):
        data = bytearray(blob)
        at = int(rng.integers(104, len(blob) - 16))
        data[at:at + 8] = bytes(rng.integers(0, 256, 8, dtype=np.uint8))
        pool[f"bytes{i}"] = forged(bytes(data), {})
    paths = []
    for name, data in pool.items():
        path = folder / f"{name}.bin"
        path.write_bytes(data)
        paths.append(path)
    return paths


def by_f(fmu, commands) -> list:
    """``commands`` with scene_load set false first and after every reset (it starts true with the scene's load):
    the force is the F the sequence sets, as before; a scene load under 'exact' over a step of 1e7 s is work the
    sequence was not written for."""
    if "scene_load" not in fmu.vr:
        return list(commands)
    driven = ["setb:scene_load:0"]
    for command in commands:
        driven += [command, "setb:scene_load:0"] if command == "reset" else [command]
    return driven


def sequence(rng, fmu, paths) -> list:
    reals = [name for name in fmu.vr if name not in ("stepper", "scene_load", "n")] + ["9999"]
    pick = lambda values: values[int(rng.integers(len(values)))]  # noqa: E731
    commands = []
    for _ in range(LENGTH):
        kind = int(rng.integers(22))
        if kind < 5:
            name = pick(reals)
            value = pick(INTERNAL_STEPS) if name == "step" else (pick(REALS) if rng.random() < 0.7
                                                                 else float(rng.normal()))
            commands.append(f"setr:{name}:{value!r}")
        elif kind < 9:
            commands.append(f"getr:{pick(reals)}")
        elif kind < 12:
            commands.append(f"step:{pick(POINTS)!r}:{pick(STEPS)!r}")
        elif kind == 12:
            commands.append(pick(["setup:0", "setup:nan", "setup:0:1", "setup:1:0", "setup:inf"]))
        elif kind == 13:
            commands.append(pick(["enter", "exit", "term", "reset", "cancel", "status", "debug:1", "debug:0"]))
        elif kind == 14 and "stepper" in fmu.vr:
            commands.append(f"sets:stepper:{pick(NAMES)}")
        elif kind == 15:
            commands.append(pick(["save", "restore", "freestate"]))
        elif kind == 16:
            commands.append(f"load:{pick(paths)}")
        elif kind == 17:
            commands.append(f"poke:{pick(paths)}")
        elif kind == 18:
            commands.append(f"dump:{paths[0].parent / 'dumped.bin'}")
        elif kind == 19:
            commands.append(pick(["nullc", f"nulla:{pick(list(fmu.vr))}"]))
        elif kind == 20 and fmu.fmi == 2:  # F's derivatives set, an output's asked (any variable, any order)
            order = pick([0, 1, 2, 3, -1])
            commands.append(pick([f"deriv:{pick(reals)}:{order}:{pick(REALS)!r}", f"oderiv:{pick(reals)}:{order}"]))
        elif kind == 20 and fmu.fmi == 3 and any(name.startswith("u_") for name in fmu.vr):
            # an elongation u_i (the array u with arrays) asked with 0 to 4 values
            elongations = [name for name in fmu.vr if name == "u" or name.startswith("u_")]
            commands.append(f"geta:{pick(elongations)}:{int(rng.integers(0, 5))}")
        else:
            commands.extend(START if rng.random() < 0.5 else ["reset"] + START)
    if rng.random() < 0.2:
        commands.insert(int(rng.integers(len(commands))), "free")
    return by_f(fmu, commands)


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", list(SCENES))
def test_random_call_sequences_never_crash_and_never_show_a_non_finite_value(name, fmi, tmp_path_factory):
    folder = tmp_path_factory.mktemp(f"fuzz_{name}_{fmi}")
    host = compile_trust_host(folder, fmi)
    fmu = built_native(name, SCENES[name], fmi, tmp_path_factory.mktemp("trust"))
    rng = np.random.default_rng([31, fmi, list(SCENES).index(name)])
    paths = blobs(host, fmu, folder, rng)
    for index in range(SEQUENCES):
        commands = sequence(rng, fmu, paths)
        run = run_trust(host, fmu, commands, logging=bool(index % 2), timeout=60)
        where = f"sequence {index} of {name} FMI {fmi}: {commands}"
        assert run.code == 0 and run.ended, (where, run.out[-3000:])
        assert all(category in DECLARED for _, category, _ in run.logs), where
        assert all(math.isfinite(value) for _, value in run.values), (where, run.values)
        for line in run.out.splitlines():
            if line.startswith("STATUS "):
                assert math.isfinite(float(line.split()[1])), where
        assert [status for _, status in run.calls if status not in ("-1", "ok")] == [
            status for _, status in run.calls if status in ("0", "1", "2", "3", "97", "98", "99")], where
