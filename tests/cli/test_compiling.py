"""Saying so while the kernels compile (compiling.py): a status line on a terminal's stderr, nothing elsewhere."""
import io

from numba import njit

from prandtl_fmu.compiling import compiling_status


class Terminal(io.StringIO):
    def isatty(self):
        return True


def _fresh_kernel():
    @njit(cache=False)
    def triple(x):
        return 3 * x
    return triple


def test_a_terminal_is_told_what_compiled_and_where_the_cache_is():
    from prandtl_fmu._jit import CACHE, cache_root

    stream = Terminal()
    with compiling_status(stream):
        assert _fresh_kernel()(2) == 6
    text = stream.getvalue()
    assert "compiled 1 kernels in" in text and text.endswith("\n")
    assert (str(cache_root()) if CACHE else "memory only") in text


def test_nothing_is_written_when_nothing_compiles_or_where_it_is_no_terminal():
    kernel = _fresh_kernel()
    kernel(1)  # compiled before: the body only calls it
    stream = Terminal()
    with compiling_status(stream):
        assert kernel(2) == 6
    assert stream.getvalue() == ""
    pipe = io.StringIO()  # not a terminal: a log, a pipe, a captured stderr
    with compiling_status(pipe):
        assert _fresh_kernel()(2) == 6
    assert pipe.getvalue() == ""


def test_a_long_command_says_its_stages_on_the_line_then_leaves_it_empty():
    import time

    from prandtl_fmu.compiling import REFRESH, stage

    stream = Terminal()
    with compiling_status(stream):
        stage("native build: linking x86_64-linux")
        time.sleep(4 * REFRESH)
    text = stream.getvalue()
    assert "native build: linking x86_64-linux: 0 s" in text
    assert "compiled" not in text and text.endswith("\r")  # nothing compiled: no closing line
    pipe = io.StringIO()
    with compiling_status(pipe):
        stage("native build: linking x86_64-linux")
        time.sleep(2 * REFRESH)
    assert pipe.getvalue() == ""
    stage("outside any command")  # nothing to say it on: nothing happens
