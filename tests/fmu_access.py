"""Drive an FMU through its FMI 2.0 C API with FMPy's low-level classes: set inputs and
parameters by name, read outputs, states and derivatives. Used to get static solutions and
linearisations out of an FMU by FMI calls alone."""

import ctypes
import shutil

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (FMU2Model, FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

# FMPy's native logger proxy forwards every proxied FMU's messages to one global target, which
# each simulate_fmu(logger=...) points at a logger it frees when it returns: an FMU that then logs
# through FMPy's default callbacks calls freed memory, and re-pointing the target here would take
# the messages from a test's recorder. So an FMU given no callbacks gets a logger of its own that
# bypasses the proxy (it sees the format string, not the formatted text, and drops it: tests that
# read messages give a recorder), kept alive for the process.
_KEPT = []


def quiet_callbacks():
    """Callbacks whose logger is called directly and says nothing, kept alive."""
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, category, message: None)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(0)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(0)
    _KEPT.append(callbacks)
    return callbacks


class Fmu:
    def __init__(self, filename, kind="ModelExchange", callbacks=None):
        self.md = read_model_description(filename)
        self.dir = extract(filename)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.var = {v.name: v for v in self.md.modelVariables}
        cls = FMU2Model if kind == "ModelExchange" else FMU2Slave
        iface = self.md.modelExchange if kind == "ModelExchange" else self.md.coSimulation
        self.kind = kind
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.dir,
                       modelIdentifier=iface.modelIdentifier, instanceName="test")
        self.fmu.instantiate(callbacks=callbacks if callbacks is not None else quiet_callbacks())
        self.nx = len(self.md.derivatives)

    def set(self, **values):
        for name, value in values.items():
            self.set_named(name, value)

    def set_named(self, name, value):
        if self.var[name].type == "Boolean":
            self.fmu.setBoolean([self.vr[name]], [bool(value)])
        else:
            self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def initialize(self, start_time=0.0):
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        if self.kind == "ModelExchange":
            self.fmu.newDiscreteStates()
            self.fmu.enterContinuousTimeMode()

    def states(self):
        x = np.zeros(self.nx)
        self.fmu.getContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), self.nx)
        return x

    def set_states(self, x):
        x = np.ascontiguousarray(x, dtype=float)
        self.fmu.setContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), self.nx)

    def derivatives(self):
        dx = np.zeros(self.nx)
        self.fmu.getDerivatives(dx.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), self.nx)
        return dx

    def jacobian(self, x0, h=1e-6):
        """State matrix d(xdot)/dx by central differences of fmi2GetDerivatives."""
        a = np.zeros((self.nx, self.nx))
        for j in range(self.nx):
            step = h * max(1.0, abs(x0[j]))
            xp = x0.copy(); xp[j] += step
            xm = x0.copy(); xm[j] -= step
            self.set_states(xp); fp = self.derivatives()
            self.set_states(xm); fm = self.derivatives()
            a[:, j] = (fp - fm) / (2 * step)
        self.set_states(x0)
        return a

    def output_map(self, x0, names):
        """d(outputs)/d(states) by unit steps of each state from x0 (the flange outputs u, phi are
        linear in the modal states, so the difference is exact)."""
        base = self.get(*names)
        c = np.zeros((len(names), self.nx))
        for j in range(self.nx):
            x = x0.copy(); x[j] += 1.0
            self.set_states(x)
            c[:, j] = self.get(*names) - base
        self.set_states(x0)
        return c

    def close(self, terminate=True):
        try:
            if terminate:
                self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self.dir, ignore_errors=True)
