"""The PythonFMU FMU (our loader, ``prandtl_fmu/fmu/python/loader``, and the slaves) against a hostile FMI 2.0 host.

Driven through ctypes, not FMPy, so that a test can pass what FMPy never does: a NULL instance, NULL argument
pointers, made-up state pointers, calls out of order, NaN and inf times. Where the stock loader crashed, the
calls run in a child process (``sys.executable``): a crash is that test's failure, not the suite's end.
Issue 31 (Trust, round three), items 6, 7, 9, 10 and 12; the fuzz is in test_hostile_call_sequences.py.
"""
import ctypes as C
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("fmpy")

from tests.paths import ROOT  # noqa: E402

if not (sys.platform.startswith("linux") and sys.maxsize > 2**32):
    pytest.skip("the FMU's own loader is built for Linux x86-64", allow_module_level=True)

OK, WARNING, DISCARD, ERROR, FATAL = range(5)
LAST_SUCCESSFUL_TIME, TERMINATED = 2, 3  # fmi2StatusKind

ELEMENT_SCENE = """\
name = "trust_element"
[mass]
m = 1.0
[spring]
k0 = 1.0
[damper]
c = 0.1
[branches]
k = [0.5, 2.0]
eta = [0.1, 0.3]
[solver]
stepper = "projected"
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""
CONNECTOR_SCENE = """\
name = "trust_connector"
[spring]
k0 = 1.0
[damper]
c = 0.1
[branches]
k = [0.5, 2.0]
eta = [0.1, 0.3]
[fmu]
causality = "displacement"
[solver]
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""

LOGGER = C.CFUNCTYPE(None, C.c_void_p, C.c_char_p, C.c_int, C.c_char_p, C.c_char_p)


class Callbacks(C.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", C.c_void_p), ("freeMemory", C.c_void_p),
                ("stepFinished", C.c_void_p), ("componentEnvironment", C.c_void_p)]


_P, _VR, _REAL, _INT = C.c_void_p, C.POINTER(C.c_uint), C.POINTER(C.c_double), C.POINTER(C.c_int)
_STR = C.POINTER(C.c_char_p)
# every fmi2 function of a co-simulation FMU: (result, arguments)
SIGNATURES = {
    "fmi2Instantiate": (_P, [C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.POINTER(Callbacks), C.c_int, C.c_int]),
    "fmi2FreeInstance": (None, [_P]),
    "fmi2SetDebugLogging": (C.c_int, [_P, C.c_int, C.c_size_t, _STR]),
    "fmi2SetupExperiment": (C.c_int, [_P, C.c_int, C.c_double, C.c_double, C.c_int, C.c_double]),
    "fmi2EnterInitializationMode": (C.c_int, [_P]),
    "fmi2ExitInitializationMode": (C.c_int, [_P]),
    "fmi2Terminate": (C.c_int, [_P]),
    "fmi2Reset": (C.c_int, [_P]),
    "fmi2GetReal": (C.c_int, [_P, _VR, C.c_size_t, _REAL]),
    "fmi2GetInteger": (C.c_int, [_P, _VR, C.c_size_t, _INT]),
    "fmi2GetBoolean": (C.c_int, [_P, _VR, C.c_size_t, _INT]),
    "fmi2GetString": (C.c_int, [_P, _VR, C.c_size_t, _STR]),
    "fmi2SetReal": (C.c_int, [_P, _VR, C.c_size_t, _REAL]),
    "fmi2SetInteger": (C.c_int, [_P, _VR, C.c_size_t, _INT]),
    "fmi2SetBoolean": (C.c_int, [_P, _VR, C.c_size_t, _INT]),
    "fmi2SetString": (C.c_int, [_P, _VR, C.c_size_t, _STR]),
    "fmi2GetFMUstate": (C.c_int, [_P, C.POINTER(_P)]),
    "fmi2SetFMUstate": (C.c_int, [_P, _P]),
    "fmi2FreeFMUstate": (C.c_int, [_P, C.POINTER(_P)]),
    "fmi2SerializedFMUstateSize": (C.c_int, [_P, _P, C.POINTER(C.c_size_t)]),
    "fmi2SerializeFMUstate": (C.c_int, [_P, _P, C.c_char_p, C.c_size_t]),
    "fmi2DeSerializeFMUstate": (C.c_int, [_P, C.c_char_p, C.c_size_t, C.POINTER(_P)]),
    "fmi2GetDirectionalDerivative": (C.c_int, [_P, _VR, C.c_size_t, _VR, C.c_size_t, _REAL, _REAL]),
    "fmi2SetRealInputDerivatives": (C.c_int, [_P, _VR, C.c_size_t, _INT, _REAL]),
    "fmi2GetRealOutputDerivatives": (C.c_int, [_P, _VR, C.c_size_t, _INT, _REAL]),
    "fmi2DoStep": (C.c_int, [_P, C.c_double, C.c_double, C.c_int]),
    "fmi2CancelStep": (C.c_int, [_P]),
    "fmi2GetStatus": (C.c_int, [_P, C.c_int, _INT]),
    "fmi2GetRealStatus": (C.c_int, [_P, C.c_int, _REAL]),
    "fmi2GetIntegerStatus": (C.c_int, [_P, C.c_int, _INT]),
    "fmi2GetBooleanStatus": (C.c_int, [_P, C.c_int, _INT]),
    "fmi2GetStringStatus": (C.c_int, [_P, C.c_int, _STR]),
}


