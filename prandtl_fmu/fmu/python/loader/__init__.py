"""The FMU's native loader: PythonFMU 0.7.0's, patched, for Linux x86-64.

A PythonFMU FMU is a small C++ library (``binaries/<platform>/<modelIdentifier>.so``) that starts the
slave script in the host's Python and forwards every FMI call to it. PythonFMU 0.7.0's library has
defects that no slave script can fully work around; ``src/`` holds its sources (NTNU-IHB/PythonFMU
6e6f489, the 0.7.0 loader, MIT licence in ``src/LICENSE.PythonFMU``; first commit verbatim) with
these changes, each marked ``prandtl_fmu:`` in the code:

1. a Python exception in a slave call fails the FMI call with **fmi2Error**, not fmi2Fatal, and
   leaves the instance as it was (the stock loader released its references to the slave's class,
   instance and log queue, and again when the instance was freed: a double free);
2. the script is found without releasing a reference it never took (the module's dict), without
   leaking the class names it reads, without finalizing the host's interpreter on a syntax error,
   and with the script's own exception reported (e.g. "No module named numba");
3. no leaked references per logged message, per ``fmi2SetFMUstate``, per ``sys.path`` insert;
   ``fmi2GetFMUstate`` into a state returned earlier releases that state, ``fmi2FreeFMUstate`` sets
   it to NULL (FMI 2.0, 2.1.8);
4. the GIL is released on every path, an exception's included;
5. getters check the slave's answer (length, types) instead of reading past it;
6. ``fmi2Terminated`` reports the last step (the stock loader kept it true after the first Discard);
7. every FMI function given a NULL, unknown or freed instance returns fmi2Error (``fmi2FreeInstance``:
   nothing), and no C++ exception reaches the host; NULL argument pointers (with nvr > 0), a NULL
   string, a string that is not UTF-8 and a state pointer this library did not return (or has freed)
   are refused with fmi2Error and the reason logged (the stock loader dereferenced them);
8. FMI 2.0's co-simulation call sequence, for every function (the Reference-FMUs' masks): a call the
   instance's mode does not allow is refused with fmi2Error, 'not allowed <where>' logged; a refused
   call changes nothing, so the instance stays usable;
9. a non-finite start time or communication point, a negative or non-finite communication step (or
   one whose end is not finite) is refused with fmi2Error and the reason; ``fmi2LastSuccessfulTime``
   is the start time before any step (the stock loader: NaN).

The slave is told by the ``pythonfmu_loader`` keyword argument (``fmu/python/common.py``) and the
``__prandtl_loader__`` mark in its script's globals (``fmu/python/entry.py``) that it runs under this
loader; under the stock one (the Windows binary PythonFMU ships, or an FMU built with
``loader="pythonfmu"``) it keeps compensating that loader's reference counting, and refusals are
fmi2Fatal there. Even so, once in CI a process that had made 400 refused calls through the stock
loader died at exit with a heap corruption (glibc: "corrupted double-linked list"), after the
instance had stepped on correctly: that loader calls the host's logger while a Python exception is
pending, which no slave can prevent. tests/fmu/python/test_loader.py records it as an expected failure.

The library is prebuilt (``linux64/``, committed, with the digest of the sources it was built from
in ``linux64/SOURCE_SHA256``; a test checks that they match) because a user's machine need not have
a compiler. Rebuild after editing ``src/``::

    python -m prandtl_fmu.fmu.python.loader

It needs g++ (C++17) and Python's headers. Like PythonFMU's, it is built for Python's stable ABI,
takes the Python symbols from the host process, and links libstdc++ dynamically: it needs glibc
2.32 and GLIBCXX 3.4.30, the same as the stock library.
"""
from __future__ import annotations

import hashlib
import os
import subprocess
import sysconfig
import tempfile
from pathlib import Path
from typing import Optional

