"""A small fmpy-based host for the tyre FMU: one instance, point by point.

Used by the tests, the vehicle example and the benchmark.  It drives the FMU
through fmpy's low-level classes (``FMU2Model`` / ``FMU2Slave`` / ``FMU3Model`` /
``FMU3Slave``) so Model Exchange and Co-Simulation are exercised exactly as an
importing tool would: instantiate, set start values, initialise, then set inputs
and read outputs (ME in continuous-time mode; CS through ``doStep``).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

#: Input names in the order of :meth:`FMUTyre.evaluate`'s arguments.
INPUT_NAMES = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega", "muRoad")


def make_callbacks(messages: list | None = None, logger: Callable[[int, str, str], None] | None = None):
    """FMI 2.0 callbacks whose logger calls ``logger(status, category, message)`` -- by default it
    appends ``(status, category, message)`` to ``messages``.

    The logger is a plain ctypes callback owned by the returned object, not fmpy's logger
    proxy (``fmpy.logging.addLoggerProxy``): the proxy keeps *one* process-wide pointer to
    the last Python logger registered, so with several hosts every message goes to the
    newest one, and the pointer dangles once that host is garbage collected.  mftire's FMUs
    pass their messages pre-formatted (every '%' doubled, no variadic arguments), so no
    proxy is needed.  Keep the returned object alive as long as the instances.
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
    sink = logger or (lambda status, category, message: store.append((status, category, message)))

    def log(env, instance, status, category, message):
        sink(int(status), (category or b"").decode(), (message or b"").decode().replace("%%", "%"))

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(log)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    cb._mftire_keep = (log, sink, store)
    return cb


class FMUTyre:
    """One instance of a tyre FMU.

    Parameters
    ----------
    fmu : path
        The ``.fmu`` file or a directory where it was extracted (shared between instances).
    interface : "ME" or "CS"
        Model Exchange or Co-Simulation.
    start_values : mapping, optional
        ``{name: value}`` for parameters (and ``useMode``) set before initialisation.
    logger : callable, optional
        ``logger(status: int, category: str, message: str)`` receives the FMU's log
        messages (warnings have status 1).  Default: collect them in :attr:`messages`.
    instance_name : str
    step : float
        Communication step for Co-Simulation.
    """

    def __init__(
        self,
        fmu: str | os.PathLike,
        interface: str = "ME",
        start_values: Mapping[str, float] | None = None,
        logger: Callable[[int, str, str], None] | None = None,
        instance_name: str = "tyre",
        step: float = 1e-3,
    ) -> None:
        from fmpy import extract, read_model_description

        fmu = Path(fmu)
        self.unzipdir = str(fmu) if fmu.is_dir() else extract(str(fmu))
        self._owns_dir = not fmu.is_dir()
        md = read_model_description(self.unzipdir)
        self.model_description = md
        self.fmi_version = int(md.fmiVersion[0])
        self.interface = interface.upper()
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        self.messages: list[tuple[int, str, str]] = []
        self._logger = logger or (lambda status, cat, msg: self.messages.append((status, cat, msg)))
        self.time = 0.0
        self.step = step
        self._instantiate(md, instance_name)
        if start_values:
            self.set(start_values)
        self._initialise()

    # ------------------------------------------------------------------ setup
    def _instantiate(self, md, name: str) -> None:
        kw = dict(unzipDirectory=self.unzipdir, instanceName=name)
        if self.fmi_version == 2:
            from fmpy.fmi2 import FMU2Model, FMU2Slave

            ident = (md.modelExchange if self.interface == "ME" else md.coSimulation).modelIdentifier
            cls = FMU2Model if self.interface == "ME" else FMU2Slave
            self.fmu = cls(guid=md.guid, modelIdentifier=ident, **kw)
            # a logger of this instance's own, kept alive by it (not fmpy's process-wide proxy)
            self._callbacks = cb = make_callbacks(logger=self._logger)
            self.fmu.instantiate(callbacks=cb)
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        else:
            from fmpy.fmi3 import FMU3Model, FMU3Slave

            ident = (md.modelExchange if self.interface == "ME" else md.coSimulation).modelIdentifier
            cls = FMU3Model if self.interface == "ME" else FMU3Slave
            self.fmu = cls(guid=md.guid, modelIdentifier=ident, **kw)

            def log3(env, status, category, message):
                self._logger(int(status), category.decode(), message.decode())

            self._log3 = log3
            self.fmu.instantiate(logMessage=log3)
            self.fmu.enterInitializationMode(startTime=0.0)

    def _initialise(self) -> None:
        self.fmu.exitInitializationMode()
        if self.interface == "ME":
            if self.fmi_version == 2:
                self.fmu.newDiscreteStates()
            else:
                self.fmu.updateDiscreteStates()
            self.fmu.enterContinuousTimeMode()

    # ------------------------------------------------------------------ access
    def set(self, values: Mapping[str, float]) -> None:
        """Set Real (or the Integer ``useMode``) variables by name."""
        reals = [(self.vr[k], float(v)) for k, v in values.items() if self.types[k] in ("Real", "Float64")]
        ints = [(self.vr[k], int(v)) for k, v in values.items() if self.types[k] in ("Integer", "Int32")]
        if reals:
            vrs, vals = zip(*reals, strict=True)
            (self.fmu.setReal if self.fmi_version == 2 else self.fmu.setFloat64)(list(vrs), list(vals))
        if ints:
            vrs, vals = zip(*ints, strict=True)
            (self.fmu.setInteger if self.fmi_version == 2 else self.fmu.setInt32)(list(vrs), list(vals))

    def get(self, names: Sequence[str]) -> list[float]:
        """Read Real variables by name."""
        vrs = [self.vr[n] for n in names]
        return list((self.fmu.getReal if self.fmi_version == 2 else self.fmu.getFloat64)(vrs))

    def evaluate(
        self, Fz, kappa, alpha, gamma=0.0, phit=0.0, Vx=None, P=None, omega=0.0, muRoad=1.0, **variables
    ) -> dict:
        """Set the inputs, advance (CS: one ``doStep``) and return every output by name.

        ``variables`` are the external-variable inputs of the model extensions, by name
        (e.g. ``temperature=60.0``; ``**{"brake temp": 60.0}`` for other names; ``time=...``
        sets the input ``ext_time``).
        """
        values = dict(Fz=Fz, kappa=kappa, alpha=alpha, gamma=gamma, phit=phit, omega=omega, muRoad=muRoad)
        # an external variable named like an FMU variable (time) is the input ext_<name>
        values.update({f"ext_{k}" if f"ext_{k}" in self.vr else k: v for k, v in variables.items()})
        if Vx is not None:
            values["Vx"] = Vx
        if P is not None:
            values["P"] = P
        self.set(values)
        if self.interface == "CS":
            self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=self.step)
            self.time += self.step
        return dict(zip(self.outputs, self.get(self.outputs), strict=True))

    def close(self) -> None:
        """Terminate and free the instance (and remove the extracted files it owns)."""
        import shutil

        if getattr(self, "fmu", None) is None:
            return
        try:
            self.fmu.terminate()
            self.fmu.freeInstance()
        finally:
            self.fmu = None
            if self._owns_dir:
                shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self) -> FMUTyre:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