def build(folder, scene_text, stem, loader="prandtl"):
    """Build the scene's PythonFMU FMU (our loader, or PythonFMU's stock one) into ``folder``; its path."""
    from prandtl_fmu.fmu.build import build_fmu

    scene = Path(folder) / f"{stem}.toml"
    scene.write_text(scene_text)
    return str(build_fmu(scene, Path(folder) / f"{stem}.fmu", loader=loader))


class Binary:
    """An FMU's extracted binary, loaded with ctypes; ``instantiate`` makes an :class:`Instance`."""

    def __init__(self, fmu_path):
        from fmpy import extract, read_model_description

        self.md = read_model_description(fmu_path)
        self.folder = str(extract(fmu_path))
        self.lib = C.CDLL(f"{self.folder}/binaries/linux64/{self.md.coSimulation.modelIdentifier}.so")
        for name, (result, arguments) in SIGNATURES.items():
            function = getattr(self.lib, name)
            function.restype, function.argtypes = result, arguments
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]

    def instantiate(self, logging=False, name=b"trust"):
        return Instance(self, logging, name)


class Instance:
    """One instance; ``messages`` holds (status, category, text) as logged; ``call`` returns the status."""

    def __init__(self, binary, logging, name):
        self.binary, self.lib, self.messages = binary, binary.lib, []

        def log(env, instance, status, category, message):
            self.messages.append((status, None if category is None else category.decode(),
                                  message.decode("utf-8", "replace")))

        self._logger = LOGGER(log)  # kept alive with the instance
        self.callbacks = Callbacks(self._logger, None, None, None, None)
        uri = f"file://{binary.folder}/resources".encode()
        self.c = self.lib.fmi2Instantiate(name, 1, binary.md.guid.encode(), uri, C.byref(self.callbacks), 0,
                                          int(logging))
        assert self.c, self.messages

    def call(self, function, *arguments):
        return getattr(self.lib, "fmi2" + function)(self.c, *arguments)

    def refs(self, *names):
        return (C.c_uint * len(names))(*[self.binary.vr[name] for name in names])

    def get(self, *names):
        values = (C.c_double * len(names))()
        return self.call("GetReal", self.refs(*names), len(names), values), list(values)

    def set(self, name, value):
        return self.call("SetReal", self.refs(name), 1, (C.c_double * 1)(value))

    def initialized(self, start=0.0):
        assert self.call("SetupExperiment", 0, 0.0, start, 0, 0.0) == OK
        assert self.call("EnterInitializationMode") == OK
        assert self.call("ExitInitializationMode") == OK, self.messages
        return self

    def free(self):
        self.lib.fmi2FreeInstance(self.c)


