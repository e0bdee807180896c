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
import struct
from collections.abc import Mapping, Sequence
from functools import partial

import numpy as np

from mftire.errors import MftireError
from mftire.fmu.host import make_callbacks


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

    The inputs and outputs of all instances live in two contiguous C buffers, seen from
    Python as the arrays :attr:`u` (n x k) and :attr:`y` (n x m).  With ``fast=True`` a
    step makes exactly three foreign calls per instance (``fmi2SetReal`` of all its inputs,
    ``fmi2DoStep``, ``fmi2GetReal`` of all its outputs) with every argument prepared once:
    the calls go to fresh function objects of the library fmpy loaded (fmpy's own
    wrappers are left as they are), without ctypes argument conversion.
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
        self.slaves = []
        try:
            md = read_model_description(self.unzipdir)
            if md.coSimulation is None or not any(v.name == "der(u)" for v in md.modelVariables):
                raise MftireError(f"{fmu}: not a transient tyre FMU (export it with --transient)")
            vr = {v.name: v.valueReference for v in md.modelVariables}
            missing = [n for n in (*inputs, *outputs, *(start_values or {})) if n not in vr]
            if missing:
                raise MftireError(f"{fmu}: no variable(s) {', '.join(missing)}")
            self.vr = vr
            self.fast = fast
            self.inputs, self.outputs = tuple(inputs), tuple(outputs)
            self.messages: list[tuple[int, str, str]] = []  #: (status, category, message) logged by the FMU
            self._callbacks = make_callbacks(self.messages)
            for name in names:
                s = FMU2Slave(guid=md.guid, unzipDirectory=self.unzipdir,
                              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)  # fmt: skip
                s.instantiate(callbacks=self._callbacks)
                self.slaves.append(s)
                s.setupExperiment(startTime=0.0)
                s.enterInitializationMode()
                if start_values:
                    s.setReal([vr[k] for k in start_values], [float(v) for v in start_values.values()])
                s.exitInitializationMode()
        except BaseException:
            self.close()
            raise
        self.n, self.k, self.m = len(names), len(inputs), len(outputs)
        self.in_vr = [vr[k] for k in inputs]
        self.out_vr = [vr[k] for k in outputs]
        n, k, m = self.n, self.k, self.m
        self._ubuf = (ctypes.c_double * (n * k))()
        self._ybuf = (ctypes.c_double * (n * m))()
        self.u = np.ctypeslib.as_array(self._ubuf).reshape(n, k)  #: inputs (n x k), the C buffer itself
        self.y = np.ctypeslib.as_array(self._ybuf).reshape(n, m)  #: outputs (n x m), the C buffer itself
        # flat formats of the two buffers for struct.pack_into / unpack_from (step_values)
        self._ufmt, self._yfmt = f"={n * k}d", f"={n * m}d"
        # fresh function objects on fmpy's library (dll[name] makes a new one each time); every argument is
        # prepared once as a ctypes parameter object (from_param of a value, byref of a buffer), which
        # ctypes passes on without converting anything per call; only DoStep's time is set per step
        dll = self.slaves[0].dll
        set_real, self._do_step, get_real = dll["fmi2SetReal"], dll["fmi2DoStep"], dll["fmi2GetReal"]
        for f in (set_real, self._do_step, get_real):
            f.restype = ctypes.c_int
        self._vr_arrays = (ctypes.c_uint * k)(*self.in_vr), (ctypes.c_uint * m)(*self.out_vr)
        vin, vout = (ctypes.byref(a) for a in self._vr_arrays)
        nk, nm = ctypes.c_size_t.from_param(k), ctypes.c_size_t.from_param(m)
        self._yes = ctypes.c_int.from_param(1)
        self._t = ctypes.c_double(0.0)
        size = ctypes.sizeof(ctypes.c_double)
        self._set_get = []  # per instance: (SetReal, the component, GetReal) with every argument bound
        for i, s in enumerate(self.slaves):
            comp = ctypes.c_void_p.from_param(s.component)
            self._set_get.append((
                partial(set_real, comp, vin, nk, ctypes.byref(self._ubuf, i * k * size)),
                comp,
                partial(get_real, comp, vout, nm, ctypes.byref(self._ybuf, i * m * size)),
            ))  # fmt: skip
        self._bind(1e-3)

    def _bind(self, h: float) -> None:
        """Bind the step size ``h`` into the DoStep calls: ``_calls`` per instance (SetReal, DoStep, GetReal)."""
        self._h, step = h, ctypes.c_double.from_param(h)
        do_step, t, yes = self._do_step, self._t, self._yes
        self._calls = [(st, partial(do_step, comp, t, step, yes), gt) for st, comp, gt in self._set_get]

    def _advance(self, t: float, h: float) -> None:
        """The 3 FMI calls per instance: set the inputs from the buffer, step, read the outputs into the buffer."""
        if h != self._h:
            self._bind(h)
        self._t.value = t
        for set_real, do_step, get_real in self._calls:
            if set_real() or do_step() or get_real():
                raise MftireError(f"transient tyre FMU: a call failed at t = {t:g}")

    def step(self, t: float, h: float, u: np.ndarray | None = None) -> np.ndarray:
        """Set the inputs ``u`` (n x k; default: the buffer :attr:`u`), advance by ``h``, return outputs (n x m).

        The returned array is the buffer :attr:`y` (overwritten by the next step).
        """
        if u is not None:
            self.u[...] = u
        if self.fast:
            self._advance(t, h)
        else:
            for i, s in enumerate(self.slaves):
                s.setReal(self.in_vr, self.u[i].tolist())
                s.doStep(t, h)
                self.y[i] = s.getReal(self.out_vr)
        return self.y

    def step_values(self, t: float, h: float, values: Sequence[float]) -> tuple[float, ...]:
        """:meth:`step` on plain floats: ``values`` are the n x k inputs row by row (instance by
        instance); returns the n x m outputs the same way, as a tuple.  The lean path for a
        vehicle model written in scalar Python."""
        struct.pack_into(self._ufmt, self._ubuf, 0, *values)
        if self.fast:
            self._advance(t, h)
        else:
            self.step(t, h)
        return struct.unpack_from(self._yfmt, self._ybuf)

    def get(self, names: Sequence[str]) -> np.ndarray:
        """Read variables (n x len(names)) through fmpy."""
        return np.array([s.getReal([self.vr[k] for k in names]) for s in self.slaves])

    def close(self) -> None:
        for s in self.slaves:
            s.terminate()
            s.freeInstance()
        self.slaves = []
        self._calls = self._set_get = []
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self) -> TransientFMUs:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


__all__ = ["TransientFMUs", "make_callbacks"]
