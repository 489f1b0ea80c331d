"""The native FMU trusts nothing it is handed (issue 31, the native part): FMI 2.0 and 3.0, the element (on the
memory stack; a continuum too for the forged stack) and the connector (series dashpots), each in the small C host
of tests/c_host/trust_host.c built with the sanitizers where the compiler has them (the FMU too): a crash, an
invalid access, undefined behaviour or a leak ends the host with an error, and every test asserts that the host ran
to its end.

Item by item: a communication step of more internal steps than ADVANCE_BUDGET is discarded at once (4);
coefficients without a physical magnitude are refused in the library's words (3); a NULL instance (6) or NULL
pointer (7) is an error, never a crash; a non-finite communication point, step or start time is an error (9); no
output is NaN or inf with an OK status, a step that would make one is rolled back (10); the call sequence of the
standard is enforced (12); a state blob with a recomputed checksum is checked field by field (5)."""
import math
import os
import shutil
import struct

import numpy as np
import pytest

from prandtl_fmu import scene as rules
from prandtl_fmu.kernels import stack

from tests.conftest import base_tables
from tests.native_host import built_native, compile_trust_host, run_trust

# the native FMUs rebuilt with AddressSanitizer and UBSan for a C host (about two minutes of building, cold):
# run by .ci/run after the quick suite, as `pytest -m slow`; tests/fmu/native/test_c_host.py keeps a C host in the
# quick one
pytestmark = pytest.mark.slow

if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

OK, DISCARD, ERROR = 0, 2, 3
DECLARED = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal", "logAll"}
SOLVER = {"stepper": "implicit", "step": 1e-3, "stop_time": 1.0, "output_interval": 0.1}
N_STACK = 70
# the element: mass, spring, dashpot, 70 branches on the memory stack (no cubic spring: x may grow huge while the
# forces stay finite, so that an energy overflows first)
ELEMENT = base_tables(cubic=None, solver=SOLVER,
                      branches={"k": [0.02] * N_STACK, "eta": np.linspace(0.01, 0.8, N_STACK).tolist()})
# the connector: spring, dashpot, three branches with series dashpots (the O(n) kernel)
N_SERIES = 3
CONNECTOR = base_tables(mass=None, cubic=None, solver=SOLVER, fmu={"causality": "displacement"},
                        branches={"k": [1.0, 0.6, 2.0], "eta": [0.1, 0.3, 0.05], "c": [0.5, 2.0, 8.0]})