def run_child(script, *arguments, timeout=300):
    """Run ``script`` in a fresh Python (a crash is its return code); its stdout lines."""
    done = subprocess.run([sys.executable, "-c", script, *map(str, arguments)], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)
    return done


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pythonfmu_trust")
    return {"element": build(folder, ELEMENT_SCENE, "element"),
            "connector": build(folder, CONNECTOR_SCENE, "connector")}


@pytest.fixture(scope="module")
def binaries(fmus):
    return {kind: Binary(path) for kind, path in fmus.items()}


# ---------------------------------------------------------------- item 6: a NULL instance

NULL_INSTANCE = """
import ctypes as C, sys
from tests.fmu.python.test_hostile_host import Binary
binary = Binary(sys.argv[1])
vr, real, integer, text = (C.c_uint * 1)(0), (C.c_double * 1)(0.0), (C.c_int * 1)(0), (C.c_char_p * 1)(b"x")
state, size, buffer = C.c_void_p(), C.c_size_t(), C.create_string_buffer(64)
arguments = {
    "fmi2SetDebugLogging": (1, 1, (C.c_char_p * 1)(b"logAll")),
    "fmi2SetupExperiment": (0, 0.0, 0.0, 0, 0.0),
    "fmi2EnterInitializationMode": (), "fmi2ExitInitializationMode": (), "fmi2Terminate": (), "fmi2Reset": (),
    "fmi2GetReal": (vr, 1, real), "fmi2SetReal": (vr, 1, real),
    "fmi2GetInteger": (vr, 1, integer), "fmi2SetInteger": (vr, 1, integer),
    "fmi2GetBoolean": (vr, 1, integer), "fmi2SetBoolean": (vr, 1, integer),
    "fmi2GetString": (vr, 1, text), "fmi2SetString": (vr, 1, text),
    "fmi2GetFMUstate": (C.byref(state),), "fmi2SetFMUstate": (None,), "fmi2FreeFMUstate": (C.byref(state),),
    "fmi2SerializedFMUstateSize": (None, C.byref(size)), "fmi2SerializeFMUstate": (None, buffer, 64),
    "fmi2DeSerializeFMUstate": (b"{}", 2, C.byref(state)),
    "fmi2GetDirectionalDerivative": (vr, 1, vr, 1, real, real),
    "fmi2SetRealInputDerivatives": (vr, 1, integer, real), "fmi2GetRealOutputDerivatives": (vr, 1, integer, real),
    "fmi2DoStep": (0.0, 0.1, 1), "fmi2CancelStep": (),
    "fmi2GetStatus": (0, integer), "fmi2GetRealStatus": (2, real), "fmi2GetIntegerStatus": (0, integer),
    "fmi2GetBooleanStatus": (3, integer), "fmi2GetStringStatus": (0, text),
}
freed = binary.instantiate()
freed.free()
for which, c in (("NULL", None), ("freed", freed.c)):
    for name, args in arguments.items():
        print(which, name, getattr(binary.lib, name)(c, *args), flush=True)
    binary.lib.fmi2FreeInstance(c)
    print(which, "fmi2FreeInstance", "returned", flush=True)
"""


def test_every_function_given_a_null_or_freed_instance_returns_error_and_never_crashes(fmus):
    """The stock loader dereferenced the instance in every function (SIGSEGV on the first NULL); a freed one
    was used after free (and freed again by a second fmi2FreeInstance). Now: fmi2Error, nothing touched."""
    done = run_child(NULL_INSTANCE, fmus["element"])
    lines = [line.split() for line in done.stdout.splitlines()]
    assert done.returncode == 0, (lines[-1:], done.stderr[-1500:])
    for which in ("NULL", "freed"):
        statuses = {name: status for kind, name, status in lines if kind == which}
        assert len(statuses) == len(SIGNATURES) - 1, statuses  # all but fmi2Instantiate
        assert statuses.pop("fmi2FreeInstance") == "returned"
        assert set(statuses.values()) == {str(ERROR)}, statuses


