"""The one FMU variable table, and everything generated from it.

:func:`variable_table` lists every variable of the tyre FMU -- the independent
variable ``time``, the inputs, the outputs, the integer ``useMode`` and one tunable
parameter per numeric ``.tir`` key -- with its value reference, causality,
variability, start value, SI unit and description.  From that single list this
module generates:

* the GUID / instantiation token (:func:`guid`, a hash of the table),
* ``modelDescription.xml`` for FMI 2.0 and FMI 3.0 (:func:`model_description_xml`),
* the C header ``mf_params.h`` with the ``MFParams`` struct, one ``double`` per
  parameter, and the export-time configuration of the model extensions
  (:func:`params_header`),
* the C header ``mf_model_gen.h`` with the GUID, the value-reference table, the
  start values and the variable names (:func:`model_header`),

so the C code, the XML and the GUID cannot disagree.

* the C header ``mf_ext_gen.h`` with the model-extension terms (:func:`extension_header`):
  the term table, and the C of every variable and form, generated from the one
  definition of each in :mod:`mftire.mf.extensions`.

Model extensions (``[MFTIRE_EXTENSIONS]``, :mod:`mftire.mf.extensions`): the terms'
targets, forms and variables are fixed at export time (:func:`extension_spec`); their
numeric keys (REF, SCALE, MIN, MAX, levels, coefficients) are tunable parameters; every
external variable they read (e.g. ``temperature``) is an extra continuous input.
"""

from __future__ import annotations

import hashlib
import re
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from mftire.errors import MftireInputError
from mftire.mf import cheaders, spec
from mftire.mf.cheaders import c_comment, c_string
from mftire.mf.extensions import (
    MAX_EXTERNAL,
    SECTION,
    Extension,
    ExtensionSet,
    parse_section,
)
from mftire.parameters import PARAMETERS

#: ``useMode`` of a new FMU: limit checks, no alpha-star, combined slip (MFeval's default).
DEFAULT_USE_MODE = 111

#: Parameters whose change means a different model: ``fixed`` (set before initialisation only).
FIXED_PARAMETERS = frozenset({"FITTYP"})

#: ``.tir`` keys that are not FMU parameters: ``USE_MODE`` is the ADAMS mode switch of the file; the FMU
#: has one mode variable, the integer parameter ``useMode`` (its start value is the export's ``use_mode``).
NOT_PARAMETERS = frozenset({"USE_MODE"})

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

#: FMI unit name -> (SI base-unit exponents kg, m, s, rad) for every unit the table uses.
UNITS: dict[str, dict[str, int]] = {
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N/rad": {"kg": 1, "m": 1, "s": -2, "rad": -1},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "1/m": {"m": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "s": {"s": 1},
    "1/s": {"s": -1},
    "degC": {"K": 1, "offset": 273.15},  # the thermal block's temperatures
    "K/s": {"K": 1, "s": -1},
    "J/K": {"kg": 1, "m": 2, "s": -2, "K": -1},
    "W/K": {"kg": 1, "m": 2, "s": -3, "K": -1},
}

#: mftire parameter-table units -> FMI unit names ("-" is dimensionless: no unit).
_PARAM_UNIT = {
    "-": None, "m": "m", "N": "N", "N/m": "N/m", "N*s/m": "N.s/m", "N*m/rad": "N.m/rad", "Pa": "Pa",
    "kg": "kg", "kg*m^2": "kg.m2", "m/s": "m/s", "m/s^2": "m/s2", "rad": "rad", "s": "s", "1/s": "1/s",
}  # fmt: skip

#: Inputs: (name, C field of MFInputs, unit, description, start) -- start is a .tir key or a number.
INPUTS: tuple[tuple[str, str, str | None, str, str | float], ...] = (
    ("Fz", "Fz", "N", "Vertical load (negative: lift-off, treated as 0)", "FNOMIN"),
    ("kappa", "kappa", None, "Longitudinal slip ratio (-1 = locked wheel)", 0.0),
    ("alpha", "alpha", "rad", "Slip angle", 0.0),
    ("gamma", "gamma", "rad", "Inclination (camber) angle", 0.0),
    ("phit", "phit", "1/m", "Turn slip (used when useMode ends in 2)", 0.0),
    ("Vx", "Vx", "m/s", "Longitudinal speed of the wheel centre", "LONGVL"),
    ("P", "P", "Pa", "Inflation pressure (NaN or <= 0: INFLPRES)", "INFLPRES"),
    ("omega", "omega", "rad/s", "Wheel spin speed; 0 = estimate from kappa, Vx and Re", 0.0),
    ("muRoad", "muRoad", None, "Road friction factor, multiplies LMUX and LMUY", 1.0),
)

