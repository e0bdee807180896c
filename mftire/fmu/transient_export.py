"""The transient tyre FMU (``mftire export-fmu TIR --transient``): FMI 2.0 or 3.0, ME + CS.

Wheel kinematics in (:data:`mftire.transient.INPUTS`), two continuous states ``u``,
``v`` with their derivatives ``der(u)``, ``der(v)``, the steady-state channels at the
transient slips out.  One variable table (:func:`transient_variable_table`, built
from :mod:`mftire.transient` and the steady-state table of
:mod:`mftire.fmu.variables`) generates the XML, the GUID and the C headers
(``mf_params.h`` with the transient constants ``TR_*`` as tunable parameters, and
``mt_model_gen.h``).  The C model is ``mftire/mf/c/mf_transient.c`` (the equations of
``mftire/transient.py``) on top of the steady-state evaluator ``mf_eval.c``; ``mftire/fmu/c/mt_model.c``
puts it behind the one model interface (``fmu_model.h``), and the same thin FMI 2 and FMI 3 wrappers as the
steady-state FMU's (``fmi2_wrapper.c``, ``fmi3_wrapper.c``) make it an FMU.

Thermal block (a ``.tir`` with ``[MFTIRE_THERMAL]``; :class:`mftire.transient.TransientTyre` ``thermal=True``):
three more states ``T_s``, ``T_b``, ``T_g`` (node temperatures, °C), inputs ``T_ambient``, ``T_road``,
outputs ``T_surface``, ``T_bulk``, ``T_gas``, ``P_hot``, the section's keys as parameters (the initial
temperatures ``TH_T_INIT_*`` among them), and the temperature laws of ``[MFTIRE_EXTENSIONS]`` compiled in
(their C generated from :mod:`mftire.mf.extensions` as the steady FMU's), each reading its node.  The
generated ``mt_config_gen.h`` (:func:`mftire.mf.cheaders.transient_config_header`) switches it on
(``MT_THERMAL``); a ``.tir`` without the section gives the transient FMU without it.
"""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from mftire.errors import MftireError
from mftire.fmu import variables as vt
from mftire.fmu.build import (
    CFLAGS,
    LIBS,
    MODEL_SOURCES,
    UNITY,
    FMUExportError,
    _load,
    export_identifier,
    find_compiler,
    package_fmu,
    read_source,
    source_files,
)
from mftire.fmu.documentation import documentation_files
from mftire.mf import spec
from mftire.mf.extensions import ExtensionSet
from mftire.mf.thermal_section import TEXTS as TH_TEXTS
from mftire.mf.thermal_section import ThermalParameters
from mftire.transient import (
    CONSTANTS,
    INPUTS,
    STATES,
    THERMAL_INPUTS,
    THERMAL_OUTPUTS,
    THERMAL_STATES,
    TRANSIENT_OUTPUTS,
    input_defaults,
)
from mftire.transient.slip_dynamics import thermal_input_defaults


@dataclass(frozen=True)
class ThermalExport:
    """The thermal block of a transient FMU: the section's parameters, the extension terms (each law of an
    ``EXTn_NODE`` reading its node variable) and the node index of each external variable, in data-slot order
    (:func:`mftire.transient.slip_dynamics.thermal_block`)."""

    params: ThermalParameters
    extensions: ExtensionSet | None
    nodes: tuple[int, ...]


def output_names(thermal: bool = False) -> list[str]:
    """Output names of the transient FMU, in order: the forces and moments, the transient slips,
    then the steady-state channels of the steady-state FMU (:data:`mftire.fmu.variables.OUTPUTS`); the thermal
    block's outputs (:data:`mftire.transient.THERMAL_OUTPUTS`) last."""
    return (
        [n for n, *_ in vt.OUTPUTS[:2]]
        + ["Mz", "Mx", "My"]
        + [n for n, *_ in TRANSIENT_OUTPUTS]
        + [n for n, *_ in vt.OUTPUTS if n not in ("Fx", "Fy", "Mz", "Mx", "My")]
        + ([n for n, *_ in THERMAL_OUTPUTS] if thermal else [])
    )


#: Hand-written C sources of the transient model (the FMI wrapper and the interface are added per FMI version).
TRANSIENT_SOURCES = MODEL_SOURCES["transient"]