# ---------------------------------------------------------------- item 7: NULL arguments of a valid instance

NULL_ARGUMENTS = """
import ctypes as C, json, sys
from tests.fmu.python.test_hostile_host import Binary
binary = Binary(sys.argv[1])
instance = binary.instantiate(logging=False).initialized()
vr, real, integer = instance.refs("x"), (C.c_double * 1)(0.0), (C.c_int * 1)(0)
stepper, text = instance.refs("stepper"), (C.c_char_p * 1)(b"projected")
state, size, buffer = C.c_void_p(), C.c_size_t(), C.create_string_buffer(1 << 16)
assert instance.call("GetFMUstate", C.byref(state)) == 0
assert instance.call("SerializedFMUstateSize", state, C.byref(size)) == 0
cases = [
    ("GetReal", (None, 1, real)), ("GetReal", (vr, 1, None)), ("SetReal", (None, 1, real)),
    ("SetReal", (instance.refs("F"), 1, None)),
    ("GetInteger", (instance.refs("n"), 1, None)), ("SetInteger", (None, 1, integer)),
    ("GetBoolean", (instance.refs("scene_load"), 1, None)), ("SetBoolean", (instance.refs("scene_load"), 1, None)),
    ("GetString", (stepper, 1, None)), ("SetString", (None, 1, text)), ("SetString", (stepper, 1, None)),
    ("SetString", (stepper, 1, (C.c_char_p * 1)(None))),
    ("SetDebugLogging", (1, 2, None)), ("SetDebugLogging", (1, 1, (C.c_char_p * 1)(None))),
    ("GetFMUstate", (None,)), ("SetFMUstate", (None,)), ("SetFMUstate", (C.c_void_p(0xdeadbeef),)),
    ("SerializedFMUstateSize", (state, None)), ("SerializedFMUstateSize", (None, C.byref(size))),
    ("SerializeFMUstate", (None, buffer, size.value)), ("SerializeFMUstate", (state, None, size.value)),
    ("SerializeFMUstate", (C.c_void_p(0xdeadbeef), buffer, size.value)),
    ("DeSerializeFMUstate", (None, 10, C.byref(C.c_void_p()))), ("DeSerializeFMUstate", (b"{}", 2, None)),
    ("FreeFMUstate", (C.byref(C.c_void_p(0xdeadbeef)),)),
    ("GetStatus", (0, None)), ("GetRealStatus", (2, None)), ("GetIntegerStatus", (0, None)),
    ("GetBooleanStatus", (3, None)), ("GetStringStatus", (0, None)),
]
for function, args in cases:
    before = len(instance.messages)
    status = instance.call(function, *args)
    print(json.dumps([function, status, instance.messages[before:]]), flush=True)
print(json.dumps(["FreeFMUstate NULL", instance.call("FreeFMUstate", None), []]), flush=True)
print(json.dumps(["FreeFMUstate", instance.call("FreeFMUstate", C.byref(state)), [state.value]]), flush=True)
print(json.dumps(["DoStep", instance.call("DoStep", 0.0, 0.1, 1), instance.get("x")]), flush=True)
instance.call("Terminate")
instance.free()
"""