#: Outputs: (name, C field of MFOutputs, unit, description), the outputs of :data:`mftire.mf.spec.OUTPUTS`
#: the FMU publishes.  The output load is ``Fz_out`` because FMI variable names are unique and ``Fz`` is
#: the input.
OUTPUTS: tuple[tuple[str, str, str | None, str], ...] = tuple(
    (o.fmu, o.field, None if o.unit == "-" else o.unit, o.description) for o in spec.OUTPUTS if o.fmu and o.field
)


#: External-variable inputs the C code has room for (``MF_MAX_DATA`` in mf_eval.h).
MAX_DATA_INPUTS = MAX_EXTERNAL

#: Largest double: an absent MIN/MAX of a term (no clipping) as a finite FMU start value.
_BIG = 1.7976931348623157e308


def _valid_fmi_name(name: str) -> bool:
    return bool(name) and not any(ord(ch) < 0x20 or 0x7F <= ord(ch) < 0xA0 for ch in name) and name == name.strip()


def extension_spec(section) -> ExtensionSet | None:
    """The validated ``[MFTIRE_EXTENSIONS]`` terms to compile in (None: no extension).

    Raises :class:`~mftire.errors.MftireInputError` for a section the Python evaluator
    rejects, and for external-variable names that cannot be FMI variable names.
    """
    ext = parse_section(section)
    if not ext:
        return None
    for var in ext.external_variables:
        if not _valid_fmi_name(var):
            raise MftireInputError(
                f"[{SECTION}] variable {var!r} cannot be an FMI variable name (control characters or surrounding "
                "blanks)"
            )
    return ext


def fmu_input_name(variable: str, taken) -> str:
    """The FMU input of an external variable: its own name, or ``ext_<name>`` when an FMU
    variable already has that name (``time`` is the FMI independent variable)."""
    return f"ext_{variable}" if variable in taken else variable


def term_fields(t: Extension) -> list[tuple[str, float]]:
    """The numeric fields of term ``t`` as FMU parameters, in struct order
    (levels directly before the coefficients, as the C form reads them)."""
    names = ["REF", "SCALE", "MIN", "MAX"]
    if t.variable2 is not None:
        names += ["REF2", "SCALE2", "MIN2", "MAX2"]
    out = [(t.key(n), min(max(t.value(n), -_BIG), _BIG)) for n in names]
    out += [(k, t.numbers[k]) for k in t.level_keys]
    out += [(k, t.numbers.get(k, 0.0)) for k in t.coefficient_keys]
    return out


@dataclass(frozen=True)
class Variable:
    """One FMU variable."""

    name: str
    vr: int  #: value reference (unique over all types)
    kind: str  #: "time", "input", "output", "mode" or "param"
    type: str  #: "Real" or "Integer"
    causality: str
    variability: str
    start: float | int | None
    unit: str | None  #: FMI unit name (see :data:`UNITS`) or None
    description: str
    field: str  #: C member (MFInputs / MFOutputs / MFParams), "" for time and useMode

    @property
    def initial(self) -> str | None:
        if self.kind == "output":
            return "calculated"
        if self.kind in ("param", "mode"):
            return "exact"
        return None


