"""Co-Simulation of several instances of the transient tyre FMU through fmpy, with little overhead.

fmpy loads and instantiates the FMU (``fmpy.fmi2.FMU2Slave``: instantiate, set start
values, initialise); every communication step then calls the FMI functions of the
library fmpy loaded -- ``fmi2SetReal``, ``fmi2DoStep``, ``fmi2GetReal`` -- directly
through ctypes with preallocated buffers (``fast=True``) or through fmpy's wrapper
methods (``fast=False``; those add argument conversion and status checks per call).
Used by the vehicle example and ``benchmarks/bench_transient.py``.
"""

from __future__ import annotations

import ctypes
import os
import shutil
from collections.abc import Mapping, Sequence

import numpy as np

from mftire.errors import MftireError


def make_callbacks(messages: list | None = None):
    """FMI 2.0 callbacks whose logger appends ``(status, category, message)`` to ``messages``.

    The logger is a plain ctypes callback, not fmpy's logger proxy: the proxy keeps *one*
    process-wide pointer to the last Python logger registered, which dangles once that
    logger is garbage collected.  The transient FMU passes its messages pre-formatted, so
    no proxy is needed.  Keep the returned object alive as long as the instances.
    """
    from fmpy.fmi2 import (
        calloc,
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
        free,
    )

    store = messages if messages is not None else []

    def log(env, instance, status, category, message):
        store.append((int(status), (category or b"").decode(), (message or b"").decode().replace("%%", "%")))

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(log)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    cb._mftire_keep = (log, store)
    return cb


class TransientFMUs:
    """``n`` Co-Simulation instances of one transient tyre FMU.

    Parameters
    ----------
    fmu : path
        The ``.fmu`` (from ``mftire export-fmu --transient``).
    names : sequence of str
        Instance names (one instance each).
    inputs, outputs : sequence of str
        Variables set and read at every step, in the column order of :meth:`step`.
    start_values : mapping, optional
        Parameters (e.g. ``TR_CS_STEP``) or inputs set before initialisation, for all instances.
    fast : bool
        Call the FMI functions directly through ctypes (default) or through fmpy's methods.
    """

    def __init__(
        self,
        fmu: str | os.PathLike,
        names: Sequence[str] = ("FL", "FR", "RL", "RR"),
        inputs: Sequence[str] = ("Fz", "Vx", "Vy", "omega"),
        outputs: Sequence[str] = ("Fx", "Fy", "Mz", "My"),
        start_values: Mapping[str, float] | None = None,
        fast: bool = True,
    ) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.unzipdir = extract(str(fmu))
        md = read_model_description(self.unzipdir)
        if md.coSimulation is None or not any(v.name == "der(u)" for v in md.modelVariables):
            raise MftireError(f"{fmu}: not a transient tyre FMU (export it with --transient)")
        vr = {v.name: v.valueReference for v in md.modelVariables}
        missing = [n for n in (*inputs, *outputs, *(start_values or {})) if n not in vr]
        if missing:
            raise MftireError(f"{fmu}: no variable(s) {', '.join(missing)}")
        self.vr = vr
        self.fast = fast
        self.messages: list[tuple[int, str, str]] = []  #: (status, category, message) logged by the FMU
        self._callbacks = make_callbacks(self.messages)
        self.slaves = []
        for name in names:
            s = FMU2Slave(guid=md.guid, unzipDirectory=self.unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)  # fmt: skip
            s.instantiate(callbacks=self._callbacks)
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            if start_values:
                s.setReal([vr[k] for k in start_values], [float(v) for v in start_values.values()])
            s.exitInitializationMode()
            self.slaves.append(s)
        self.n, self.k, self.m = len(names), len(inputs), len(outputs)
        self.in_vr = [vr[k] for k in inputs]
        self.out_vr = [vr[k] for k in outputs]
        self.u = np.zeros((self.n, self.k))
        self.y = np.zeros((self.n, self.m))
        dll = self.slaves[0].dll
        D, U = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint)
        self._set, self._do, self._get = dll.fmi2SetReal, dll.fmi2DoStep, dll.fmi2GetReal
        for f in (self._set, self._get):
            f.argtypes, f.restype = [ctypes.c_void_p, U, ctypes.c_size_t, D], ctypes.c_int
        self._do.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
        self._do.restype = ctypes.c_int
        self._vin = (ctypes.c_uint * self.k)(*self.in_vr)
        self._vout = (ctypes.c_uint * self.m)(*self.out_vr)
        self._pin = [self.u[i].ctypes.data_as(D) for i in range(self.n)]
        self._pout = [self.y[i].ctypes.data_as(D) for i in range(self.n)]
        self._comp = [s.component for s in self.slaves]

    def step(self, t: float, h: float, u: np.ndarray | None = None) -> np.ndarray:
        """Set the inputs ``u`` (n x k; default: the buffer :attr:`u`), advance by ``h``, return outputs (n x m).

        The returned array is the buffer :attr:`y` (overwritten by the next step).
        """
        if u is not None:
            self.u[...] = u
        if self.fast:
            st, do, gt, vin, vout, k, m = self._set, self._do, self._get, self._vin, self._vout, self.k, self.m
            for c, pin, pout in zip(self._comp, self._pin, self._pout, strict=True):
                if st(c, vin, k, pin) or do(c, t, h, 1) or gt(c, vout, m, pout):
                    raise MftireError(f"transient tyre FMU: a call failed at t = {t:g}")
        else:
            for i, s in enumerate(self.slaves):
                s.setReal(self.in_vr, list(self.u[i]))
                s.doStep(t, h)
                self.y[i] = s.getReal(self.out_vr)
        return self.y

    def get(self, names: Sequence[str]) -> np.ndarray:
        """Read variables (n x len(names)) through fmpy."""
        return np.array([s.getReal([self.vr[k] for k in names]) for s in self.slaves])

    def close(self) -> None:
        for s in self.slaves:
            s.terminate()
            s.freeInstance()
        self.slaves = []
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self) -> TransientFMUs:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


__all__ = ["TransientFMUs", "make_callbacks"]