#: Unit names of :data:`mftire.transient.CONSTANTS` -> FMI units.
_CONST_UNIT = {"s": "s", "m": "m", "-": None}

#: C member of MTOutputs for each output name.
_STEADY_FIELD = {name: field for name, field, _, _ in vt.OUTPUTS}

#: The channel group of ``mf_evaluate_want`` (``MF_WANT_<group>``, :data:`mftire.mf.spec.GROUPS`) each output
#: needs: the FMU evaluates only the groups of the outputs read (lazy outputs, ``mt_model.c``).
OUTPUT_GROUPS: dict[str, str] = {o.fmu: o.group for o in spec.OUTPUTS if o.fmu and o.group}

#: Outputs every evaluation sets (no channel group): the transient slips, the load used and Re; the thermal
#: block's node temperatures and pressure.
UNGROUPED_OUTPUTS = ("kappa_t", "alpha_t", *(o.fmu for o in spec.OUTPUTS if o.fmu and not o.group),
                     *(n for n, *_ in THERMAL_OUTPUTS))  # fmt: skip


def output_group(name: str) -> str:
    """The C expression of the channel-group bits of output ``name`` (``0`` for :data:`UNGROUPED_OUTPUTS`)."""
    if name in OUTPUT_GROUPS:
        return f"MF_WANT_{OUTPUT_GROUPS[name]}"
    if name in UNGROUPED_OUTPUTS:
        return "0"
    raise FMUExportError(f"transient FMU output {name!r} has no channel group (add it to OUTPUT_GROUPS)")


def _output_rows(thermal: bool = False) -> list[tuple[str, str, str | None, str]]:
    steady = {name: (field, unit, desc) for name, field, unit, desc in vt.OUTPUTS}
    trans = {name: (name, unit, desc) for name, unit, desc in (*TRANSIENT_OUTPUTS, *THERMAL_OUTPUTS)}
    rows = []
    for name in output_names(thermal):
        if name in trans:
            field, unit, desc = trans[name]
        else:
            field, unit, desc = steady[name]
            field = "ss." + field
            if name in ("Fx", "Fy", "Mz", "My"):
                desc += " (transient; low-speed model below VXLOW)"
            else:
                desc += " (at the transient slips)"
        rows.append((name, field, unit, desc))
    return rows


def _thermal_flat(flat: dict[str, float], th: ThermalParameters) -> dict[str, float]:
    """``flat`` with every parameter of the thermal block (``TH_*``; the initial temperatures default to the
    ``T_ambient`` start value, ``TH_COLD_TEMPERATURE``)."""
    out = dict(flat)
    for name in TH_TEXTS:
        value = getattr(th, name)
        if value is None and name.startswith("t_init_"):
            value = th.cold_temperature
        if value is not None:
            out["TH_" + name.upper()] = float(value)
    return out


