"""Driving a built FMU by hand with FMPy, capturing what it logs."""
import ctypes

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)


# Set by the tests that load an FMU built with PythonFMU's stock loader into the test process (see
# conftest.pytest_unconfigure: that loader's use-after-free at exit).
STOCK_LOADER_LOADED = False


def stock_loader_loaded():
    global STOCK_LOADER_LOADED
    STOCK_LOADER_LOADED = True


class Slave:
    """One FMU2Slave instance with name-based access and a list of logged messages."""

    def __init__(self, fmu_path, unzipdir=None, name="element", start_values=None, start_time=0.0):
        self.md = read_model_description(fmu_path)
        self.unzipdir = unzipdir or extract(fmu_path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.messages = []

        def logger(env, instance, status, category, message):
            self.messages.append((status, message.decode("utf-8", "replace")))

        self._logger = fmi2CallbackLoggerTYPE(logger)  # keep the callbacks alive
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        for key, value in (start_values or {}).items():
            self.set(key, value)
        self.fmu.exitInitializationMode()
        self.time = start_time

    def set(self, name, value):
        if self.types[name] == "String":
            self.fmu.setString([self.vr[name]], [value])
        elif self.types[name] == "Integer":
            self.fmu.setInteger([self.vr[name]], [value])
        elif self.types[name] == "Boolean":
            self.fmu.setBoolean([self.vr[name]], [value])
        else:
            self.fmu.setReal([self.vr[name]], [value])

    def get(self, *names):
        values = self.fmu.getReal([self.vr[n] for n in names])
        return values if len(names) > 1 else values[0]

    def step(self, size, force=None):
        if force is not None:
            self.set("F", force)
        self.fmu.doStep(self.time, size)
        self.time += size

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def rss_bytes():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * ctypes.sizeof(ctypes.c_char) * 4096


def held_input(times, values):
    """FMPy input signal that takes value[k] exactly at times[k] (the start of step k)."""
    signal = np.zeros(len(times), dtype=[("time", float), ("F", float)])
    signal["time"], signal["F"] = times, values
    return signal