def _number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def variable_table(
    flat: dict[str, float], use_mode: int = DEFAULT_USE_MODE, extensions: ExtensionSet | None = None
) -> list[Variable]:
    """The FMU's variables for the flat parameter dict ``flat`` (see ``with_defaults``).

    Value references: 0 ``time``, 1.. inputs (the data variables of the model
    extensions last), then outputs, ``useMode``, then the parameters in the order of
    :data:`mftire.parameters.PARAMETERS`, followed by the file's non-standard
    numeric keys (in file order) and the keys of the active model extensions
    (``extensions``, see :func:`extension_spec`; in library order).
    """
    out: list[Variable] = [
        Variable("time", 0, "time", "Real", "independent", "continuous", None, "s", "Simulation time", "")
    ]
    for name, field, unit, desc, start in INPUTS:
        value = float(flat[start]) if isinstance(start, str) else float(start)
        out.append(Variable(name, len(out), "input", "Real", "input", "continuous", value, unit, desc, field))
    terms = extensions.terms if extensions else ()
    ext_keys = {k: v for t in terms for k, v in term_fields(t)}
    taken = {"time", *(i[0] for i in INPUTS), *(o[0] for o in OUTPUTS), "useMode", *flat}
    for i, name in enumerate(extensions.external_variables if extensions else ()):
        users = ", ".join(f"EXT{t.index}" for t in terms if name in t.variables())
        desc = f"External variable '{name}' of the model extension(s) {users} (unit as in the fitted data)"
        out.append(Variable(fmu_input_name(name, taken), len(out), "input", "Real", "input", "continuous", 0.0, None,
                            desc, f"data[{i}]"))  # fmt: skip
    for name, field, unit, desc in OUTPUTS:
        out.append(Variable(name, len(out), "output", "Real", "output", "continuous", None, unit, desc, field))
    out.append(
        Variable(
            "useMode", len(out), "mode", "Integer", "parameter", "tunable", int(use_mode), None,
            "The one mode switch of the FMU (the file's USE_MODE is not a parameter): three digits, "
            "hundreds 1 limit checks / 2 none; tens 1 / 2 alpha-star; units 0 pure slip / 1 combined / "
            "2 combined + turn slip",
            "",
        )
    )  # fmt: skip
    standard = {p.key: p for p in PARAMETERS if p.unit != "str" and p.key not in NOT_PARAMETERS}
    keys = list(standard) + [
        k for k in flat if k not in standard and k not in NOT_PARAMETERS and k not in ext_keys
        and _IDENT.fullmatch(k) and _number(flat[k])
    ]  # fmt: skip
    for key in keys:
        row = standard.get(key)
        unit = _PARAM_UNIT[row.unit] if row else None
        desc = f"[{row.section}] {row.description}" if row else "Non-standard .tir key (not used by the equations)"
        variability = "fixed" if key in FIXED_PARAMETERS else "tunable"
        out.append(
            Variable(key, len(out), "param", "Real", "parameter", variability, float(flat[key]), unit, desc, key)
        )
    for t in terms:
        desc = f"[{SECTION}] EXT{t.index}: {t.describe()} (targets, form, variables fixed at export)"
        for key, value in term_fields(t):
            out.append(Variable(key, len(out), "param", "Real", "parameter", "tunable", value, None, desc, key))
    names = [v.name for v in out]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise MftireInputError(
            f"FMU variable name(s) {', '.join(map(repr, dup))} used twice: a variable of [{SECTION}] must not "
            "be named like an FMU input, output or parameter"
        )
    return out


def _fmt(value: float | int) -> str:
    if isinstance(value, int):
        return str(value)
    if value != value:
        return "NaN"
    if value in (float("inf"), float("-inf")):
        return "INF" if value > 0 else "-INF"
    return repr(float(value))


def guid(variables: list[Variable], fmi_version: int) -> str:
    """GUID (FMI 2) / instantiation token (FMI 3): a hash of the variable table.

    The descriptions of the model-extension parameters are hashed too: they carry
    the export-time choices (targets, form, variables) compiled into the binary.
    """
    h = hashlib.sha256(f"mftire-fmu fmi{fmi_version}\n".encode())
    for v in variables:
        start = "" if v.start is None else _fmt(v.start)
        line = f"{v.vr}|{v.name}|{v.type}|{v.causality}|{v.variability}|{start}|{v.unit}"
        if v.description.startswith(f"[{SECTION}]") or v.field.startswith("data["):
            line += "|" + v.description
        h.update((line + "\n").encode())
    return "{" + str(uuid.UUID(bytes=h.digest()[:16])) + "}"


# --------------------------------------------------------------------------- C headers