def transient_variable_table(flat: dict[str, float], use_mode: int = vt.DEFAULT_USE_MODE,
                             thermal: ThermalExport | None = None) -> list[vt.Variable]:  # fmt: skip
    """Every variable of the transient FMU (value references 0..n-1).

    ``time``; the inputs; the outputs; ``useMode``; the ``.tir`` parameters (as the
    steady-state FMU); the transient constants ``TR_*``; the states ``u``, ``v`` and
    their derivatives ``der(u)``, ``der(v)`` (kinds ``"state"`` and ``"der"``; the
    ``field`` of both is the state index).  ``thermal``: the thermal block's inputs, outputs, parameters
    (``TH_*``, the laws' ``EXTn_*``) and states ``T_s``, ``T_b``, ``T_g`` (no start value: they start at
    the parameters ``TH_T_INIT_*``).
    """
    V = vt.Variable
    out: list[vt.Variable] = [
        V("time", 0, "time", "Real", "independent", "continuous", None, "s", "Simulation time", "")
    ]
    defaults = input_defaults(flat)
    rows = list(INPUTS)
    if thermal is not None:
        defaults.update(thermal_input_defaults(flat, thermal.params))
        rows = [r if r[0] != "P" else ("P", "Pa", "Cold set inflation pressure at TH_COLD_TEMPERATURE (NaN or <= 0: "
                                      "INFLPRES); with TH_PRESSURE = 1 the MF uses the gas law's P_hot", r[3])
                for r in rows] + list(THERMAL_INPUTS)  # fmt: skip
        flat = _thermal_flat(flat, thermal.params)
    for name, unit, desc, _ in rows:
        value = defaults[name]
        out.append(V(name, len(out), "input", "Real", "input", "continuous", value, unit, desc, name))
    for name, field, unit, desc in _output_rows(thermal is not None):
        out.append(V(name, len(out), "output", "Real", "output", "continuous", None, unit, desc, field))
    try:
        steady = vt.variable_table(flat, use_mode, thermal.extensions if thermal is not None else None)
    except MftireError as exc:
        raise FMUExportError(f"the model extensions cannot be exported: {exc}") from None
    from mftire.mf.thermal_section import UNITS as TH_UNITS

    for v in steady:
        if v.kind in ("mode", "param"):
            unit, desc, variability = v.unit, v.description, v.variability
            name = v.name[3:].lower() if v.name.startswith("TH_") else None
            if thermal is not None and name in TH_TEXTS:
                unit, desc = TH_UNITS[name], f"[MFTIRE_THERMAL] {TH_TEXTS[name]}"
                variability = "fixed" if name.startswith("t_init_") else "tunable"
            out.append(V(v.name, len(out), v.kind, v.type, v.causality, variability, v.start, unit, desc,
                         v.field))  # fmt: skip
    for name, value, unit, desc in CONSTANTS:
        out.append(V(name, len(out), "param", "Real", "parameter", "tunable", float(value), _CONST_UNIT[unit],
                     f"[transient] {desc}", name))  # fmt: skip
    states = [(name, desc, 0.0, "m", "m/s") for name, desc in STATES]
    if thermal is not None:
        states += [(name, desc + ": starts at TH_T_INIT_" + ("SURFACE", "BULK", "GAS")[i], None, "degC", "K/s")
                   for i, (name, desc) in enumerate(THERMAL_STATES)]  # fmt: skip
    for i, (name, desc, start, unit, _) in enumerate(states):
        out.append(V(name, len(out), "state", "Real", "local", "continuous", start, unit, desc, str(i)))
    for i, (name, _desc, _, _, dunit) in enumerate(states):
        out.append(V(f"der({name})", len(out), "der", "Real", "local", "continuous", None, dunit,
                     f"Time derivative of {name}", str(i)))  # fmt: skip
    names = [v.name for v in out]
    assert len(set(names)) == len(names), "transient FMU variable names must be unique"
    return out


def transient_model_header(variables: list[vt.Variable], model_identifier: str, fmi_version: int = 2) -> str:
    """``mt_model_gen.h`` (:func:`mftire.fmu.variables.model_header` of the transient model): GUID, value-reference
    table with the outputs' channel groups, start values (the states' too), names; the thermal bounds."""
    params = {v.name: v for v in variables if v.kind == "param"}
    states = sorted((v for v in variables if v.kind == "state"), key=lambda v: v.vr)
    init = ("TH_T_INIT_SURFACE", "TH_T_INIT_BULK", "TH_T_INIT_GAS")
    # a state without a start value starts at its parameter TH_T_INIT_* (thermal block)
    state_start = ", ".join(vt._c_double(v.start if v.start is not None else params[init[int(v.field) - 2]].start)
                            for v in states)  # fmt: skip
    extra = [f"static const double MT_STATE_START[{len(states)}] = {{{state_start}}};", ""]
    if len(states) > 2:
        extra += _thermal_bounds()
    return vt.model_header(variables, model_identifier, fmi_version, prefix="MT", include="mf_transient.h",
                           structs={"input": "MTInputs", "output": "MTOutputs", "param": "MFParams"},
                           want=lambda v: output_group(v.name), extra=extra)  # fmt: skip


