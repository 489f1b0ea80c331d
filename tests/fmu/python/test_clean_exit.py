"""Processes that ran the FMU exit cleanly (issue: the SIGABRT "corrupted double-linked list" at interpreter exit).

Root cause (found with valgrind, fixed in prandtl_fmu/fmu/python/loader): PythonFMU 0.7.0's loader keeps its
interpreter state in a global std::shared_ptr whose static destructor runs in exit()'s handlers, and then
assigns to that destroyed shared_ptr from the library's destructor function in _dl_fini: a reference count
decremented inside a freed 128-byte block, and a second destruction when it reaches zero. Numba's and LLVM's
teardown reuse such blocks, hence the abort after FMPy runs of a numba slave, rare and load dependent.
"""
import os
import re
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

pytest.importorskip("fmpy")

PLAIN_SLAVE = textwrap.dedent('''\
    from pythonfmu import Fmi2Causality, Fmi2Slave, Real


    class ExitProbe(Fmi2Slave):
        """A plain slave: y integrates u."""

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.u = 1.0
            self.y = 0.0
            self.register_variable(Real("u", causality=Fmi2Causality.input))
            self.register_variable(Real("y", causality=Fmi2Causality.output))

        def do_step(self, current_time, step_size):
            self.y += self.u * step_size
            return True
''')

RUN = textwrap.dedent('''\
    import sys
    if sys.argv[2] == "numba-first":  # the libraries loaded before the FMU's, as in a test session
        import numba
        import prandtl_fmu
    from fmpy import simulate_fmu
    result = simulate_fmu(sys.argv[1], stop_time=2.0, output_interval=0.5, start_values={"F": 0.3, "scene_load": False})
    print(repr(float(result["x"][-1])), flush=True)
''')


def _plain_fmus(folder):
    """The plain slave's FMU with PythonFMU's stock loader and with ours."""
    from pythonfmu import FmuBuilder

    from prandtl_fmu.fmu.python.loader import install

    source = folder / "exit_probe.py"
    source.write_text(PLAIN_SLAVE)
    fmus = {}
    for name in ("stock", "prandtl"):
        (folder / name).mkdir()
        try:
            FmuBuilder.build_FMU(source, dest=folder / name / "ExitProbe.fmu")
        finally:
            sys.modules.pop(source.stem, None)
            if str(folder) in sys.path:
                sys.path.remove(str(folder))
        fmus[name] = folder / name / "ExitProbe.fmu"
    install(fmus["prandtl"])
    return fmus


def _loader_errors(log):
    """The memcheck errors with a frame in the FMU's own library (binaries/linux64/*.so)."""
    blocks = re.split(r"==\d+== \n", log)
    return [block for block in blocks
            if re.search(r"==\d+== (Invalid|Mismatched|Conditional|Use of uninit)", block)
            and "binaries/linux64/" in block.split("Address")[0]]


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is not installed")
def test_no_memory_error_in_the_loader_at_exit_under_valgrind(tmp_path):
    """The stock loader's use-after-free at exit, shown by memcheck, is absent from ours (a plain slave: the
    loader's teardown is the same for every slave, and memcheck runs it in ~1 min instead of numba's 30)."""
    fmus = _plain_fmus(tmp_path)
    script = tmp_path / "run.py"
    script.write_text("import sys\nfrom fmpy import simulate_fmu\n"
                      "result = simulate_fmu(sys.argv[1], stop_time=1.0, output_interval=0.25)\n"
                      "print(repr(float(result['y'][-1])), flush=True)\n")
    env = dict(os.environ, PYTHONMALLOC="malloc")  # every Python allocation seen by memcheck
    # sys.executable as it is, never its realpath: in a virtual environment the realpath is the base interpreter,
    # which does not see the environment's packages (issue 23, item 16: "No module named 'fmpy'")
    runs = {name: subprocess.Popen(["valgrind", f"--log-file={tmp_path / name}.log", "--num-callers=12",
                                    sys.executable, str(script), str(fmu)],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
            for name, fmu in fmus.items()}
    for name, run in runs.items():
        out, err = run.communicate(timeout=1200)
        assert run.returncode == 0 and float(out.split()[-1]) == 1.0, err[-2000:]
    stock = _loader_errors((tmp_path / "stock.log").read_text())
    ours = _loader_errors((tmp_path / "prandtl.log").read_text())
    assert any("finalizePythonInterpreter" in block and "free'd" in block for block in stock), \
        "memcheck no longer shows the stock loader's use-after-free: is valgrind working?"
    assert ours == [], "\n".join(ours)


@pytest.mark.slow
def test_scripted_fmpy_runs_exit_with_status_0_beside_busy_processes(tmp_path):
    """20 fresh processes run simulate_fmu on the FMU and exit normally (no os._exit), 5 at a time beside two
    CPU-bound processes; half import numba and the library before the FMU is loaded. Every exit status is 0
    and every result is the library's."""
    from prandtl_fmu import Element, load_scene
    from prandtl_fmu.fmu.build import build_fmu

    fmu = build_fmu("paper-section-8", tmp_path / "paper.fmu")
    script = tmp_path / "run.py"
    script.write_text(RUN)
    element = Element(load_scene("paper-section-8"))
    for _ in range(4):
        element.advance(0.5, 0.3)
    warm = subprocess.run([sys.executable, str(script), str(fmu), "plain"], capture_output=True, text=True,
                          timeout=900)  # fills the kernel cache once
    assert warm.returncode == 0, warm.stderr[-2000:]
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    outcomes = []
    try:
        for _ in range(4):
            runs = [subprocess.Popen([sys.executable, str(script), str(fmu), kind], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
                    for kind in ("numba-first", "plain", "numba-first", "plain", "numba-first")]
            for run in runs:
                out, err = run.communicate(timeout=600)
                outcomes.append((run.returncode, out, err))
    finally:
        for process in busy:
            process.kill()
            process.wait()
    assert [status for status, _, _ in outcomes] == [0] * 20, [err[-500:] for s, _, err in outcomes if s]
    assert np.allclose([float(out) for _, out, _ in outcomes], element.x, rtol=0, atol=1e-12)