def params_header(variables: list[Variable], extensions: ExtensionSet | None = None) -> str:
    """``mf_params.h`` of the FMU: one double per parameter variable, and the external
    variables of the model extensions ``extensions`` (:func:`mftire.mf.cheaders.params_header`)."""
    fields = [(v.field, f"vr {v.vr}: {v.description[:80]}") for v in variables if v.kind == "param"]
    data = extensions.external_variables if extensions else []
    return cheaders.params_header(fields, data, " from the FMU variable table of mftire/fmu/variables.py")


def extension_header(variables: list[Variable], extensions: ExtensionSet | None = None) -> str:
    """``mf_ext_gen.h`` of the FMU: the terms of ``extensions`` compiled in
    (:func:`mftire.mf.cheaders.extension_header`)."""
    return cheaders.extension_header(extensions)


def _offset(struct: str, field: str) -> str:
    if "[" in field:  # data[i]: avoid offsetof with a subscript (an extension in C99)
        base, index = field.rstrip("]").split("[")
        return f"(offsetof({struct}, {base}) + {int(index)} * sizeof(double))"
    return f"offsetof({struct}, {field})"


def _c_double(x: float) -> str:
    if x != x:
        return "NAN"
    if x in (float("inf"), float("-inf")):
        return "INFINITY" if x > 0 else "(-INFINITY)"
    return repr(float(x))


def value_reference_table(
    variables: list[Variable], prefix: str, structs: dict[str, str], want: Callable[[Variable], str] | None = None
) -> list[str]:
    """The C lines of a model's value-reference table (``FMVarInfo`` of ``fmu/c/fmu_common.h``, one type for every
    model): ``<prefix>_VARS`` and ``<prefix>_VAR_NAMES`` (``<prefix>_N_VARS`` entries), the start values
    ``<prefix>_INPUT_START`` and ``<prefix>_PARAM_START``.  ``structs``: the C struct of the inputs, outputs and
    parameters (the offsets); states and derivatives hold their index; ``want``: an output's channel groups."""
    by_vr = sorted(variables, key=lambda v: v.vr)
    assert [v.vr for v in by_vr] == list(range(len(by_vr))), "value references must be 0..n-1"
    lines = [f"static const FMVarInfo {prefix}_VARS[{prefix}_N_VARS] = {{"]
    for v in by_vr:
        fixed = 1 if v.variability == "fixed" else 0
        off = _offset(structs[v.kind], v.field) if v.kind in structs else v.field if v.kind in ("state", "der") else "0"
        group = want(v) if want is not None and v.kind == "output" else "0"
        lines.append(f"    {{FM_K_{v.kind.upper()}, {fixed}, {group}, {off}}}, /* {v.vr} {c_comment(v.name)} */")
    lines += ["};", "", f"static const char *const {prefix}_VAR_NAMES[{prefix}_N_VARS] = {{"]
    lines += [f"    {c_string(v.name)}," for v in by_vr]
    for kind in ("input", "param"):
        lines += ["};", "", f"static const {structs[kind]} {prefix}_{kind.upper()}_START = {{"]
        lines += [f"    .{v.field} = {_c_double(v.start)}," for v in by_vr if v.kind == kind]
    return [*lines, "};", ""]


#: The C structs of the steady-state model's inputs, outputs and parameters (:func:`model_header`).
STEADY_STRUCTS = {"input": "MFInputs", "output": "MFOutputs", "param": "MFParams"}