def _thermal_bounds() -> list[str]:
    """``MT_THERMAL_BOUNDS``: the bounds of the ``[MFTIRE_THERMAL]`` parameters
    (:func:`mftire.mf.thermal_section.bounds`, the one table) for ``check_parameter`` of ``mt_model.c``."""
    from mftire.mf.thermal_section import bounds

    kinds = {">": 0, ">=": 1, "in": 2}
    lines = ["/* The bounds of the [MFTIRE_THERMAL] parameters (mftire.mf.thermal_section.bounds). */",
             "typedef struct {", "    size_t offset;", "    double bound;",
             "    int kind; /* 0: >, 1: >=, 2: 0 or 1 */", "    const char *text;", "} MTThermalBound;",
             "#define MT_THERMAL_BOUNDS { \\"]  # fmt: skip
    for name, op, bound in bounds():
        key = "TH_" + name.upper()
        if name in ("cold_pressure", "temperature"):
            continue  # not used by the block (and not always a parameter)
        text = "0 or 1" if op == "in" else f"{op} {bound:g}"
        entry = f"{{offsetof(MFParams, {key}), {vt._c_double(bound)}, {kinds[op]}, {vt.c_string(text)}}}"
        lines.append(f"    {entry}, \\")
    lines += ["}", ""]
    return lines


def _config_header(thermal: ThermalExport | None) -> str:
    """The transient model's ``mt_config_gen.h`` (:func:`mftire.mf.cheaders.transient_config_header`) for this export:
    the thermal block on with its laws' nodes, or off."""
    from mftire.mf.cheaders import transient_config_header
    from mftire.thermal.heat import KELVIN

    return transient_config_header(thermal is not None, thermal.nodes if thermal is not None else (), KELVIN)


def transient_model_description_xml(
    variables: list[vt.Variable], model_identifier: str, model_name: str, description: str, sources: list[str],
    fmi_version: int = 2,
) -> str:
    """``modelDescription.xml`` (FMI 2.0 or 3.0, ME + CS) with the states and their derivatives
    (:func:`mftire.fmu.variables.model_description_xml`; default step 1 ms)."""
    return vt.model_description_xml(variables, model_identifier, fmi_version, model_name, description, sources,
                                    step_size=0.001)  # fmt: skip


def generate_transient_sources(
    flat: dict[str, float], model_identifier: str, use_mode: int = vt.DEFAULT_USE_MODE, fmi_version: int = 2,
    thermal: ThermalExport | None = None,
) -> tuple[list[vt.Variable], dict[str, str]]:
    """The variable table and every file of ``sources/`` of the transient FMU (``thermal``: with the thermal
    block; its laws' C generated from :mod:`mftire.mf.extensions` as the steady FMU's)."""
    variables = transient_variable_table(flat, use_mode, thermal)
    ext = thermal.extensions if thermal is not None else None  # no other extension terms (refused at export)
    files = source_files("transient", fmi_version)
    files["mf_params.h"] = vt.params_header(variables, ext)
    files["mf_ext_gen.h"] = vt.extension_header(variables, ext)
    files["mt_config_gen.h"] = _config_header(thermal)
    files["mt_model_gen.h"] = transient_model_header(variables, model_identifier, fmi_version)
    if fmi_version == 3:
        files["buildDescription.xml"] = vt.build_description_xml(model_identifier, [UNITY])
    return variables, files


def _check_transient(tir, thermal: bool | None = None) -> tuple[dict[str, float], str, ThermalExport | None]:
    """Flat parameters, name and thermal block of a ``.tir`` for the transient FMU.  ``thermal``: None the
    thermal block when the file has ``[MFTIRE_THERMAL]``; True required (a clear error without the section);
    False without it."""
    from mftire.mf.thermal_section import SECTION
    from mftire.transient.slip_dynamics import thermal_block
    from mftire.tyre import Tyre, load

    flat, name, spec = _load(tir)
    tyre = tir if isinstance(tir, Tyre) else load(tir) if isinstance(tir, (str, os.PathLike)) else Tyre(tir)
    has = bool(tyre.parameters.sections.get(SECTION))
    if thermal is None:
        thermal = has
    if thermal:
        if not has:
            raise FMUExportError(f"{name}: the thermal block needs a [{SECTION}] section (made by mftire "
                                 "fit-thermal); this .tir has none")  # fmt: skip
        try:
            params, ext, nodes = thermal_block(tyre)
        except MftireError as exc:
            raise FMUExportError(f"{name}: cannot be exported: {exc}") from None
        return flat, name, ThermalExport(params, ext, tuple(nodes.values()))
    if spec is not None:
        raise FMUExportError(f"{name}: --transient supports [MFTIRE_EXTENSIONS] model extensions only as the "
                             f"temperature laws of the thermal block (a [{SECTION}] section)")  # fmt: skip
    return flat, name, None