HERE = Path(__file__).resolve().parent
SOURCES = HERE / "src"
LINUX64 = HERE / "linux64" / "prandtl_fmu_loader.so"
STAMP = HERE / "linux64" / "SOURCE_SHA256"
LICENSE = SOURCES / "LICENSE.PythonFMU"
# the loaders an FMU can be built with: ours (Linux x86-64; PythonFMU's own on the other platforms) or
# PythonFMU's everywhere
LOADERS = ("prandtl", "pythonfmu")


def source_digest() -> str:
    """SHA-256 of the loader's sources (paths and contents, in a fixed order)."""
    digest = hashlib.sha256()
    for path in sorted(p for p in SOURCES.rglob("*") if p.is_file()):
        digest.update(path.relative_to(SOURCES).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def prebuilt(platform: str) -> Optional[Path]:
    """The patched library for an FMU platform folder name (``linux64``), or None where PythonFMU's own
    is used (win64, darwin64)."""
    return LINUX64 if platform == "linux64" else None


def replacement(entry: str) -> Optional[bytes]:
    """The bytes that replace an FMU archive entry (``binaries/linux64/<modelIdentifier>.so``) with the
    patched library, or None to keep the entry."""
    parts = entry.split("/")
    if len(parts) == 3 and parts[0] == "binaries" and parts[2] and prebuilt(parts[1]) is not None:
        return prebuilt(parts[1]).read_bytes()
    return None


def install(fmu: os.PathLike) -> None:
    """Put the patched library into an FMU built by PythonFMU's own builder (the examples' plain slaves), in
    place of PythonFMU's (rewritten in a new file, then renamed over it)."""
    import zipfile

    if stale():
        raise RuntimeError(stale())
    fmu = Path(fmu)
    with zipfile.ZipFile(fmu) as archive:
        entries = [(info, archive.read(info)) for info in archive.infolist()]
    import io

    from ....outputs import write_atomically

    rewritten = io.BytesIO()
    with zipfile.ZipFile(rewritten, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for info, data in entries:
            archive.writestr(info, replacement(info.filename) or data)
        archive.write(LICENSE, "documentation/licenses/PythonFMU.txt")
    write_atomically(fmu, rewritten.getvalue())


def stale() -> Optional[str]:
    """Why the prebuilt library does not match the sources (None if it does)."""
    if not LINUX64.is_file() or not STAMP.is_file():
        return f"{LINUX64} is missing: run python -m prandtl_fmu.fmu.python.loader"
    if STAMP.read_text().strip() != source_digest():
        return f"{LINUX64} was built from other sources than {SOURCES}: run python -m prandtl_fmu.fmu.python.loader"
    return None


def compile_loader(out: Path, compiler: str = "g++") -> str:
    """Compile ``src/`` into the shared library ``out``; returns the compiler's warnings (raises
    CalledProcessError with its output on failure)."""
    include = sysconfig.get_paths()["include"]
    command = [compiler, "-std=c++17", "-O2", "-fPIC", "-shared", "-Wall",
               "-DPy_LIMITED_API=0x03080000",  # the stable ABI: one library for every Python 3.8+
               f"-I{SOURCES}", f"-I{include}",
               str(SOURCES / "pythonfmu" / "PySlaveInstance.cpp"), str(SOURCES / "pythonfmu" / "fmi2.cpp"),
               "-s", "-o", str(out)]
    return subprocess.run(command, check=True, capture_output=True, text=True).stderr


def build() -> Path:
    """Rebuild ``linux64/prandtl_fmu_loader.so`` and its stamp from ``src/`` (the library is renamed into
    place: never half-written)."""
    LINUX64.parent.mkdir(exist_ok=True)
    handle, partial = tempfile.mkstemp(prefix=".loader-", suffix=".so.part", dir=LINUX64.parent)
    os.close(handle)
    try:
        compile_loader(Path(partial))
        os.chmod(partial, 0o755)
        os.replace(partial, LINUX64)
    finally:
        if os.path.exists(partial):
            os.unlink(partial)
    STAMP.write_text(source_digest() + "\n")
    return LINUX64
