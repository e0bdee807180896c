"""Co-Simulation of several instances of the transient tyre FMU through fmpy, with little overhead.

Three ways to drive ``n`` instances of one transient tyre FMU, all through fmpy (``mode``):

``"container"``
    fmpy's container FMU (:mod:`fmpy.container_fmu`) holds the ``n`` instances; fmpy loads and
    instantiates the container, and every communication step makes three foreign calls in all:
    ``fmi2SetReal`` of the inputs of every instance, ``fmi2DoStep``, ``fmi2GetReal`` of their
    outputs.  The container (fmpy's compiled binary) forwards them to the instances through FMI 2.
``"direct"``
    fmpy loads and instantiates the ``n`` instances (``fmpy.fmi2.FMU2Slave``); every step calls
    ``fmi2SetReal``, ``fmi2DoStep``, ``fmi2GetReal`` of the library fmpy loaded once per instance
    (3 n foreign calls).
``"fmpy"``
    As ``"direct"``, through fmpy's wrapper methods (``setReal``, ``doStep``, ``getReal``: argument
    conversion and status checks per call).

In ``"container"`` and ``"direct"`` mode every call goes to a function object made once on the
library fmpy loaded, with every argument prepared once as a ctypes parameter object, and without
releasing the GIL (the FMU's work per call is about a microsecond).  Used by the vehicle example and
``benchmarks/bench_transient.py``.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import struct
import tempfile
import uuid
from collections.abc import Mapping, Sequence
from functools import partial
from pathlib import Path

import numpy as np

from mftire.errors import MftireError
from mftire.fmu.host import make_callbacks

#: The ways :class:`TransientFMUs` drives the instances.
MODES = ("container", "direct", "fmpy")


def container_available() -> bool:
    """Whether fmpy offers its container FMU (:mod:`fmpy.container_fmu`: fmpy >= 0.3.28, used with 0.3.32)
    with a binary for this platform."""
    try:
        import fmpy
        from fmpy.container_fmu import cli  # noqa: F401
    except ImportError:
        return False
    binaries = Path(fmpy.__file__).parent / "container_fmu" / "binaries"
    return any((binaries / d / f"container_fmu{ext}").is_file()
               for d in (fmpy.platform_tuple,) for ext in (".so", ".dll", ".dylib"))  # fmt: skip


def _function(dll, name: str):
    """A fresh function object for ``name`` of the library ``dll`` (fmpy's), returning a C int, that keeps the
    GIL during the call (``ctypes.PYFUNCTYPE``) and converts no argument (every argument is passed as a
    ctypes parameter object)."""
    return ctypes.PYFUNCTYPE(ctypes.c_int)((name, dll))


def build_container(
    fmu: str | os.PathLike,
    names: Sequence[str],
    inputs: Sequence[str],
    outputs: Sequence[str],
    start_values: Mapping[str, float] | None,
    step_size: float,
    directory: str | os.PathLike,
) -> Path:
    """An fmpy container FMU (FMI 2.0 Co-Simulation) of ``len(names)`` instances of ``fmu``.

    Its variables: ``time`` (value reference 0); the inputs ``<name>.<input>`` instance by instance
    (1 ..); the outputs ``<name>.<output>`` instance by instance; one parameter per ``start_values``
    item, set in every instance.  The container steps its instances with the fixed step ``step_size``.
    """
    from fmpy import read_model_description
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Configuration
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable, Unknown

    fmu = Path(fmu).resolve()
    md = read_model_description(str(fmu))
    var = {v.name: v for v in md.modelVariables}
    components = [Component(name=name, filename=fmu, modelDescription=md) for name in names]
    variables = [ModelVariable(name="time", type="Real", causality="independent", variability="continuous")]
    mappings = {}

    def add(v, targets):
        variables.append(v)
        mappings[v] = targets

    for c in components:
        for k in inputs:
            add(ModelVariable(name=f"{c.name}.{k}", type="Real", causality="input", variability="continuous",
                              start=var[k].start, description=var[k].description), [(c, var[k])])  # fmt: skip
    for c in components:
        for k in outputs:
            add(ModelVariable(name=f"{c.name}.{k}", type="Real", causality="output", variability="continuous",
                              initial="calculated", description=var[k].description), [(c, var[k])])  # fmt: skip
    for k, value in (start_values or {}).items():
        add(ModelVariable(name=k, type="Real", causality="parameter", variability="tunable", start=repr(float(value)),
                          description=var[k].description), [(c, var[k]) for c in components])  # fmt: skip
    container = ModelDescription(
        fmiVersion="2.0",
        modelName=f"{md.modelName} x {len(components)}",
        instantiationToken=f"{{{uuid.uuid5(uuid.NAMESPACE_OID, md.guid + ' x ' + ','.join(names))}}}",
        description=f"{len(components)} instances of {md.modelName} (fmpy container FMU, built by mftire)",
        defaultExperiment=DefaultExperiment(stepSize=repr(step_size)),
        coSimulation=CoSimulation(fixedInternalStepSize=step_size),
        modelVariables=variables,
        outputs=[Unknown(variable=v) for v in variables if v.causality == "output"],
        initialUnknowns=[Unknown(variable=v) for v in variables if v.causality == "output"],
    )
    config = Configuration(parallelDoStep=False, modelDescription=container, components=components,
                           connections=[], variableMappings=mappings)  # fmt: skip
    directory = Path(directory)
    work = directory / "container_build"
    work.mkdir(parents=True, exist_ok=True)
    out = directory / "tyres_container.fmu"
    create_container_fmu(config, work, out)
    shutil.rmtree(work, ignore_errors=True)
    return out


class TransientFMUs:
    """``n`` Co-Simulation instances of one transient tyre FMU, driven through fmpy.

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
    mode : "container", "direct" or "fmpy"
        How the instances are called (see the module docstring; :data:`MODES`).
    step_size : float
        ``"container"`` mode: the communication step (the container's fixed step); every
        :meth:`step` then advances by exactly this, contiguously from t = 0.

    The inputs and outputs of all instances live in two contiguous C buffers, seen from
    Python as the arrays :attr:`u` (n x k) and :attr:`y` (n x m).
    """

    def __init__(
        self,
        fmu: str | os.PathLike,
        names: Sequence[str] = ("FL", "FR", "RL", "RR"),
        inputs: Sequence[str] = ("Fz", "Vx", "Vy", "omega"),
        outputs: Sequence[str] = ("Fx", "Fy", "Mz", "My"),
        start_values: Mapping[str, float] | None = None,
        mode: str = "direct",
        step_size: float = 1e-3,
    ) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        if mode not in MODES:
            raise MftireError(f"TransientFMUs: mode must be one of {', '.join(MODES)}, not {mode!r}")
        if mode == "container" and not container_available():
            raise MftireError("TransientFMUs: this fmpy has no container FMU for this platform (use mode='direct')")
        self.mode = mode
        self.slaves = []
        self._tmp = None
        self.unzipdir = extract(str(fmu))
        try:
            md = read_model_description(self.unzipdir)
            if md.coSimulation is None or not any(v.name == "der(u)" for v in md.modelVariables):
                raise MftireError(f"{fmu}: not a transient tyre FMU (export it with --transient)")
            vr = {v.name: v.valueReference for v in md.modelVariables}
            missing = [n for n in (*inputs, *outputs, *(start_values or {})) if n not in vr]
            if missing:
                raise MftireError(f"{fmu}: no variable(s) {', '.join(missing)}")
            self.vr = vr
            self.names, self.inputs, self.outputs = tuple(names), tuple(inputs), tuple(outputs)
            self.messages: list[tuple[int, str, str]] = []  #: (status, category, message) logged by the FMU
            self._callbacks = make_callbacks(self.messages)
            if mode == "container":
                self._tmp = tempfile.mkdtemp(prefix="mftire-container-")
                path = build_container(fmu, names, inputs, outputs, start_values, step_size, self._tmp)
                cdir = extract(str(path), unzipdir=os.path.join(self._tmp, "unzipped"))
                cmd = read_model_description(cdir)
                s = FMU2Slave(guid=cmd.guid, unzipDirectory=cdir, modelIdentifier=cmd.coSimulation.modelIdentifier,
                              instanceName="tyres")  # fmt: skip
                s.instantiate(callbacks=self._callbacks)  # sets the start values (parameters) of the container
                self.slaves.append(s)
                s.setupExperiment(startTime=0.0)
                s.enterInitializationMode()
                s.exitInitializationMode()
            else:
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
        self._t = ctypes.c_double(0.0)
        if mode == "fmpy":
            return
        # every argument prepared once as a ctypes parameter object (from_param of a value, byref of a
        # buffer), which ctypes passes on without converting anything per call; DoStep's time is set per step
        dll = self.slaves[0].dll
        set_real, self._do_step, get_real = (_function(dll, f) for f in ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal"))
        self._yes = ctypes.c_int.from_param(1)
        if mode == "container":
            # container value references: time 0, the inputs 1 .. n k, the outputs n k + 1 .. n k + n m
            self._vr_arrays = (ctypes.c_uint * (n * k))(*range(1, n * k + 1)), \
                (ctypes.c_uint * (n * m))(*range(n * k + 1, n * k + n * m + 1))  # fmt: skip
            blocks = [(0, n * k, n * m)]
        else:
            self._vr_arrays = (ctypes.c_uint * k)(*self.in_vr), (ctypes.c_uint * m)(*self.out_vr)
            blocks = [(i, k, m) for i in range(n)]
        vin, vout = (ctypes.byref(a) for a in self._vr_arrays)
        size = ctypes.sizeof(ctypes.c_double)
        self._set_get = []  # per FMU instance called: (SetReal, the component, GetReal) with every argument bound
        for s, (i, nk, nm) in zip(self.slaves, blocks, strict=True):
            comp = ctypes.c_void_p.from_param(s.component)
            self._set_get.append((
                partial(set_real, comp, vin, ctypes.c_size_t.from_param(nk), ctypes.byref(self._ubuf, i * k * size)),
                comp,
                partial(get_real, comp, vout, ctypes.c_size_t.from_param(nm), ctypes.byref(self._ybuf, i * m * size)),
            ))  # fmt: skip
        self._bind(step_size)

    def _bind(self, h: float) -> None:
        """Bind the step size ``h`` into the DoStep calls: ``_calls`` per instance (SetReal, DoStep, GetReal),
        and make :meth:`step_values` for it."""
        self._h, step = h, ctypes.c_double.from_param(h)
        do_step, t, yes = self._do_step, self._t, self._yes
        self._calls = [(st, partial(do_step, comp, t, step, yes), gt) for st, comp, gt in self._set_get]
        self.step_values = self._step_values_for(h)

    def _failed(self, t: float) -> MftireError:
        return MftireError(f"transient tyre FMU: a call failed at t = {t:g}"
                           + "".join(f"\n  {msg}" for _, _, msg in self.messages[-3:]))  # fmt: skip

    def _step_values_for(self, h0: float):
        """:meth:`step_values` as a closure over everything it needs, for steps of ``h0``: the host's work per
        step is a few dozen bytecodes around the FMI calls."""
        pack = partial(struct.Struct(self._ufmt).pack_into, self._ubuf, 0)
        unpack = partial(struct.Struct(self._yfmt).unpack_from, self._ybuf)
        calls, tc, time, half = self._calls, self._t, 0.0, 0.5 * h0

        if self.mode == "container":
            set_real, do_step, get_real = calls[0]

            def step_values(t: float, h: float, values: Sequence[float]) -> tuple[float, ...]:
                nonlocal time
                # the container checks the communication point against its own time, a sum of fixed steps
                if h != h0 or not -half < t - time < half:
                    raise MftireError(f"TransientFMUs (container): fixed steps of {h0:g} s one after the other "
                                      f"from t = 0 (expected t = {time:g}; got t = {t:g}, h = {h:g})")  # fmt: skip
                pack(*values)
                tc.value = time
                if set_real() or do_step() or get_real():
                    raise self._failed(t)
                time += h
                return unpack()

        else:

            def step_values(t: float, h: float, values: Sequence[float]) -> tuple[float, ...]:
                if h != h0:
                    self._bind(h)
                    return self.step_values(t, h, values)
                pack(*values)
                tc.value = t
                for set_real, do_step, get_real in calls:
                    if set_real() or do_step() or get_real():
                        raise self._failed(t)
                return unpack()

        step_values.__doc__ = TransientFMUs.step_values.__doc__
        return step_values

    def step(self, t: float, h: float, u: np.ndarray | None = None) -> np.ndarray:
        """Set the inputs ``u`` (n x k; default: the buffer :attr:`u`), advance by ``h``, return outputs (n x m).

        The returned array is the buffer :attr:`y` (overwritten by the next step).
        """
        if u is not None:
            self.u[...] = u
        if self.mode != "fmpy":
            self.step_values(t, h, self._ubuf)
        else:
            for i, s in enumerate(self.slaves):
                s.setReal(self.in_vr, self.u[i].tolist())
                s.doStep(t, h)
                self.y[i] = s.getReal(self.out_vr)
        return self.y

    def step_values(self, t: float, h: float, values: Sequence[float]) -> tuple[float, ...]:
        """:meth:`step` on plain floats: ``values`` are the n x k inputs row by row (instance by
        instance); returns the n x m outputs the same way, as a tuple.  The lean path for a
        vehicle model written in scalar Python.

        In ``"container"`` mode the steps must follow each other from t = 0 with the fixed step
        ``step_size`` (the container checks the time; the FMU's outputs do not depend on it)."""
        struct.pack_into(self._ufmt, self._ubuf, 0, *values)
        self.step(t, h)
        return struct.unpack_from(self._yfmt, self._ybuf)

    def get(self, names: Sequence[str]) -> np.ndarray:
        """Read variables (n x len(names)) through fmpy (``"direct"`` and ``"fmpy"`` modes)."""
        if self.mode == "container":
            raise MftireError("TransientFMUs.get: not in container mode (list the variables in outputs)")
        return np.array([s.getReal([self.vr[k] for k in names]) for s in self.slaves])

    def close(self) -> None:
        for s in self.slaves:
            s.terminate()
            s.freeInstance()
        self.slaves = []
        self._calls = self._set_get = []
        shutil.rmtree(self.unzipdir, ignore_errors=True)
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def __enter__(self) -> TransientFMUs:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


__all__ = ["MODES", "TransientFMUs", "build_container", "container_available", "make_callbacks"]
