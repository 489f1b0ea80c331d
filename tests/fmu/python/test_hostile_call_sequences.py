"""Random FMI 2.0 call sequences against the PythonFMU FMU (issue 31): out of order, NULL pointers, NaN, inf and
huge values, FMU-state blobs valid, truncated, bit-flipped and forged (well-formed JSON with wrong contents).

Each run is a child process (``sys.executable``) driving the element and the connector FMU through ctypes
(tests/fmu/python/test_hostile_host.py's harness) from one seed: the same seed, the same calls. The test fails if the
child crashes or hangs, if a call returns a status outside fmi2OK..fmi2Error (never fmi2Fatal: every refusal
leaves the instance usable), if a getter answers fmi2OK with a non-finite Real, if a message is logged without a
category, or if the instance cannot be reset and stepped at the end. Replay a failure with
``python -c "from tests.fmu.python.test_hostile_call_sequences import fuzz; fuzz(SEED, ELEMENT_FMU, CONNECTOR_FMU, CALLS)"``:
it prints every call.
"""
import ctypes as C
import json
import math
import random
import sys

import pytest

from tests.fmu.python.test_hostile_host import (CONNECTOR_SCENE, ELEMENT_SCENE, ERROR, LAST_SUCCESSFUL_TIME, OK, TERMINATED,
                                   Binary, build, run_child)

# seeded random call sequences in child processes (a minute or two with their builds): run by .ci/run after
# the quick suite, as `pytest -m slow`
pytestmark = pytest.mark.slow

CALLS = 2500  # per FMU and seed: ~5 s per seed here (more the first time numba compiles a stepper)
SEEDS = [11, 2026, 31, 7]

# the values a hostile master sends
NUMBERS = [0.0, -0.0, 1.0, -1.0, 0.3, 2.5, 1e-50, 1e50, 1e-51, 1e51, 5e-324, 1e-300, 1e300, 1.7976931348623157e308,
           -1.7976931348623157e308, math.nan, math.inf, -math.inf]
STEPS = [0.1, 0.1, 0.1, 0.05, 0.0, 1e-9, 1.0, -0.1, math.nan, math.inf, -math.inf, 1e300, 1e9]
TIMES = [math.nan, math.inf, -math.inf, -1.0, 1e300]
STEPPERS = [b"projected", b"implicit", b"symplectic", b"verlet", b"exact", b"rk4", b"", b"\xff\xfe", None]
STEP_PARAMETER = [0.01, 0.001, 1e-50, 1e-300, 0.0, -1.0, math.nan, math.inf, 1e308]


