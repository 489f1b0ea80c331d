"""The small C host of ``tests/c_host/fmi2_host.c``: compiled once per test process, run on an extracted FMU.

A host that is not a Python process meets what FMPy forgives (a NULL log category aborts OMSimulator, a refusal
must reach a logger that was instantiated with logging off). A PythonFMU FMU in such a host needs the host's
libpython preloaded and the environment's packages on PYTHONPATH (the README's recipe): :func:`python_recipe`.

The trust host of ``tests/c_host/trust_host.c`` (FMI 2.0 or 3.0, with the sanitizers where they run) calls a native
FMU as nobody should (issue 31): :func:`compile_trust_host`, :func:`built_native`, :func:`run_trust`."""
import os
import shutil
import subprocess
import sys
import sysconfig
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "c_host" / "fmi2_host.c"
FMI_HEADERS = HERE.parent / "prandtl_fmu" / "fmu" / "python" / "loader" / "src" / "fmi"
_BUILT = {}


def compile_host(folder: Path) -> Path:
    """The host's executable (built with the system's C compiler into ``folder``); skips without one."""
    if "host" in _BUILT:
        return _BUILT["host"]
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler (cc or gcc) to build the test host")
    out = Path(folder) / "fmi2_host"
    subprocess.run([compiler, "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-O1", "-Wall", "-Werror",
                    f"-I{FMI_HEADERS}", str(SOURCE), "-o", str(out), "-ldl"], check=True, capture_output=True)
    _BUILT["host"] = out
    return out


def python_recipe() -> dict:
    """The environment in which a native host can run a PythonFMU FMU: libpython preloaded, this environment's
    packages and the project on PYTHONPATH. Skips where Python was built without a shared libpython."""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        pytest.skip("this Python has no shared libpython: a native host cannot load a PythonFMU FMU")
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("LDLIBRARY")
    paths = [p for p in sys.path if p.endswith("-packages")] + [str(HERE.parent)]
    return dict(os.environ, LD_PRELOAD=str(libpython), PYTHONPATH=os.pathsep.join(paths))


class Extracted:
    """An FMU unpacked into a folder: its library, resource URI, GUID and value references by name."""

    def __init__(self, fmu: Path, folder: Path):
        folder.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(fmu) as archive:
            archive.extractall(folder)
        root = ET.parse(folder / "modelDescription.xml").getroot()
        self.guid = root.get("guid")
        identifier = root.find("CoSimulation").get("modelIdentifier")
        self.library = folder / "binaries" / "linux64" / f"{identifier}.so"
        self.resources = (folder / "resources").as_uri()
        self.vr = {v.get("name"): int(v.get("valueReference")) for v in root.iter("ScalarVariable")}
        self.outputs = [v.get("name") for v in root.iter("ScalarVariable") if v.get("causality") == "output"]


def run_host(host: Path, fmu: Extracted, commands, logging: bool = False, env=None, timeout=300):
    """Run the host; returns (returncode, calls {command: [status...]}, logs [(status, category, message)],
    values [(vr, value)], stdout). Commands may name variables: ``setr:m:-1``, ``getr:x``."""
    argv = [str(host), str(fmu.library), fmu.resources, fmu.guid, "1" if logging else "0"]
    written = {}  # the command as the host prints it -> as the caller wrote it
    for command in commands:
        parts = command.split(":")
        if parts[0] in ("setr", "getr", "setb", "sets") and not parts[1].isdigit():
            parts[1] = str(fmu.vr[parts[1]])
        if parts[0] == "timeit":
            parts = parts[:4] + [str(fmu.vr[name]) if not name.isdigit() else name for name in parts[4:]]
        argv.append(":".join(parts))
        written[argv[-1]] = command
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout,
                          env=env if env is not None else python_recipe())
    calls, logs, values = {}, [], []
    for line in done.stdout.splitlines():
        if line.startswith("CALL "):
            name, _, status = line[5:].rpartition(" ")
            calls.setdefault(written.get(name, name), []).append(status)
        elif line.startswith("LOG "):
            status, category, message = line[4:].split(" ", 2)
            logs.append((int(status), category, message))
        elif line.startswith("VALUE "):
            _, vr, value = line.split(" ")
            values.append((int(vr), float(value)))
    return done.returncode, calls, logs, values, done.stdout + done.stderr


# ------------------------------------------------------------------ the trust host (issue 31)

TRUST_SOURCE = HERE / "c_host" / "trust_host.c"
FMI3_HEADERS = HERE.parent / "prandtl_fmu" / "fmu" / "native" / "fmi3"
SANITIZERS = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]
# a leak, an invalid access or undefined behaviour ends the process with an error: the tests see it
SANITIZER_ENV = {"ASAN_OPTIONS": "detect_leaks=1:exitcode=86", "UBSAN_OPTIONS": "halt_on_error=1:exitcode=87"}


def _compiler() -> str:
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler (cc or gcc) to build the test host")
    return compiler


def sanitizers() -> list:
    """The sanitizer flags where the compiler has them and a sanitized program runs here, else []."""
    if "sanitizers" not in _BUILT:
        import tempfile

        flags = []
        with tempfile.TemporaryDirectory() as folder:
            probe = Path(folder) / "probe.c"
            probe.write_text("#include <stdlib.h>\nint main(void) { free(malloc(8)); return 0; }\n")
            built = subprocess.run([_compiler(), *SANITIZERS, str(probe), "-o", str(Path(folder) / "probe")],
                                   capture_output=True)
            if built.returncode == 0 and subprocess.run([str(Path(folder) / "probe")], capture_output=True,
                                                        env=dict(os.environ, **SANITIZER_ENV)).returncode == 0:
                flags = SANITIZERS
        _BUILT["sanitizers"] = flags
    return _BUILT["sanitizers"]