def write_transient_fmu(tir, output: str | os.PathLike, fmi_version: int, cc: list[str], model_identifier: str | None,
                        use_mode: int, thermal: bool | None) -> Path:  # fmt: skip
    """Write the transient FMU (FMI 2.0 or 3.0, Model Exchange + Co-Simulation) of
    :func:`mftire.fmu.export.export_fmu` ``(..., transient=True)``, which checked the request and found the C
    compiler ``cc`` (:func:`mftire.fmu.build.check_export`).

    ``thermal``: the thermal block (module docstring); None: when the file has a
    ``[MFTIRE_THERMAL]`` section, True requires one (an error without), False leaves it out.

    Inputs ``Fz, Vx, Vy, omega, gamma, P, muRoad, yawRate``; outputs ``Fx, Fy, Mz, Mx,
    My, kappa_t, alpha_t`` and the steady-state channels at the transient slips; states
    ``u``, ``v``.  Co-Simulation advances the states with the model's own integration
    (``mt_advance`` of ``mf_transient.c``).  The model identifier is, by default, the file name,
    ``_transient`` and a short hash of the parameters.  See ``docs/transient.md``.
    """
    flat, name, th = _check_transient(tir, thermal)
    table = partial(transient_variable_table, flat, use_mode, th)
    ident = export_identifier(model_identifier, name + "_transient", table, fmi_version)
    variables, files = generate_transient_sources(flat, ident, use_mode, fmi_version, th)
    description = (
        f"Transient Magic Formula tyre {name} (FITTYP {int(flat['FITTYP'])}) exported by mftire: wheel kinematics "
        "in, relaxation-length slip states u, v, low-speed model; ISO-W axes, SI units"
    )
    if th is not None:
        description += ("; thermal block: node temperatures T_s, T_b, T_g [degC] (inputs T_ambient, T_road; the gas "
                        "law's hot pressure P_hot)")  # fmt: skip
    xml = transient_model_description_xml(variables, ident, name, description, [UNITY], fmi_version)
    docs = documentation_files(model_name=name, model_identifier=ident, description=description, variables=variables,
                               flat=flat, fmi_version=fmi_version, transient=True)  # fmt: skip
    return package_fmu(output, xml, files, ident, fmi_version, cc, docs)


#: The C harness of :func:`build_probe_library` (``mftire/fmu/c/mt_probe.c``).
PROBE = "mt_probe.c"


def build_probe_library(tir, directory: str | os.PathLike, compiler: str | None = None,
                        thermal: bool | None = None) -> Path:  # fmt: skip
    """Compile the transient C model with a small harness (``mt_probe_*``) into a shared library.

    For tests (C vs Python derivatives) and the benchmark; the FMU itself exports only
    the FMI functions.  Returns the library path.
    """
    flat, name, th = _check_transient(tir, thermal)
    _, files = generate_transient_sources(flat, "mt_probe", thermal=th)
    files[PROBE] = read_source(PROBE)
    directory = Path(directory)
    src = directory / "probe_src"
    src.mkdir(parents=True, exist_ok=True)
    for fname, text in files.items():
        (src / fname).write_text(text, encoding="utf-8")
    lib = directory / "libmt_probe.so"
    cc = find_compiler(compiler)
    c_files = [str(src / f) for f in (*(f for f in TRANSIENT_SOURCES if f.endswith(".c") and f != "mt_model.c"),
                                      PROBE)]  # the model and the harness only, no FMI functions
    cmd = [*cc, *CFLAGS, "-D_POSIX_C_SOURCE=199309L", "-I", str(src), *c_files, "-o", str(lib), *LIBS]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if res.returncode != 0:
        raise FMUExportError("compiling the probe library failed:\n" + (res.stderr or res.stdout)[-2000:])
    return lib


__all__ = [
    "ThermalExport",
    "build_probe_library",
    "generate_transient_sources",
    "transient_model_description_xml",
    "transient_model_header",
    "transient_variable_table",
    "write_transient_fmu",
]