def test_null_arguments_are_refused_with_a_logged_reason_even_with_logging_off(fmus):
    """The stock loader dereferenced them (SIGSEGV) or handed the slave None (a NULL string: accepted) and
    released a made-up state pointer. Now each call is fmi2Error with its reason logged under a category the
    modelDescription declares, with loggingOn false; fmi2FreeFMUstate(NULL) is ignored (FMI 2.0 2.1.8); the
    instance steps on unchanged."""
    done = run_child(NULL_ARGUMENTS, fmus["element"])
    results = [json.loads(line) for line in done.stdout.splitlines()]
    assert done.returncode == 0, (results[-1:], done.stderr[-1500:])
    *refusals, ignored, freed, step = results
    assert len(refusals) == 30
    for function, status, messages in refusals:
        assert status == ERROR, (function, messages)
        assert [(s, category) for s, category, _ in messages] == [(ERROR, "logStatusError")], (function, messages)
        reason = messages[0][2]
        assert reason.startswith(f"fmi2{function} refused: ") and ("NULL" in reason or "not a state" in reason), reason
    assert ignored[1] == OK and freed[1:] == [OK, [None]]
    assert step[1] == OK and step[2][0] == OK and math.isfinite(step[2][1][0])


# ---------------------------------------------------------------- item 9: non-finite times and steps

@pytest.mark.parametrize("kind", ["element", "connector"])
@pytest.mark.parametrize("time, step, culprit", [
    (math.nan, 0.1, "currentCommunicationPoint = nan"),
    (math.inf, 0.1, "currentCommunicationPoint = inf"),
    (-math.inf, 0.1, "currentCommunicationPoint = -inf"),
    (0.0, math.nan, "communicationStepSize = nan"),
    (0.0, math.inf, "communicationStepSize = inf"),
    (0.0, -0.1, "communicationStepSize = -0.1"),
    (1e308, 1.7e308, "ends at a time that is not finite"),
])
def test_a_non_finite_time_or_a_negative_step_is_refused_and_the_clock_stays(binaries, kind, time, step, culprit):
    """The stock loader took NaN with fmi2OK and its fmi2LastSuccessfulTime became NaN (a negative step was a
    Discard, a non-finite time an exception from the library). Now fmi2Error with the value named, the clock
    and the outputs as they were, and the next good step is taken."""
    instance = binaries[kind].instantiate().initialized()
    try:
        assert instance.call("DoStep", 0.0, 0.1, 1) == OK
        outputs = instance.get(*binaries[kind].outputs)
        before = len(instance.messages)
        assert instance.call("DoStep", time, step, 1) == ERROR
        assert [(s, c) for s, c, _ in instance.messages[before:]] == [(ERROR, "logStatusError")]
        assert culprit in instance.messages[before][2] and "fmi2DoStep refused" in instance.messages[before][2]
        clock = C.c_double()
        assert instance.call("GetRealStatus", LAST_SUCCESSFUL_TIME, C.byref(clock)) == OK
        assert clock.value == 0.1
        assert instance.get(*binaries[kind].outputs) == outputs
        assert instance.call("DoStep", 0.1, 0.1, 1) == OK
    finally:
        instance.free()


STOCK_CLOCK = """
import json, sys
from tests.fmu.python.test_hostile_host import Binary
for kind, path in zip(("element", "connector"), sys.argv[1:3]):
    instance = Binary(path).instantiate(logging=True).initialized()  # the stock loader logs nothing without
    for time, step in ((float("nan"), 0.1), (0.0, float("inf")), (0.0, -0.1)):
        status = instance.call("DoStep", time, step, 1)
        print(json.dumps([kind, status, [text for _, _, text in instance.messages if "fmi2DoStep refused" in text]]))
        instance.messages.clear()
    status = instance.call("DoStep", 0.0, 0.1, 1)
    print(json.dumps([kind, status, instance.get(*instance.binary.outputs)]), flush=True)
    instance.call("Terminate")
    instance.free()
"""


