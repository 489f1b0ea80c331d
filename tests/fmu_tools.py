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


def driven_by_f(types: dict, start) -> dict:
    """The start values of an instance the test drives by F: ``scene_load`` false unless ``start`` sets it (it
    starts true when the scene names a load, issue 44.3), so that the force is F alone, as the library's element is
    driven by ``advance(size, force)``."""
    return {**({"scene_load": False} if "scene_load" in types else {}), **(start or {})}


class Slave:
    """One FMU2Slave instance with name-based access and a list of logged messages (the force F alone unless
    ``start_values`` sets scene_load: :func:`driven_by_f`)."""

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
        for key, value in driven_by_f(self.types, start_values).items():
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


OK, DISCARD, ERROR = 0, 2, 3  # FMI's statuses (2.0 and 3.0)


class NativeInstance:
    """One instance of a native FMU (FMI 2.0 or 3.0) through FMPy, its messages kept; ``start``: values set in
    initialization mode, scene_load false unless it sets it (:func:`driven_by_f`; ``refused``: the status of a
    refused exit of initialization mode, else None); ``start_time``: the experiment's; ``driven`` false: the
    scene's own load stays as the FMU starts it (``start`` may still set scene_load)."""

    def __init__(self, fmu, name="element", start=None, start_time=0.0, driven=True):
        from fmpy import extract, read_model_description

        md = read_model_description(fmu)
        self.fmi = 3 if md.fmiVersion.startswith("3") else 2
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.messages = []
        self.time = 0.0
        folder = extract(fmu)
        if self.fmi == 2:
            from fmpy import calloc, free
            from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                                   fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

            self._logger = fmi2CallbackLoggerTYPE(self._log2)  # kept alive with the instance
            callbacks = fmi2CallbackFunctions()
            callbacks.logger = self._logger
            callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            self._callbacks = callbacks
            self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            self.fmu.instantiate(callbacks=callbacks, loggingOn=False)
            self.fmu.setupExperiment(startTime=start_time)
        else:
            from fmpy.fmi3 import FMU3Slave

            self.fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=folder,
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            self.fmu.instantiate(loggingOn=False, logMessage=self._log3)
        self.time = start_time
        if self.fmi == 2:
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(startTime=start_time)
        for key, value in (driven_by_f(self.types, start) if driven else start or {}).items():
            self.set(key, value)
        from fmpy.fmi1 import FMICallException

        try:
            self.fmu.exitInitializationMode()
            self.refused = None
        except FMICallException as exc:  # (kept: the refusal's words are in the messages)
            self.refused = exc.status

    def _log2(self, env, instance, status, category, message):
        self.messages.append((status, message.decode("utf-8", "replace")))

    def _log3(self, env, status, category, message):
        self.messages.append((status, message.decode("utf-8", "replace")))

    def set(self, name, value):
        kind, vr = self.types[name], [self.vr[name]]
        if kind == "String":
            self.fmu.setString(vr, [value])
        elif kind == "Boolean":
            self.fmu.setBoolean(vr, [value])
        elif kind in ("Integer", "Int32"):
            (self.fmu.setInteger if self.fmi == 2 else self.fmu.setInt32)(vr, [value])
        else:
            (self.fmu.setReal if self.fmi == 2 else self.fmu.setFloat64)(vr, [value])

    def get(self, *names):
        return list((self.fmu.getReal if self.fmi == 2 else self.fmu.getFloat64)([self.vr[n] for n in names]))

    def step(self, size, force):
        """One doStep from the instance's time under ``force``; its status (FMPy raises beyond a warning)."""
        self.set("F", force)
        return self.do_step(size)

    def move(self, size, x, v):
        """A connector's doStep from the instance's time with the motion (x, v) set; its status."""
        self.set("x", x)
        self.set("v", v)
        return self.do_step(size)

    def do_step(self, size):
        from fmpy.fmi1 import FMICallException

        try:
            self.fmu.doStep(self.time, size)
        except FMICallException as exc:
            return exc.status
        self.time += size
        return OK

    def get_state(self):
        return self.fmu.getFMUstate() if self.fmi == 2 else self.fmu.getFMUState()

    def set_state(self, state):
        (self.fmu.setFMUstate if self.fmi == 2 else self.fmu.setFMUState)(state)

    def serialize(self) -> bytes:
        if self.fmi == 2:
            return bytes(self.fmu.serializeFMUstate(self.fmu.getFMUstate()))
        return bytes(self.fmu.serializeFMUState(self.fmu.getFMUState()))

    def deserialize(self, blob):
        """The FMU state ``blob`` holds (FMPy raises on a refusal)."""
        return self.fmu.deSerializeFMUstate(blob) if self.fmi == 2 else self.fmu.deserializeFMUState(blob)

    def restore(self, blob):
        self.set_state(self.deserialize(blob))

    def said(self, words):
        return [message for _, message in self.messages if words in message]

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