def model_header(
    variables: list[Variable],
    model_identifier: str,
    fmi_version: int,
    *,
    prefix: str = "MF",
    include: str = "mf_eval.h",
    structs: dict[str, str] = STEADY_STRUCTS,
    want: Callable[[Variable], str] | None = None,
    extra: Sequence[str] = (),
) -> str:
    """A model's ``<prefix>_model_gen.h`` (default the steady-state tyre's ``mf_model_gen.h``): GUID, model
    identifier, the ``useMode`` variable, the value-reference table with names and start values
    (:func:`value_reference_table`), then the model's ``extra`` lines.  ``include``: the model's interface."""
    mode = next(v for v in variables if v.kind == "mode")
    guard = f"{prefix}_MODEL_GEN_H"
    lines = [
        f"/* {prefix.lower()}_model_gen.h -- GENERATED by mftire/fmu/variables.py from the FMU variable table. "
        "Do not edit. */",
        f"#ifndef {guard}",
        f"#define {guard}",
        "",
        "#include <math.h>",
        "#include <stddef.h>",
        f'#include "{include}"',
        "",
        f'#define {prefix}_GUID "{guid(variables, fmi_version)}"',
        f'#define {prefix}_MODEL_IDENTIFIER "{model_identifier}"',
        f"#define {prefix}_FMI_VERSION {fmi_version}",
        f"#define {prefix}_N_VARS {len(variables)}",
        f"#define {prefix}_VR_USEMODE {mode.vr}",
        f"#define {prefix}_USEMODE_START {int(mode.start)}",
        "",
        *value_reference_table(variables, prefix, structs, want),
        *extra,
        f"#endif /* {guard} */",
        "",
    ]
    return "\n".join(lines)


# --------------------------------------------------------------------------- XML


def _attrs(**kw: object) -> str:
    return "".join(f" {k}={quoteattr(str(v))}" for k, v in kw.items() if v is not None)


def _unit_definitions(variables: list[Variable], fmi_version: int) -> list[str]:
    used = sorted({v.unit for v in variables if v.unit})
    lines = ["  <UnitDefinitions>"]
    for name in used:
        base = _attrs(**UNITS[name])
        lines.append(f"    <Unit name={quoteattr(name)}><BaseUnit{base}/></Unit>")
    lines.append("  </UnitDefinitions>")
    return lines


def _log_categories() -> list[str]:
    return [
        "  <LogCategories>",
        '    <Category name="logStatusWarning" description="Limit checks, NaN inputs, clipped curvature factors"/>',
        '    <Category name="logStatusError" description="Invalid calls, modes or parameters"/>',
        '    <Category name="logAll" description="Warnings and errors (each kind of warning at most once per 1000'
        ' evaluations, with the count of the others)"/>',
        "  </LogCategories>",
    ]