def test_under_the_stock_loader_the_slaves_refuse_a_bad_clock_and_survive(tmp_path):
    """PythonFMU's stock loader passes NaN, inf and negative steps on: the slaves refuse them (fmi2Fatal there, as
    every refusal, see fmu/python/common.py) with the reason, and step on. The element used to raise outside its step's
    guard (the library's 'time must be finite'), a bare exception for which that loader freed the instance's
    objects, and took a negative step as a Discard."""
    paths = [build(tmp_path, ELEMENT_SCENE, "element", loader="pythonfmu"),
             build(tmp_path, CONNECTOR_SCENE, "connector", loader="pythonfmu")]
    done = run_child(STOCK_CLOCK, *paths)
    results = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(results) == 8, (results, done.stderr[-2000:])  # it may die at exit (test_loader.py)
    for kind in ("element", "connector"):
        *refusals, (_, status, (got, outputs)) = [r for r in results if r[0] == kind]
        assert [status for _, status, _ in refusals] == [FATAL] * 3, refusals
        assert all(len(reasons) == 1 for _, _, reasons in refusals), refusals
        assert "communication point nan must be finite" in refusals[0][2][0]
        assert "communication step -0.1 must be finite and >= 0" in refusals[2][2][0]
        assert status == OK and got == OK and all(math.isfinite(value) for value in outputs)


@pytest.mark.parametrize("start, stop_defined, stop, culprit", [
    (math.nan, 0, 0.0, "startTime = nan"),
    (math.inf, 0, 0.0, "startTime = inf"),
    (0.0, 1, math.nan, "stopTime = nan"),
    (1.0, 1, 0.5, "stopTime = 0.5 must be finite and >= startTime = 1"),
])
def test_a_non_finite_start_time_is_refused_at_setup(binaries, start, stop_defined, stop, culprit):
    """The stock loader took startTime = NaN with fmi2OK (the initialization then failed on a NaN clock). Now
    fmi2SetupExperiment refuses with the reason and a good one is accepted after it."""
    instance = binaries["element"].instantiate()
    try:
        assert instance.call("SetupExperiment", 0, 0.0, start, stop_defined, stop) == ERROR
        assert culprit in instance.messages[-1][2], instance.messages
        instance.initialized(start=0.5)
        clock = C.c_double()
        assert instance.call("GetRealStatus", LAST_SUCCESSFUL_TIME, C.byref(clock)) == OK and clock.value == 0.5
    finally:
        instance.free()


# ---------------------------------------------------------------- item 12: the call sequence

def _sequence(instance, binary):
    string = (C.c_char_p * 1)
    clock, flag = C.c_double(), C.c_int()
    calls = {
        "terminate": lambda: instance.call("Terminate"),
        "setup": lambda: instance.call("SetupExperiment", 0, 0.0, 0.0, 0, 0.0),
        "enter": lambda: instance.call("EnterInitializationMode"),
        "exit": lambda: instance.call("ExitInitializationMode"),
        "step": lambda: instance.call("DoStep", 0.0, 0.1, 1),
        "set k0": lambda: instance.set("k0", 2.0),
        "set stepper": lambda: instance.call("SetString", instance.refs("stepper"), 1, string(b"implicit")),
        "get x": lambda: instance.get("x")[0],
        "last time": lambda: instance.call("GetRealStatus", LAST_SUCCESSFUL_TIME, C.byref(clock)),
        "terminated": lambda: instance.call("GetBooleanStatus", TERMINATED, C.byref(flag)),
        "cancel": lambda: instance.call("CancelStep"),
        "reset": lambda: instance.call("Reset"),
    }
    return calls


# (call, status): FMI 2.0's co-simulation state machine (as the Reference-FMUs' masks), a refusal changing nothing
SEQUENCE = [
    ("terminate", ERROR), ("get x", ERROR), ("step", ERROR), ("last time", ERROR), ("terminated", ERROR),
    ("exit", ERROR), ("set k0", OK), ("setup", OK), ("enter", OK), ("setup", ERROR), ("enter", ERROR),
    ("step", ERROR), ("terminate", ERROR), ("get x", OK), ("last time", ERROR), ("exit", OK), ("exit", ERROR),
    ("enter", ERROR), ("setup", ERROR), ("step", OK), ("last time", OK), ("terminated", OK), ("cancel", ERROR),
    ("set k0", OK), ("set stepper", OK), ("step", OK), ("terminate", OK), ("terminate", ERROR),
    ("set k0", ERROR), ("set stepper", ERROR), ("step", ERROR), ("get x", OK), ("last time", OK),
    ("reset", OK), ("terminate", ERROR), ("get x", ERROR), ("setup", OK), ("enter", OK), ("exit", OK),
    ("step", OK), ("reset", OK),
]