def compile_trust_host(folder: Path, fmi: int) -> Path:
    """tests/c_host/trust_host.c for FMI ``fmi`` (2 or 3), with the sanitizers where they run."""
    key = f"trust{fmi}"
    if key not in _BUILT:
        out = Path(folder) / f"trust_host{fmi}"
        headers = FMI_HEADERS if fmi == 2 else FMI3_HEADERS
        subprocess.run([_compiler(), "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-O1", "-Wall", "-Werror",
                        f"-DFMI_VERSION={fmi}", *sanitizers(), f"-I{headers}", str(TRUST_SOURCE), "-o", str(out),
                        "-ldl"], check=True, capture_output=True)
        _BUILT[key] = out
    return _BUILT[key]


class Native:
    """A native FMU (FMI 2.0 or 3.0) built with the sanitizers where they run, unpacked: its library, token (GUID),
    value references by name and outputs."""

    def __init__(self, fmu: Path, folder: Path, fmi: int):
        folder.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(fmu) as archive:
            archive.extractall(folder)
        root = ET.parse(folder / "modelDescription.xml").getroot()
        self.fmi = fmi
        self.guid = root.get("guid") if fmi == 2 else root.get("instantiationToken")
        identifier = root.find("CoSimulation").get("modelIdentifier")
        platform = "linux64" if fmi == 2 else "x86_64-linux"
        self.library = folder / "binaries" / platform / f"{identifier}.so"
        variables = list(root.iter("ScalarVariable")) if fmi == 2 else list(root.find("ModelVariables"))
        self.vr = {v.get("name"): int(v.get("valueReference")) for v in variables}
        self.outputs = [v.get("name") for v in variables if v.get("causality") == "output"]


def built_native(name: str, tables: dict, fmi: int, folder: Path) -> Native:
    """The native FMU of ``tables`` for FMI ``fmi``, built once per test process (with the sanitizers' flags where
    they run: $PRANDTL_NATIVE_CFLAGS) and shared by the test modules."""
    from prandtl_fmu.fmu.build import build_fmu

    from tests.conftest import scene_text

    key = ("native", name, fmi)
    if key not in _BUILT:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        scene = folder / f"{name}.toml"
        scene.write_text(scene_text(tables))
        saved = os.environ.get("PRANDTL_NATIVE_CFLAGS")
        os.environ["PRANDTL_NATIVE_CFLAGS"] = " ".join(sanitizers())
        try:
            fmu = build_fmu(scene, folder / f"{name}-{fmi}.fmu", runtime="native", fmi=fmi)
        finally:
            if saved is None:
                del os.environ["PRANDTL_NATIVE_CFLAGS"]
            else:
                os.environ["PRANDTL_NATIVE_CFLAGS"] = saved
        _BUILT[key] = Native(fmu, folder / f"{name}-{fmi}", fmi)
    return _BUILT[key]


class Run:
    """What the trust host did: its return code, the statuses of the calls in order [(command, status)], the logs
    [(status, category, message)], the values read [(vr, value)], its whole output."""

    def __init__(self, done, written):
        self.code, self.calls, self.logs, self.values = done.returncode, [], [], []
        self.out = done.stdout + done.stderr
        for line in done.stdout.splitlines():
            if line.startswith("CALL "):
                command, _, status = line[5:].rpartition(" ")
                self.calls.append((written.get(command, command), status))
            elif line.startswith("LOG "):
                status, category, message = line[4:].split(" ", 2)
                self.logs.append((int(status), category, message))
            elif line.startswith("VALUE "):
                _, vr, value = line.split(" ")
                self.values.append((int(vr), float(value)))
        self.ended = done.stdout.rstrip().endswith("END")

    def status(self, command, which=0) -> int:
        """The status of the ``which``-th call of ``command``."""
        return int([status for name, status in self.calls if name == command][which])

    def said(self, words) -> list:
        """The logged messages with ``words`` in them."""
        return [message for _, _, message in self.logs if words in message]


def run_trust(host: Path, fmu: Native, commands, logging: bool = False, timeout: float = 120) -> Run:
    """Run the trust host on ``fmu``; commands may name variables (``setr:m:-1``, ``getr:x``, ``sets:stepper:NULL``,
    ``seti:noise_seed:7``, ``setb:scene_load:0``, ``nulla:stepper``). The process must end by itself: a crash or a sanitizer's report is a
    failure the caller asserts (``run.code == 0 and run.ended``)."""
    argv = [str(host), str(fmu.library), fmu.guid, "1" if logging else "0"]
    written = {}  # the command as the host prints it -> as the caller wrote it
    for command in commands:
        parts = command.split(":")
        named = parts[0] in ("setr", "getr", "geta", "sets", "seti", "geti", "setb", "nulla", "deriv", "oderiv")
        if named and len(parts) > 1 and parts[1] in fmu.vr:
            parts[1] = str(fmu.vr[parts[1]])
        argv.append(":".join(parts))
        written[argv[-1]] = command
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), **SANITIZER_ENV}  # no Python in the host
    return Run(subprocess.run(argv, capture_output=True, text=True, timeout=timeout, env=env), written)