class Fuzzer:
    def __init__(self, rng, binary):
        self.rng, self.binary, self.violations = rng, binary, []
        self.reals = [n for n, t in binary.types.items() if t == "Real"]
        self.inputs = [v.name for v in binary.md.modelVariables if v.causality == "input"]
        self.has_stepper = "stepper" in binary.vr  # the element (the connector has no String, no Boolean)
        self.instance, self.instances, self.freed = None, [], []  # freed: handles of freed instances
        self.states = []  # state pointers returned (some freed since: kept, to be passed again)
        self.blobs = []  # serialized states
        self.new_instance()

    @property
    def time(self):
        """The current instance's clock as the master keeps it."""
        return getattr(self.instance, "clock", 0.0)

    @time.setter
    def time(self, value):
        self.instance.clock = value

    # ------------------------------------------------------------ bookkeeping

    def new_instance(self):
        """Two instances of the FMU at a time (states pass between them); renewing frees one."""
        if len(self.instances) == 2:
            old = self.instances.pop(self.rng.randrange(2))
            old.free()
            self.freed.append(old.c)
        self.instances.append(self.binary.instantiate(logging=self.rng.random() < 0.5))
        self.instance = self.instances[-1]
        self.time = 0.0

    def pick(self):
        if len(self.instances) < 2 or self.rng.random() < 0.05:
            self.new_instance()
        elif self.rng.random() < 0.1:
            self.instance = self.rng.choice(self.instances)

    def stale(self):
        """A call on a freed instance: fmi2Error, nothing touched."""
        live = {each.c for each in self.instances}
        self.freed = [c for c in self.freed if c not in live]  # malloc may hand a freed address out again
        if not self.freed:
            return "no freed instance"
        c = self.rng.choice(self.freed)
        statuses = [self.binary.lib.fmi2DoStep(c, 0.0, 0.1, 1), self.binary.lib.fmi2Terminate(c),
                    self.binary.lib.fmi2GetFMUstate(c, C.byref(C.c_void_p()))]
        self.binary.lib.fmi2FreeInstance(c)
        if statuses != [ERROR] * 3:
            self.violations.append(f"a freed instance answered {statuses}")
        return f"stale -> {statuses}"

    def check(self, what, status):
        if status not in (0, 1, 2, 3):
            self.violations.append(f"{what}: status {status}")
        for message in self.instance.messages:
            if message[1] is None:
                self.violations.append(f"{what}: a message without a category: {message}")
        self.instance.messages.clear()
        return status

    def call(self, what, function, *arguments):
        return self.check(what, self.instance.call(function, *arguments))

    def finite_if_ok(self, what, status, values):
        if status == OK and not all(math.isfinite(v) for v in values):
            self.violations.append(f"{what}: fmi2OK with {values}")

    # ------------------------------------------------------------ the operations

    def lifecycle(self):
        rng = self.rng
        kind = rng.choice(["setup", "enter", "exit", "terminate", "reset", "cancel", "logging", "renew"])
        if kind == "setup":
            start = rng.choice([0.0, 0.0, 1.5] + TIMES)
            stop = rng.choice([1.0, 10.0, -1.0, math.nan])
            tolerance = rng.choice([1e-6, -1.0, math.nan])
            status = self.call(f"setup {start} {stop} {tolerance}", "SetupExperiment", rng.random() < 0.5, tolerance,
                               start, rng.random() < 0.5, stop)
            if status == OK:
                self.time = start
            return f"setup {start!r} -> {status}"
        if kind == "renew":
            self.new_instance()
            return "renew"
        if kind == "logging":
            categories = rng.choice([None, [b"logAll"], [b"logStatusError", None], [b"nonsense"]])
            count = 0 if categories is None else len(categories)
            array = None if categories is None else (C.c_char_p * count)(*categories)
            n = count if rng.random() < 0.8 else 3
            status = self.call("logging", "SetDebugLogging", rng.random() < 0.5, n, array)
            return f"logging {categories} n={n} -> {status}"
        function = {"setup": "", "enter": "EnterInitializationMode", "exit": "ExitInitializationMode",
                    "terminate": "Terminate", "reset": "Reset", "cancel": "CancelStep"}[kind]
        status = self.call(kind, function)
        if kind == "reset" and status == OK:
            self.time = 0.0
        return f"{kind} -> {status}"

    def restart(self):
        """Back to stepping from the start (most calls are only refused outside it)."""
        statuses = [self.call("reset", "Reset"), self.call("setup", "SetupExperiment", 0, 0.0, 0.0, 0, 0.0),
                    self.call("enter", "EnterInitializationMode"), self.call("exit", "ExitInitializationMode")]
        self.time = 0.0
        return f"restart -> {statuses}"

    def step(self):
        rng = self.rng
        t = self.time if rng.random() < 0.85 else rng.choice(TIMES + [self.time - 0.5, self.time + 3.0])
        h = rng.choice(STEPS)
        status = self.call(f"step {t} {h}", "DoStep", t, h, 1)
        if status == OK:
            self.time = t + h
        clock = C.c_double()
        got = self.call("last time", "GetRealStatus", LAST_SUCCESSFUL_TIME, C.byref(clock))
        self.finite_if_ok("fmi2LastSuccessfulTime", got, [clock.value])
        return f"step {t!r} {h!r} -> {status}"

    def set_value(self):
        rng, instance = self.rng, self.instance
        kind = rng.random()
        if kind < 0.6:
            name = rng.choice(self.reals)
            value = rng.choice(NUMBERS) if rng.random() < 0.5 else rng.gauss(0.0, 3.0)
            if name == "step":
                value = rng.choice(STEP_PARAMETER)
            status = self.call(f"set {name}", "SetReal", instance.refs(name), 1, (C.c_double * 1)(value))
            return f"set {name} = {value!r} -> {status}"
        if kind < 0.8 and self.has_stepper:
            stepper = rng.choice(STEPPERS)
            status = self.call("set stepper", "SetString", instance.refs("stepper"), 1, (C.c_char_p * 1)(stepper))
            return f"set stepper = {stepper!r} -> {status}"
        if kind < 0.9 and self.has_stepper:
            value = rng.choice([0, 1, 2, -1])
            status = self.call("set scene_load", "SetBoolean", instance.refs("scene_load"), 1, (C.c_int * 1)(value))
            return f"set scene_load = {value} -> {status}"
        vr = rng.choice([10_000, 2**32 - 1, 2**31])  # no such variable, or one of another type
        function = rng.choice(["SetReal", "SetInteger", "SetBoolean"])
        array = (C.c_double * 1)(1.0) if function == "SetReal" else (C.c_int * 1)(1)
        status = self.call(f"{function} vr {vr}", function, (C.c_uint * 1)(vr), 1, array)
        return f"{function} vr {vr} -> {status}"

    def get_values(self):
        rng, instance = self.rng, self.instance
        names = rng.sample(self.reals, rng.randint(1, len(self.reals)))
        values = (C.c_double * len(names))()
        status = self.call("get", "GetReal", instance.refs(*names), len(names), values)
        self.finite_if_ok(f"GetReal {names}", status, list(values))
        text, flag, number = (C.c_char_p * 1)(), (C.c_int * 1)(), (C.c_int * 1)()
        if self.has_stepper:
            self.call("get stepper", "GetString", instance.refs("stepper"), 1, text)
            self.call("get scene_load", "GetBoolean", instance.refs("scene_load"), 1, flag)
        self.call("get n", "GetInteger", instance.refs("n"), 1, number)
        wrong = self.call("get a Real as an Integer", "GetInteger", instance.refs(names[0]), 1, number)
        if wrong != ERROR:
            self.violations.append(f"GetInteger of the Real {names[0]}: {wrong}")
        return f"get {len(names)} -> {status}"

    def null_pointer(self):
        rng, instance = self.rng, self.instance
        vr, real = instance.refs("stiffness"), (C.c_double * 1)()
        name = "stepper" if self.has_stepper else "n"  # a String, or an Integer where there is none
        function, arguments = rng.choice([
            ("GetReal", (None, 1, real)), ("GetReal", (vr, 1, None)), ("SetReal", (None, 1, real)),
            ("SetReal", (instance.refs(self.inputs[0]), 1, None)), ("GetString", (instance.refs(name), 1, None)),
            ("SetString", (instance.refs(name), 1, None)), ("GetFMUstate", (None,)), ("SetFMUstate", (None,)),
            ("SerializedFMUstateSize", (None, None)), ("SerializeFMUstate", (None, None, 10)),
            ("DeSerializeFMUstate", (None, 5, None)), ("GetRealStatus", (LAST_SUCCESSFUL_TIME, None)),
            ("GetBooleanStatus", (TERMINATED, None)), ("GetStatus", (0, None)), ("FreeFMUstate", (None,)),
            ("GetReal", (None, 0, None)),
        ])
        status = self.call(f"NULL {function}", function, *arguments)
        return f"NULL {function} -> {status}"

    def status(self):
        rng = self.rng
        kind = rng.choice([0, 1, 2, 3, 7, -1])
        function = rng.choice(["GetStatus", "GetRealStatus", "GetIntegerStatus", "GetBooleanStatus",
                               "GetStringStatus"])
        value = {"GetRealStatus": C.c_double(), "GetStringStatus": C.c_char_p()}.get(function, C.c_int())
        status = self.call(f"{function} {kind}", function, kind, C.byref(value))
        if function == "GetRealStatus":
            self.finite_if_ok("GetRealStatus", status, [value.value])
        return f"{function} {kind} -> {status}"

    def state(self):
        rng = self.rng
        kind = rng.choice(["get", "get", "set", "free", "serialize", "deserialize", "deserialize", "made-up"])
        if kind == "get":
            slot = rng.choice(self.states) if self.states and rng.random() < 0.3 else C.c_void_p()
            status = self.call("get state", "GetFMUstate", C.byref(slot))
            if status == OK and slot not in self.states:
                self.states.append(slot)
            return f"get state -> {status}"
        if kind == "made-up":
            pointer = C.c_void_p(rng.choice([0xdeadbeef, 8, id(self)]))
            status = self.call("set made-up state", "SetFMUstate", pointer)
            if status != ERROR:
                self.violations.append(f"a made-up state pointer was accepted: {status}")
            return f"set made-up state -> {status}"
        if not self.states and kind != "deserialize":
            return "no state"
        if kind == "set":
            slot = rng.choice(self.states)
            return f"set state -> {self.call('set state', 'SetFMUstate', slot)}"
        if kind == "free":
            slot = rng.choice(self.states)
            kept = C.c_void_p(slot.value)  # the freed pointer, to be passed again later
            status = self.call("free state", "FreeFMUstate", C.byref(slot))
            self.states.append(kept)
            return f"free state -> {status}"
        if kind == "serialize":
            slot, size = rng.choice(self.states), C.c_size_t()
            status = self.call("state size", "SerializedFMUstateSize", slot, C.byref(size))
            if status == OK:
                wanted = size.value + rng.choice([0, 0, 0, -1, 1])
                buffer = C.create_string_buffer(max(wanted, 1))
                if self.call("serialize", "SerializeFMUstate", slot, buffer, wanted) == OK:
                    self.blobs.append(buffer.raw[:wanted])
            return f"serialize -> {status}"
        blob = self.blob()
        slot = C.c_void_p()
        status = self.call("deserialize", "DeSerializeFMUstate", blob, len(blob), C.byref(slot))
        if status == OK:
            self.states.append(slot)
            applied = self.call("set deserialized", "SetFMUstate", slot)
            return f"deserialize {blob[:60]!r}... -> {status}, set -> {applied}"
        return f"deserialize -> {status}"

    def blob(self):
        """A state blob: valid, truncated, bit-flipped, forged (a leaf of the JSON changed), or garbage."""
        rng = self.rng
        if not self.blobs or rng.random() < 0.1:
            return bytes(rng.getrandbits(8) for _ in range(rng.randint(0, 64)))
        blob = rng.choice(self.blobs)
        kind = rng.choice(["valid", "truncated", "flipped", "forged", "forged", "forged"])
        if kind == "valid":
            return blob
        if kind == "truncated":
            return blob[:rng.randint(0, max(len(blob) - 1, 0))]
        if kind == "flipped":
            data = bytearray(blob)
            for _ in range(rng.randint(1, 4)):
                if data:
                    data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
            return bytes(data)
        try:
            document = json.loads(blob)
        except ValueError:
            return blob
        forge(rng, document)
        return json.dumps(document).encode()

    # ------------------------------------------------------------ the end: the instance still works

    def survives(self):
        instance = self.instance
        ok = [self.call("reset", "Reset"), self.call("setup", "SetupExperiment", 0, 0.0, 0.0, 0, 0.0),
              self.call("enter", "EnterInitializationMode"), self.call("exit", "ExitInitializationMode"),
              self.call("step", "DoStep", 0.0, 0.1, 1)]
        status, values = instance.get(*self.binary.outputs)
        self.finite_if_ok("final outputs", status, values)
        if ok + [status] != [OK] * 6:
            self.violations.append(f"the instance does not reset and step at the end: {ok + [status]}")
        for slot in self.states:
            instance.call("FreeFMUstate", C.byref(slot))  # freed ones are refused, live ones freed
        for each in self.instances:
            each.free()