SCENES = {"element": ELEMENT, "connector": CONNECTOR}
# the continuum (a spectrum on the memory stack, its own rules of a valid stack): for the forged stack only
CONTINUUM = base_tables(cubic=None, damper=None, solver=dict(SOLVER, stepper="verlet"),
                        branches={"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0]})
START = ["setup:0", "enter", "exit"]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("trust")
    return {(name, fmi): (compile_trust_host(folder, fmi), built_native(name, tables, fmi, folder))
            for name, tables in SCENES.items() for fmi in (2, 3)}


def ran(run):
    """The host ended by itself, no sanitizer spoke, and every message has a declared category."""
    assert run.code == 0 and run.ended, run.out[-3000:]
    assert all(category in DECLARED for _, category, _ in run.logs), run.logs
    return run


def both(test):
    return pytest.mark.parametrize("fmi", [2, 3])(test)


# ------------------------------------------------------------------ 4: the advance budget


@both
def test_a_communication_step_beyond_the_advance_budget_is_discarded_at_once(fmus, fmi):
    """1e7 s and 1e12 s with h = 1e-3 (1e10 and 1e15 internal steps, more than ADVANCE_BUDGET = 1e8): fmi2Discard /
    fmi3Discard in well under the host's timeout, the reason gives the count and the budget, the state is unchanged
    (the next step is the one a fresh instance takes). fmi2CancelStep is no way out: it is refused (no step is in
    progress)."""
    host, fmu = fmus["element", fmi]
    commands = START + ["setr:F:0.3", "step:0:0.1", "getr:x", "step:0.1:1e7", "step:0.1:1e12", "cancel",
                        "step:0.1:0.1", "getr:x"]
    run = ran(run_trust(host, fmu, commands, timeout=60))
    assert run.status("step:0.1:1e7") == DISCARD and run.status("step:0.1:1e12") == DISCARD, run.out
    assert run.status("cancel") == ERROR
    assert run.status("step:0.1:0.1") == OK
    budget = f"more than the budget of {rules.ADVANCE_BUDGET:.0e} steps of one advance"
    assert run.said("takes 1e+10 steps of h = 0.001 s, " + budget), run.logs
    assert run.said("takes 1e+15 steps of h = 0.001 s, " + budget), run.logs
    fresh = ran(run_trust(host, fmu, START + ["setr:F:0.3", "step:0:0.1", "step:0.1:0.1", "getr:x"]))
    assert run.values[-1] == fresh.values[-1]


# ------------------------------------------------------------------ 3: magnitudes


@both
@pytest.mark.parametrize("name, culprit", [("element", "m"), ("element", "k0"), ("connector", "k0"),
                                           ("connector", "c_branch[2]")])
@pytest.mark.parametrize("value", [1e-60, 1e60, -1e300])
def test_a_coefficient_without_a_physical_magnitude_is_refused_in_the_library_s_words(fmus, fmi, name, culprit,
                                                                                       value):
    """scene.magnitude_problem's reason, word for word: at initialization (Error) and at a step (Discard), the
    instance usable again once the value is set right."""
    host, fmu = fmus[name, fmi]
    good = {"m": 1.0, "k0": 0.2, "c_branch[2]": 2.0}[culprit]  # the scene's
    run = ran(run_trust(host, fmu, ["setup:0", "enter", f"setr:{culprit}:{value!r}", "exit",
                                    f"setr:{culprit}:{good!r}", "exit", f"setr:{culprit}:{value!r}", "step:0:0.1",
                                    f"setr:{culprit}:{good!r}", "step:0:0.1"]))
    assert [status for command, status in run.calls if command == "exit"] == [str(ERROR), str(OK)], run.out
    assert [status for command, status in run.calls if command == "step:0:0.1"] == [str(DISCARD), str(OK)]
    words = rules.magnitude_problem(value)
    assert words and len(run.said(f"parameter {culprit}: {words}")) == 2, (words, run.logs)


@both
@pytest.mark.parametrize("value, refused", [(1e-60, False), (-5e-324, False), (1e60, True)])
def test_a_value_has_only_the_upper_bound_as_in_the_library(fmus, fmi, value, refused):
    """x0 is a value (scene.VALUES): a tiny one is as good as 0 and accepted, a huge one refused in the library's
    words, as the scene reader and the PythonFMU FMU do."""
    host, fmu = fmus["element", fmi]
    run = ran(run_trust(host, fmu, ["setup:0", "enter", f"setr:x0:{value!r}", "exit"]))
    assert [status for command, status in run.calls if command == "exit"] == [str(ERROR if refused else OK)], run.out
    words = rules.magnitude_problem(value, coefficient=False)
    assert (words is not None) == refused
    if refused:
        assert run.said(f"parameter x0: {words}"), run.logs


# ------------------------------------------------------------------ 6 and 7: NULL instance, NULL pointers


@both
@pytest.mark.parametrize("name", list(SCENES))
def test_every_function_refuses_a_null_instance(fmus, fmi, name):
    host, fmu = fmus[name, fmi]
    run = ran(run_trust(host, fmu, ["nullc"]))
    calls = [(command, status) for command, status in run.calls if command.startswith("nullc:")]
    assert len(calls) >= 28, run.out
    assert all(status == str(ERROR) for command, status in calls if not command.endswith("FreeInstance")), calls


@both
@pytest.mark.parametrize("name", list(SCENES))
@pytest.mark.parametrize("phase", [[], START, START + ["step:0:0.1", "term"]])
def test_null_pointers_are_refused_with_a_logged_reason_logging_off(fmus, fmi, name, phase):
    """Every getter, setter and state function handed NULL (vr, value, FMUstate, size, bytes, ...) returns an error
    and logs why (logging off), in every phase; the instance still steps afterwards."""
    host, fmu = fmus[name, fmi]
    run = ran(run_trust(host, fmu, phase + ["nulla:stepper" if "stepper" in fmu.vr else "nulla:k0"]))
    calls = [(command, status) for command, status in run.calls if command.startswith("nulla:")
             and "(" in command]
    assert len(calls) >= 16, run.out
    assert all(status == str(ERROR) for _, status in calls), calls
    errors = [message for status, _, message in run.logs if status == ERROR]
    assert len(errors) >= len(calls), run.logs  # each with its reason: the NULL argument, or before it the call
    named = [message for message in errors if "NULL" in message or "call sequence" in message]  # sequence (a setter
    assert len(named) >= len(calls) - 1, run.logs  # after Terminate), or the connector's missing String variable
    if not phase:
        after = ran(run_trust(host, fmu, ["nulla:k0"] + START + ["step:0:0.1", "getr:" + _output(name)]))
        assert after.status("step:0:0.1") == OK and len(after.values) == 1


def _output(name):
    return "x" if name == "element" else "force"


# ------------------------------------------------------------------ 9: non-finite times


@both
@pytest.mark.parametrize("name", list(SCENES))
def test_a_non_finite_time_or_step_is_an_error_and_the_clock_stays_a_number(fmus, fmi, name):
    host, fmu = fmus[name, fmi]
    for bad, reason in (("nan", "the start time nan must be finite"), ("inf", "the start time inf must be finite"),
                        ("0:-1", "the stop time -1 must be finite and >= the start time 0")):
        run = ran(run_trust(host, fmu, [f"setup:{bad}", "enter", "exit", "step:0:0.1"]))
        refused = "setup" if fmi == 2 else "enter"  # fmi2SetupExperiment, fmi3EnterInitializationMode
        assert run.status(f"setup:{bad}" if fmi == 2 else "enter") == ERROR, run.out
        assert run.said(f"fmi{fmi}{'SetupExperiment' if refused == 'setup' else 'EnterInitializationMode'} refused: "
                        + reason), run.logs
    steps = ["step:nan:0.1", "step:0:nan", "step:0:inf", "step:0:-0.1", "step:inf:0.1", "step:1e308:1e308"]
    run = ran(run_trust(host, fmu, START + steps + ["step:0:0.1", "getr:" + _output(name)]
                        + (["getr:time"] if fmi == 3 else ["status"])))
    assert [run.status(step) for step in steps] == [ERROR] * len(steps), run.out
    assert len(run.said("must be finite, the step >= 0")) == len(steps)
    assert run.status("step:0:0.1") == OK
    assert all(math.isfinite(value) for _, value in run.values)
    if fmi == 2:  # fmi2GetRealStatus(fmi2LastSuccessfulTime): the element's clock after its one step
        time = float(next(line for line in run.out.splitlines() if line.startswith("STATUS ")).split()[1])
        assert time == (0.1 if name == "element" else 0.0)  # the connector's clock: the last sample, at t = 0


# ------------------------------------------------------------------ 10: no output NaN or inf with OK


@both
def test_a_connector_step_whose_outputs_overflow_is_rolled_back_and_named(fmus, fmi):
    """v = 1e308: dissipated_damper, c (v0^2 + v0 v + v^2) dt / 3, overflows: the step is discarded naming it, the
    state is unchanged (the outputs read as before), and no getter shows a non-finite value with OK."""
    host, fmu = fmus["connector", fmi]
    names = ["force", "stiffness", "stored_energy", "dissipated_sliders", "dissipated_damper"]
    reads = [f"getr:{name}" for name in names]
    run = ran(run_trust(host, fmu, START + ["setr:x:0.05", "setr:v:0.2", "step:0:0.1"] + reads
                        + ["setr:v:1e308", "step:0.1:0.1"] + reads + ["setr:v:0.2", "setr:x:1e308"] + reads
                        + ["setr:x:0.05"] + reads))
    assert run.status("step:0.1:0.1") == DISCARD, run.out
    assert run.said("dissipated_damper would be inf, not finite (an overflow); the state is unchanged"), run.logs
    values = [value for _, value in run.values]
    assert all(math.isfinite(value) for value in values)
    assert values[:5] == values[-5:]  # rolled back: the outputs at the same inputs as before
    # at x = 1e308 (not stepped) the force is 2e307 but the stored energy overflows: that getter refuses it
    assert run.status("getr:force", 2) == OK and run.status("getr:stored_energy", 2) == ERROR, run.out
    assert run.said("fmi{}{} refused: stored_energy is inf, not a finite number".format(
        fmi, "GetReal" if fmi == 2 else "GetFloat64")), run.logs


@both
def test_an_element_step_whose_energy_overflows_is_rolled_back_and_named(fmus, fmi):
    """F = 1e200 on a unit mass: after 0.1 s x and v are finite but the kinetic energy overflows: discarded naming
    it, the state unchanged."""
    host, fmu = fmus["element", fmi]
    reads = ["getr:x", "getr:v", "getr:kinetic_energy", "getr:work"]
    run = ran(run_trust(host, fmu, START + ["setr:F:0.3", "step:0:0.1"] + reads + ["setr:F:1e200", "step:0.1:0.1"]
                        + reads))
    assert run.status("step:0.1:0.1") == DISCARD, run.out
    assert run.said("with F = 9.9999999999999997e+199 refused: kinetic_energy would be inf, not finite (an "
                    "overflow); the state is unchanged"), run.logs
    values = [value for _, value in run.values]
    assert len(values) == 8 and values[:4] == values[4:] and all(map(math.isfinite, values))


# ------------------------------------------------------------------ 12: the call sequence


@both
@pytest.mark.parametrize("name", list(SCENES))
def test_the_call_sequence_of_the_standard_is_enforced(fmus, fmi, name):
    """Terminate before initialization and twice, parameters and inputs after Terminate, exit before enter, enter
    twice, doStep before initialization: errors with the reason; a NULL String value is refused as NULL (not as a
    wrong variable); FMI 3.0's fmi3EnterStepMode (no event mode) is refused; fmi2/3Reset starts again."""
    host, fmu = fmus[name, fmi]
    run = ran(run_trust(host, fmu, ["term", "exit", "step:0:0.1", "setup:0", "enter", "enter", "term", "exit",
                                    "cancel", "step:0:0.1", "term", "term", "setr:k0:0.5", "step:0.1:0.1",
                                    "getr:k0", "reset", "setup:0", "enter", "exit", "step:0:0.1"]))
    statuses = [int(status) for _, status in run.calls[1:]]
    assert statuses == [ERROR, ERROR, ERROR, OK, OK, ERROR, ERROR, OK, ERROR, OK, OK, ERROR, ERROR, ERROR, OK, OK,
                        OK, OK, OK, OK], run.out
    sequence = run.said(f"(the FMI {fmi}.0 co-simulation call sequence)")
    assert len(sequence) == 9, run.logs
    assert f"fmi{fmi}Terminate refused: not allowed in the state 'instantiated'" in sequence[0]
    assert f"fmi{fmi}SetFloat64" in run.out or f"fmi{fmi}SetReal refused: not allowed in the state 'terminated'" \
        in run.out
    if name == "element":
        nulls = ran(run_trust(host, fmu, ["sets:stepper:NULL", "sets:stepper:verlet"]))
        assert nulls.status("sets:stepper:NULL") == ERROR and nulls.status("sets:stepper:verlet") == OK
        assert nulls.said("[0] is NULL (a stepper's name is needed)"), nulls.logs


# ------------------------------------------------------------------ 5: forged state blobs


def fnv1a(data: bytes) -> int:
    value = 1469598103934665603
    for byte in data:
        value = ((value ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return value


def forged(blob: bytes, changes) -> bytes:
    """``blob`` with doubles written at byte offsets ``changes`` {offset: value} and its checksum recomputed
    (common.h: FNV-1a of every byte before it, the last field)."""
    data = bytearray(blob)
    for offset, value in changes.items():
        data[offset:offset + 8] = struct.pack("<d", value)
    data[-8:] = struct.pack("<Q", fnv1a(bytes(data[:-8])))
    return bytes(data)


# where the fields are (the State of element.h / connector.h on x86-64): the head (magic 24, version and size 8,
# digest 65) ends at 97, the Element starts at 104 with p[10], then cs[max(n, 1)]
ELEMENT_AT = 104


def element_u(n):
    """The element's u: after p, cs, the stepper (an int, padded), h, x, v."""
    return ELEMENT_AT + 8 * (10 + n) + 8 + 24


def connector_u(n):
    """The connector's u: after p, cs, x, v, time, direction."""
    return ELEMENT_AT + 8 * (10 + n) + 32


STACK_FORGERIES = {  # the memory stack's state: count, top, d, SK, S0, moves, x, then rows (lo, hi, a, beta, gamma)
    "a billion pieces": ({0: 1e9}, "memory-stack state: wrong count of pieces"),
    "a piece of 1e300": ({7 + 2: 1e300}, "memory-stack state:"),
    "a NaN piece": ({7 + 2: math.nan}, "not a memory-stack state"),
    "a piece from -5": ({7 + 0: -5.0}, "memory-stack state: the pieces do not tile the branches"),
    "a NaN total": ({3: math.nan}, "not a memory-stack state"),
    "a wrong total": ({4: 123.0}, "memory-stack state: the running totals do not match the pieces"),
    "half a piece": ({0: 0.5}, "memory-stack state: wrong count of pieces"),
    # a weight of u0 the stack never makes: with u0 = 0 every elongation stays admissible, and the stored energy's
    # closed form was inf - inf after an OK step (the adversarial review of issue 46's bounds)
    "a gamma of 2^520": ({7 + 4: 2.0 ** 520}, stack.GAMMA_REFUSAL),
}


@pytest.fixture(scope="module")
def continuum(tmp_path_factory):
    folder = tmp_path_factory.mktemp("trust_continuum")
    return compile_trust_host(folder, 2), built_native("continuum", CONTINUUM, 2, folder)


@pytest.mark.parametrize("name, fmi", [("element", 2), ("element", 3), ("continuum", 2)])
@pytest.mark.parametrize("forgery", list(STACK_FORGERIES))
def test_a_forged_memory_stack_with_a_recomputed_checksum_is_refused(fmus, continuum, name, fmi, forgery, tmp_path):
    """The stack's header and pieces (a billion pieces made the next doStep read far beyond the array; 1e300,
    NaN, -5 gave a silently wrong x): fmi2/3DeSerializeFMUState refuses them with the library's reason, and so does
    fmi2/3SetFMUState when the forged bytes are written over a state's memory; the instance is unchanged and
    steps on. The blob itself, unforged, is accepted and continues bit for bit."""
    host, fmu = continuum if name == "continuum" else fmus["element", fmi]
    changes, reason = STACK_FORGERIES[forgery]
    blob_path = tmp_path / "state.bin"
    first = ran(run_trust(host, fmu, START + ["setr:F:0.4", "step:0:0.3", "save", f"dump:{blob_path}",
                                              "step:0.3:0.1", "getr:x"]))
    blob = blob_path.read_bytes()
    u = element_u(N_STACK if name == "element" else 1)
    count, stack_x = struct.unpack_from("<d", blob, u)[0], struct.unpack_from("<d", blob, u + 8 * 6)[0]
    assert count >= 1 and count == int(count) and math.isfinite(stack_x), (count, stack_x)  # the layout holds
    bad = tmp_path / "forged.bin"
    bad.write_bytes(forged(blob, {u + 8 * index: value for index, value in changes.items()}))
    unchanged = tmp_path / "unchanged.bin"
    unchanged.write_bytes(forged(blob, {}))
    run = ran(run_trust(host, fmu, START + ["setr:F:0.4", "step:0:0.3", "save", f"load:{bad}", f"poke:{bad}",
                                            "restore", "step:0.3:0.1", "getr:x", f"load:{unchanged}", "restore",
                                            "step:0.3:0.1", "getr:x"]))
    assert run.status(f"load:{bad}") == ERROR and run.status("restore") == ERROR, run.out
    refusals = run.said(reason)
    assert len(refusals) == 2 and all("FMU state refused" in text for text in refusals), (reason, run.logs)
    assert run.status("step:0.3:0.1") == OK and run.status(f"load:{unchanged}") == OK
    assert run.status("restore", 1) == OK
    assert [value for _, value in run.values] == [first.values[-1][1]] * 2  # unchanged; the blob continues


ELEMENT_FORGERIES = {  # byte offsets in the element's State, relative to its Element
    "m = NaN in use": ({0: math.nan}, "parameter m: must be finite"),
    "m = 1e-300 in use": ({0: 1e-300}, "parameter m: |1e-300| is outside"),
    "x = inf": ({8 * (10 + N_STACK) + 8 + 8: math.inf}, "non-finite or out-of-range value"),
    "h = -1": ({8 * (10 + N_STACK) + 8: -1.0}, "non-finite or out-of-range value"),
}
CONNECTOR_FORGERIES = {
    "an elongation beyond its range": ({connector_u(N_SERIES) - ELEMENT_AT: 10.0}, "branch 1 has elongation 10"),
    "k0 = 1e300 in use": ({8 * 3: 1e300}, "parameter k0: |1e+300| is outside"),
    "c_branch[1] = -1 in use": ({8 * 10: -1.0}, "parameter c_branch[1]: must be > 0"),
    "a NaN direction": ({8 * (10 + N_SERIES) + 24: math.nan}, "non-finite or out-of-range value"),
    # the account after u[3]: [0] unused, [1] the sliders' dissipation, [2] the dashpots'
    "a negative dissipation": ({connector_u(N_SERIES) - ELEMENT_AT + 8 * (N_SERIES + 1): -1.0},
                               "a dissipation is negative"),
}


@both
@pytest.mark.parametrize("name, forgery", [("element", f) for f in ELEMENT_FORGERIES]
                         + [("connector", f) for f in CONNECTOR_FORGERIES])
def test_a_forged_field_with_a_recomputed_checksum_is_refused(fmus, fmi, name, forgery, tmp_path):
    """The coefficients in use (checked by parameter_problem, as the setters' values), the motion, the step, the
    elongations: refused by fmi2/3DeSerializeFMUState and fmi2/3SetFMUState with the reason."""
    host, fmu = fmus[name, fmi]
    changes, reason = (ELEMENT_FORGERIES if name == "element" else CONNECTOR_FORGERIES)[forgery]
    blob_path = tmp_path / "state.bin"
    inputs = ["setr:F:0.4"] if name == "element" else ["setr:x:0.05", "setr:v:0.2"]
    ran(run_trust(host, fmu, START + inputs + ["step:0:0.3", "save", f"dump:{blob_path}"]))
    bad = tmp_path / "forged.bin"
    bad.write_bytes(forged(blob_path.read_bytes(), {ELEMENT_AT + at: value for at, value in changes.items()}))
    run = ran(run_trust(host, fmu, START + inputs + ["step:0:0.3", "save", f"load:{bad}", f"poke:{bad}", "restore",
                                                     "step:0.3:0.1", "getr:" + _output(name)]))
    assert run.status(f"load:{bad}") == ERROR and run.status("restore") == ERROR, run.out
    assert len(run.said(reason)) == 2, (reason, run.logs)
    assert run.status("step:0.3:0.1") == OK and math.isfinite(run.values[-1][1])


# ------------------------------------------------------------------ input derivatives (issue 61)


@pytest.mark.parametrize("name", list(SCENES))
def test_bad_input_derivatives_are_refused_with_a_logged_reason_never_a_crash(fmus, name):
    """fmi2SetRealInputDerivatives handed a variable that is not an input it takes derivatives of, an unknown value
    reference, order 0 or 3, a NaN: each an error with its reason (logging off), nothing set, the instance steps
    on; the element takes F's orders 1 and 2; the connector takes x's and v's, but not with branches with series
    dashpots (this one): refused, saying so."""
    host, fmu = fmus[name, 2]
    given = "F" if name == "element" else "x"
    bad = [f"deriv:{given}:3:0.1", f"deriv:{given}:0:0.1", "deriv:999999:1:0.1", f"deriv:{given}:1:nan"]
    bad.append("deriv:x:1:0.1" if name == "element" else "deriv:force:1:0.1")
    good = ["deriv:F:1:0.5", "deriv:F:2:-0.3"] if name == "element" else []
    held = [] if name == "element" else ["deriv:x:1:0.5", "deriv:v:2:-0.3"]  # well formed, refused with series
    start = ["setup:0", "enter", "setb:scene_load:0", "exit"] if name == "element" else START  # F alone
    run = ran(run_trust(host, fmu, start + bad + good + held + ["step:0:0.1", "getr:" + _output(name)]))
    for command in bad + held:
        assert run.status(command) == ERROR, command
    for command in good:
        assert run.status(command) == OK, command
    assert run.status("step:0:0.1") == OK and len(run.values) == 1 and math.isfinite(run.values[0][1])
    if name == "element":
        for words in ("order 3 of F", "order 0 of F", "value reference 999999 is not the continuous input F",
                      "order 1 = nan must be finite", f"value reference {fmu.vr['x']} is not the continuous input F"):
            assert run.said(words), (words, run.logs)
    else:
        for words in ("order 3 of x", "order 0 of x", "value reference 999999 is not the input x or v",
                      "order 1 = nan must be finite", f"value reference {fmu.vr['force']} is not the input x or v"):
            assert run.said(words), (words, run.logs)
        assert len(run.said("with series dashpots or effects with memory")) == len(held), run.logs


def test_bad_output_derivative_requests_are_refused_with_a_logged_reason_never_a_crash(fmus):
    """fmi2GetRealOutputDerivatives of the element asked for order 0 and 3, the reaction's order 2, an input, an
    unknown value reference: each an error with its reason, nothing written; x's order 1 is v."""
    host, fmu = fmus["element", 2]
    bad = ["oderiv:x:0", "oderiv:x:3", "oderiv:reaction:2", "oderiv:F:1", "oderiv:999999:1"]
    run = ran(run_trust(host, fmu, ["setup:0", "enter", "setb:scene_load:0", "exit", "setr:F:0.3", "step:0:0.1"]
                        + bad + ["oderiv:x:1", "getr:v"]))
    for command in bad:
        assert run.status(command) == ERROR, command
    assert run.status("oderiv:x:1") == OK
    assert len(run.values) == 2 and run.values[0][1] == run.values[1][1]  # x' = v, to the bit
    for words in ("order 0", "order 3", "the reaction's derivative of order 2 is not given",
                  "not an output whose derivatives"):
        assert run.said(words), (words, run.logs)


# ------------------------------------------------------------------ a negative delay gain against the step

DELAYED = base_tables(cubic=None, solver=SOLVER, delay={"gain": -0.3, "tau": 0.01})


@pytest.fixture(scope="module")
def delayed(tmp_path_factory):
    folder = tmp_path_factory.mktemp("trust_delay")
    return {fmi: (compile_trust_host(folder, fmi), built_native("delayed", DELAYED, fmi, folder)) for fmi in (2, 3)}


@both
@pytest.mark.parametrize("logging", [False, True], ids=["logging off", "logging on"])
@pytest.mark.parametrize("setting, named", [("delay_tau:0.0005", "parameter delay_gain"),
                                            ("step:0.05", "parameter step = 0.05")], ids=["tau", "step"])
def test_a_negative_delay_gain_with_tau_below_the_step_is_refused_with_the_library_s_remedy(delayed, fmi, logging,
                                                                                          setting, named):
    """A tau below the step (or a step above tau) with a negative delay gain, set in initialization: exiting it is
    an error whose logged reason names the parameter and the library's remedy word for word (a [solver] step no
    longer than tau, or a longer tau: scene.py), logging off or on, and the host ends by itself, no sanitizer
    speaking; a step after it is refused too."""
    host, fmu = delayed[fmi]
    run = ran(run_trust(host, fmu, ["setup:0", "enter", f"setr:{setting}", "exit", "step:0:0.01"], logging=logging))
    assert run.status("exit") == ERROR and run.status("step:0:0.01") == ERROR
    said = run.said("a [solver] step no longer than tau, or a longer tau")
    assert len(said) == 1 and named in said[0] and "non-monotone" in said[0], run.logs
