"""The small C host of ``tests/c_host/fmi2_host.c``: compiled once per test process, run on an extracted FMU.

A host that is not a Python process meets what FMPy forgives (a NULL log category aborts OMSimulator, a refusal
must reach a logger that was instantiated with logging off). A PythonFMU FMU in such a host needs the host's
libpython preloaded and the environment's packages on PYTHONPATH (the README's recipe): :func:`python_recipe`."""
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
FMI_HEADERS = HERE.parent / "prandtl_fmu" / "fmu" / "loader" / "src" / "fmi"
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
        if parts[0] in ("setr", "getr") and not parts[1].isdigit():
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