def forge(rng, document):
    """Change one leaf of a state document (in place) to a value of the wrong kind or size."""
    path, node = [], document
    while isinstance(node, (dict, list)) and node:
        key = rng.choice(list(node)) if isinstance(node, dict) else rng.randrange(len(node))
        path.append((node, key))
        node = node[key]
        if rng.random() < 0.2:
            break
    if not path:
        return
    parent, key = path[-1]
    choice = rng.random()
    if choice < 0.15 and isinstance(parent, dict):
        del parent[key]
    elif choice < 0.25 and isinstance(parent, list):
        parent.append(parent[key])
    elif choice < 0.3 and isinstance(parent, list):
        parent.pop(key)
    else:
        parent[key] = rng.choice(NUMBERS + ["projected", "nonsense", None, True, [], {}, [1.0, 2.0], -1, 10**400])


def fuzz(seed, element_fmu, connector_fmu, calls=CALLS):
    """Run ``calls`` random operations on each FMU; print every operation, then the violations as JSON."""
    violations = []
    for path in (element_fmu, connector_fmu):
        rng = random.Random(f"{seed} {path.rsplit('/', 1)[-1]}")
        fuzzer = Fuzzer(rng, Binary(path))
        operations = [fuzzer.lifecycle, fuzzer.restart] + [fuzzer.step] * 5 + [fuzzer.set_value] * 2 + \
            [fuzzer.get_values] * 2 + [fuzzer.null_pointer, fuzzer.status, fuzzer.stale] + [fuzzer.state] * 3
        for index in range(calls):
            fuzzer.pick()
            print(index, fuzzer.instances.index(fuzzer.instance), rng.choice(operations)(), flush=True)
        fuzzer.survives()
        violations += fuzzer.violations
    print("VIOLATIONS", json.dumps(violations), flush=True)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pythonfmu_fuzz")
    return build(folder, ELEMENT_SCENE, "element"), build(folder, CONNECTOR_SCENE, "connector")


@pytest.mark.parametrize("seed", SEEDS)
def test_random_fmi_call_sequences_never_crash_and_never_hand_out_a_non_finite_value(fmus, seed):
    script = ("import sys; from tests.fmu.python.test_hostile_call_sequences import fuzz; "
              "fuzz(int(sys.argv[1]), sys.argv[2], sys.argv[3], int(sys.argv[4]))")
    done = run_child(script, seed, *fmus, CALLS, timeout=240)
    lines = done.stdout.splitlines()
    assert done.returncode == 0, (f"seed {seed}: the child died ({done.returncode}) after", lines[-15:],
                                  done.stderr[-2000:])
    assert lines and lines[-1].startswith("VIOLATIONS "), (lines[-5:], done.stderr[-2000:])
    assert json.loads(lines[-1][len("VIOLATIONS "):]) == [], f"seed {seed}"


# python -m tests.fmu.python.test_hostile_call_sequences SEED ELEMENT_FMU CONNECTOR_FMU [CALLS]
if __name__ == "__main__":
    fuzz(int(sys.argv[1]), sys.argv[2], sys.argv[3], *map(int, sys.argv[4:5]))