def model_description_xml(
    variables: list[Variable],
    model_identifier: str,
    fmi_version: int,
    model_name: str,
    description: str,
    sources: list[str],
    generation_tool: str = "mftire",
    step_size: float | None = None,
) -> str:
    """``modelDescription.xml`` for FMI 2.0 (``fmi_version=2``) or 3.0 (``3``), ME + CS, of any model's variable
    table: the steady-state tyre's, or the transient tyre's with its continuous states (kind ``"state"``, start
    None: calculated) and their derivatives (kind ``"der"``, ``field``: the state's index).  Every output and
    derivative depends on every input and state.  ``step_size``: the default experiment's step."""
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version must be 2 or 3, not {fmi_version!r}")
    token = guid(variables, fmi_version)
    states = [v for v in variables if v.kind == "state"]
    # the initial unknowns: the outputs, the derivatives and the calculated states; with states, their
    # dependencies are left to the default (every known of the initialisation)
    initial = [v for v in variables if v.kind in ("output", "der") or (v.kind == "state" and v.start is None)]
    common = dict(
        modelName=model_name,
        description=description,
        generationTool=generation_tool,
        variableNamingConvention="flat",
    )
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    if fmi_version == 2:
        head = f'<fmiModelDescription fmiVersion="2.0"{_attrs(guid=token, **common)} numberOfEventIndicators="0">'
        lines.append(head)
        src = ["    <SourceFiles>"] + [f"      <File name={quoteattr(s)}/>" for s in sources] + ["    </SourceFiles>"]
        lines += [
            f"  <ModelExchange modelIdentifier={quoteattr(model_identifier)}"
            ' completedIntegratorStepNotNeeded="true" canNotUseMemoryManagementFunctions="true"'
            ' canBeInstantiatedOnlyOncePerProcess="false">',
            *src,
            "  </ModelExchange>",
            f"  <CoSimulation modelIdentifier={quoteattr(model_identifier)}"
            ' canHandleVariableCommunicationStepSize="true" canNotUseMemoryManagementFunctions="true"'
            ' canBeInstantiatedOnlyOncePerProcess="false">',
            *src,
            "  </CoSimulation>",
        ]
    else:
        lines += [
            f'<fmiModelDescription fmiVersion="3.0"{_attrs(instantiationToken=token, **common)}>',
            f"  <ModelExchange modelIdentifier={quoteattr(model_identifier)}"
            ' canBeInstantiatedOnlyOncePerProcess="false" needsCompletedIntegratorStep="false"/>',
            f"  <CoSimulation modelIdentifier={quoteattr(model_identifier)}"
            ' canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="false"'
            ' providesIntermediateUpdate="false" canReturnEarlyAfterIntermediateUpdate="false"/>',
        ]
    lines += _unit_definitions(variables, fmi_version)
    lines += _log_categories()
    lines.append(f'  <DefaultExperiment{_attrs(startTime=0, stopTime=1, stepSize=step_size)}/>')
    # FMI 2.0 refers to a variable by its index (1-based position), FMI 3.0 by its value reference
    ref = {v.vr: i for i, v in enumerate(variables, start=1)} if fmi_version == 2 else {v.vr: v.vr for v in variables}
    state_ref = {v.field: ref[v.vr] for v in states}
    lines.append("  <ModelVariables>")
    for i, v in enumerate(variables, start=1):
        start = {"state": "exact" if v.start is not None else "calculated", "der": "calculated"}
        attrs = _attrs(
            name=v.name, valueReference=v.vr, description=v.description, causality=v.causality,
            variability=v.variability, initial=start.get(v.kind, v.initial if v.kind != "input" else None),
        )  # fmt: skip
        inner = _attrs(unit=v.unit if v.type == "Real" else None,
                       derivative=state_ref[v.field] if v.kind == "der" else None,
                       start=None if v.start is None else _fmt(v.start))  # fmt: skip
        if fmi_version == 2:
            lines.append(f"    <ScalarVariable{attrs}><{v.type}{inner}/></ScalarVariable> <!-- {i} -->")
        else:
            lines.append(f"    <{'Float64' if v.type == 'Real' else 'Int32'}{attrs}{inner}/>")
    lines.append("  </ModelVariables>")
    deps = " ".join(str(ref[v.vr]) for kind in ("input", "state") for v in variables if v.kind == kind)
    depends = f' dependencies="{deps}"'
    initial_depends = "" if states else depends
    structure = {  # element (FMI 2.0: list, unknown; FMI 3.0: element) -> (variables, dependencies)
        ("Outputs", "Output"): ([v for v in variables if v.kind == "output"], depends),
        ("Derivatives", "ContinuousStateDerivative"): ([v for v in variables if v.kind == "der"], depends),
        ("InitialUnknowns", "InitialUnknown"): (initial, initial_depends),
    }
    lines.append("  <ModelStructure>")
    for (list2, element3), (unknowns, dep) in structure.items():
        if not unknowns:
            continue
        if fmi_version == 2:
            lines += [f"    <{list2}>", *(f'      <Unknown index="{ref[v.vr]}"{dep}/>' for v in unknowns),
                      f"    </{list2}>"]  # fmt: skip
        else:
            lines += [f'    <{element3} valueReference="{v.vr}"{dep}/>' for v in unknowns]
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"


def build_description_xml(model_identifier: str, sources: list[str]) -> str:
    """``sources/buildDescription.xml`` (FMI 3.0)."""
    files = "\n".join(f"      <SourceFile name={quoteattr(s)}/>" for s in sources if s.endswith(".c"))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<fmiBuildDescription fmiVersion="3.0">\n'
        f"  <BuildConfiguration modelIdentifier={quoteattr(model_identifier)}"
        f" description={quoteattr('C99; link with the maths library (-lm)')}>\n"
        '    <SourceFileSet language="C99">\n'
        f"{files}\n"
        "    </SourceFileSet>\n"
        '    <Library name="m"/>\n'
        "  </BuildConfiguration>\n"
        "</fmiBuildDescription>\n"
    )


__all__ = [
    "DEFAULT_USE_MODE",
    "INPUTS",
    "MAX_DATA_INPUTS",
    "OUTPUTS",
    "Variable",
    "build_description_xml",
    "c_string",
    "extension_header",
    "extension_spec",
    "guid",
    "model_description_xml",
    "model_header",
    "params_header",
    "value_reference_table",
    "variable_table",
]