def test_the_fmi2_call_sequence_is_enforced_with_the_reason(binaries):
    """fmi2Terminate before initialization or twice, a parameter after it, a step before initialization, a
    status inquiry before a step could have been taken, fmi2CancelStep with no step pending: fmi2Error with
    'not allowed <where>' logged; the stock loader accepted them (its fmi2GetRealStatus answered NaN before any
    step)."""
    instance = binaries["element"].instantiate()
    try:
        calls = _sequence(instance, binaries["element"])
        for position, (name, expected) in enumerate(SEQUENCE):
            before = len(instance.messages)
            status = calls[name]()
            assert status == expected, (position, name, instance.messages[before:])
            if expected == ERROR:
                reasons = [text for s, category, text in instance.messages[before:]
                           if s == ERROR and category == "logStatusError"]
                assert reasons, (position, name, instance.messages[before:])
                assert "not allowed" in reasons[0] or "fmi2CancelStep refused" in reasons[0], reasons
    finally:
        instance.free()


def test_a_null_string_is_refused_for_being_null(binaries):
    """fmi2SetString with a NULL value: the stock loader handed the slave None and returned fmi2OK (the next
    step was refused for 'stepper = None'). Now fmi2Error naming the NULL value, the stepper unchanged."""
    instance = binaries["element"].instantiate().initialized()
    try:
        assert instance.call("SetString", instance.refs("stepper"), 1, (C.c_char_p * 1)(None)) == ERROR
        assert "value[0] (value reference" in instance.messages[-1][2] and "is NULL" in instance.messages[-1][2]
        value = (C.c_char_p * 1)()
        assert instance.call("GetString", instance.refs("stepper"), 1, value) == OK and value[0] == b"projected"
        assert instance.call("SetString", instance.refs("stepper"), 1, (C.c_char_p * 1)(b"\xff\xfe")) == ERROR
        assert "UnicodeDecodeError" in instance.messages[-1][2]
        assert instance.call("DoStep", 0.0, 0.1, 1) == OK
    finally:
        instance.free()


# ---------------------------------------------------------------- item 10: no non-finite value with fmi2OK

@pytest.mark.parametrize("kind, name, value, read, culprit", [
    ("element", "F", math.inf, "F", "F = inf is not a finite number"),
    ("element", "F", math.nan, "F", "F = nan is not a finite number"),
    ("connector", "x", math.nan, "force", "input x = nan"),
    ("connector", "v", math.inf, "stored_energy", "v = inf"),
])
def test_a_getter_never_hands_out_a_non_finite_value_with_ok(binaries, kind, name, value, read, culprit):
    """The connector showed NaN outputs with fmi2OK for a NaN input, the element echoed F = inf. Now fmi2Error
    with the reason; a finite input again and the outputs are read as before."""
    instance = binaries[kind].instantiate().initialized()
    try:
        assert instance.call("DoStep", 0.0, 0.1, 1) == OK
        status, before = instance.get(read)
        assert status == OK
        assert instance.set(name, value) == OK  # an input may be set; the step would refuse it
        status, _ = instance.get(read)
        assert status == ERROR and any(culprit in text for _, _, text in instance.messages[-3:]), instance.messages
        assert instance.set(name, 0.0) == OK and instance.get(read) == (OK, before)
    finally:
        instance.free()


def test_an_exact_run_reads_only_finite_outputs_or_refuses(binaries):
    """exact books no energy (its account was NaN): each output is either finite with fmi2OK or refused."""
    instance = binaries["element"].instantiate()
    try:
        assert instance.call("SetString", instance.refs("stepper"), 1, (C.c_char_p * 1)(b"exact")) == OK
        instance.initialized()
        assert instance.set("F", 0.5) == OK
        assert instance.call("DoStep", 0.0, 0.5, 1) == OK
        for name in binaries["element"].outputs:
            status, (value,) = instance.get(name)
            assert (status == OK and math.isfinite(value)) or status == ERROR, (name, status, value)
    finally:
        instance.free()


# ---------------------------------------------------------------- the library's refusals reach the master

@pytest.mark.parametrize("kind, name, value, time, step, words", [
    # more internal steps than scene.ADVANCE_BUDGET in one doStep: refused at once
    ("element", None, None, 0.1, 1e7, ["more than the budget of 1e+08 steps"]),
    # a force whose step would overflow an output (x, v finite): the library names the quantity
    ("element", "F", 1e300, 0.1, 1e-3, ["would not be finite"]),
    # a coefficient outside the physical magnitudes (scene.coefficient_problem)
    ("element", "k0", 1e51, 0.1, 0.1, ["k0", "|1e+51| is outside [1e-50, 1e+50]"]),
    ("connector", "x", 1e200, 0.1, 0.1, ["stored_energy would not be finite"]),
    ("connector", "c", 1e-51, 0.1, 0.1, ["parameter c", "|1e-51| is outside"]),
])
def test_a_step_the_library_refuses_is_a_discard_with_its_reason_and_changes_nothing(binaries, kind, name, value,
                                                                                     time, step, words):
    """Element.advance's budget and its refusal of a non-finite output, the connector's refusal of an overflowing
    sample, and scene.coefficient_problem's magnitudes: fmi2Discard with the library's reason, the outputs as
    they were, and a good value and step after it are taken."""
    binary = binaries[kind]
    instance = binary.instantiate().initialized()
    try:
        assert instance.call("DoStep", 0.0, 0.1, 1) == OK
        outputs = instance.get(*binary.outputs)
        good = None if name is None else instance.get(name)[1][0]
        if name is not None:
            assert instance.set(name, value) == OK
        before = len(instance.messages)
        assert instance.call("DoStep", time, step, 1) == DISCARD
        reasons = [text for status, category, text in instance.messages[before:]
                   if status == DISCARD and category == "logStatusDiscard"]
        assert reasons and all(word in reasons[0] for word in words), instance.messages[before:]
        if name is not None:
            assert instance.set(name, good) == OK
        assert instance.get(*binary.outputs) == outputs
        assert instance.call("DoStep", 0.1, 0.1, 1) == OK
    finally:
        instance.free()


@pytest.mark.parametrize("kind, name, value", [("element", "k0", 1e51), ("element", "m", 1e-51),
                                               ("connector", "k0", 1e60)])
def test_a_magnitude_outside_the_physical_range_is_refused_at_initialization(binaries, kind, name, value):
    instance = binaries[kind].instantiate()
    try:
        assert instance.call("SetupExperiment", 0, 0.0, 0.0, 0, 0.0) == OK
        assert instance.call("EnterInitializationMode") == OK
        assert instance.set(name, value) == OK
        assert instance.call("ExitInitializationMode") == ERROR
        assert any(f"parameter {name}: |{value:g}| is outside [1e-50, 1e+50]" in text
                   for status, _, text in instance.messages if status == ERROR), instance.messages
    finally:
        instance.free()


def test_an_output_the_connector_cannot_show_is_refused_not_handed_out(binaries):
    """A sample whose energy would overflow: the preview refuses (fmi2Error with the library's reason) instead of
    showing inf; a doStep would be a Discard."""
    instance = binaries["connector"].instantiate().initialized()
    try:
        assert instance.set("x", 1e200) == OK
        status, _ = instance.get("stored_energy")
        assert status == ERROR
        assert "stored_energy would not be finite" in instance.messages[-2][2] + instance.messages[-1][2]
    finally:
        instance.free()
