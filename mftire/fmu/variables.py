"""The one FMU variable table, and everything generated from it.

:func:`variable_table` lists every variable of the tyre FMU -- the independent
variable ``time``, the inputs, the outputs, the integer ``useMode`` and one tunable
parameter per numeric ``.tir`` key -- with its value reference, causality,
variability, start value, SI unit and description.  From that single list this
module generates:

* the GUID / instantiation token (:func:`guid`, a hash of the table),
* ``modelDescription.xml`` for FMI 2.0 and FMI 3.0 (:func:`model_description_xml`),
* the C header ``mf_params.h`` with the ``MFParams`` struct, one ``double`` per
  parameter (:func:`params_header`),
* the C header ``mf_model_gen.h`` with the GUID, the value-reference table, the
  start values and the variable names (:func:`model_header`),

so the C code, the XML and the GUID cannot disagree.
"""

from __future__ import annotations

import hashlib
import re
import uuid
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from mftire.parameters import PARAMETERS

#: ``useMode`` of a new FMU: limit checks, no alpha-star, combined slip (MFeval's default).
DEFAULT_USE_MODE = 111

#: Parameters whose change means a different model: ``fixed`` (set before initialisation only).
FIXED_PARAMETERS = frozenset({"FITTYP"})

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

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

#: Outputs: (name, C field of MFOutputs, unit, description).  The output load is
#: ``Fz_out`` because FMI variable names are unique and ``Fz`` is the input.
OUTPUTS: tuple[tuple[str, str, str | None, str], ...] = (
    ("Fx", "Fx", "N", "Longitudinal force"),
    ("Fy", "Fy", "N", "Lateral force"),
    ("Fz_out", "Fz", "N", "Vertical load used (negative input set to 0)"),
    ("Mx", "Mx", "N.m", "Overturning moment"),
    ("My", "My", "N.m", "Rolling-resistance moment"),
    ("Mz", "Mz", "N.m", "Self-aligning moment"),
    ("Re", "Re", "m", "Effective rolling radius"),
    ("Rl", "Rl", "m", "Loaded radius"),
    ("rho", "rho", "m", "Tyre vertical deflection"),
    ("a2", "a2", "m", "Contact patch length 2a"),
    ("b2", "b2", "m", "Contact patch width 2b"),
    ("t", "t", "m", "Pneumatic trail"),
    ("Mzr", "Mzr", "N.m", "Residual aligning moment"),
    ("mux", "mux", None, "Longitudinal friction coefficient"),
    ("muy", "muy", None, "Lateral friction coefficient"),
    ("Kxk", "Kxk", "N", "Longitudinal slip stiffness dFx0/dkappa"),
    ("Kya", "Kya", "N/rad", "Cornering stiffness dFy0/dalpha"),
    ("sigmax", "sigmax", "m", "Longitudinal relaxation length"),
    ("sigmay", "sigmay", "m", "Lateral relaxation length"),
)


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


def variable_table(flat: dict[str, float], use_mode: int = DEFAULT_USE_MODE) -> list[Variable]:
    """The FMU's variables for the flat parameter dict ``flat`` (see ``with_defaults``).

    Value references: 0 ``time``, 1.. inputs, then outputs, ``useMode``, then the
    parameters in the order of :data:`mftire.parameters.PARAMETERS`, followed by
    the file's non-standard numeric keys (in file order).
    """
    out: list[Variable] = [
        Variable("time", 0, "time", "Real", "independent", "continuous", None, "s", "Simulation time", "")
    ]
    for name, field, unit, desc, start in INPUTS:
        value = float(flat[start]) if isinstance(start, str) else float(start)
        out.append(Variable(name, len(out), "input", "Real", "input", "continuous", value, unit, desc, field))
    for name, field, unit, desc in OUTPUTS:
        out.append(Variable(name, len(out), "output", "Real", "output", "continuous", None, unit, desc, field))
    out.append(
        Variable(
            "useMode", len(out), "mode", "Integer", "parameter", "tunable", int(use_mode), None,
            "Three-digit mode: hundreds 1 limit checks / 2 none; tens 1 / 2 alpha-star; "
            "units 0 pure slip / 1 combined / 2 combined + turn slip",
            "",
        )
    )  # fmt: skip
    standard = {p.key: p for p in PARAMETERS if p.unit != "str"}
    keys = list(standard) + [k for k in flat if k not in standard and _IDENT.match(k) and _number(flat[k])]
    for key in keys:
        row = standard.get(key)
        unit = _PARAM_UNIT[row.unit] if row else None
        desc = f"[{row.section}] {row.description}" if row else "Non-standard .tir key (not used by the equations)"
        variability = "fixed" if key in FIXED_PARAMETERS else "tunable"
        out.append(
            Variable(key, len(out), "param", "Real", "parameter", variability, float(flat[key]), unit, desc, key)
        )
    names = [v.name for v in out]
    assert len(set(names)) == len(names), "duplicate variable name"
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
    """GUID (FMI 2) / instantiation token (FMI 3): a hash of the variable table."""
    h = hashlib.sha256(f"mftire-fmu fmi{fmi_version}\n".encode())
    for v in variables:
        start = "" if v.start is None else _fmt(v.start)
        h.update(f"{v.vr}|{v.name}|{v.type}|{v.causality}|{v.variability}|{start}|{v.unit}\n".encode())
    return "{" + str(uuid.UUID(bytes=h.digest()[:16])) + "}"


# --------------------------------------------------------------------------- C headers


def params_header(variables: list[Variable]) -> str:
    """``mf_params.h``: the ``MFParams`` struct, one double per parameter variable."""
    lines = [
        "/* mf_params.h -- GENERATED by mftire/fmu/variables.py from the FMU variable table. Do not edit. */",
        "#ifndef MF_PARAMS_H",
        "#define MF_PARAMS_H",
        "",
        "typedef struct {",
    ]
    for v in variables:
        if v.kind == "param":
            lines.append(f"    double {v.field}; /* vr {v.vr}: {v.description[:80].replace('*/', '* /')} */")
    lines += ["} MFParams;", "", "#endif /* MF_PARAMS_H */", ""]
    return "\n".join(lines)


def _c_double(x: float) -> str:
    if x != x:
        return "NAN"
    if x in (float("inf"), float("-inf")):
        return "INFINITY" if x > 0 else "(-INFINITY)"
    return repr(float(x))


def model_header(variables: list[Variable], model_identifier: str, fmi_version: int) -> str:
    """``mf_model_gen.h``: GUID, value-reference table, start values, names."""
    kinds = {"time": "MF_K_TIME", "input": "MF_K_INPUT", "output": "MF_K_OUTPUT", "mode": "MF_K_MODE",
             "param": "MF_K_PARAM"}  # fmt: skip
    structs = {"input": "MFInputs", "output": "MFOutputs", "param": "MFParams"}
    by_vr = sorted(variables, key=lambda v: v.vr)
    assert [v.vr for v in by_vr] == list(range(len(by_vr))), "value references must be 0..n-1"
    mode = next(v for v in variables if v.kind == "mode")
    lines = [
        "/* mf_model_gen.h -- GENERATED by mftire/fmu/variables.py from the FMU variable table. Do not edit. */",
        "#ifndef MF_MODEL_GEN_H",
        "#define MF_MODEL_GEN_H",
        "",
        "#include <math.h>",
        "#include <stddef.h>",
        '#include "mf_eval.h"',
        "",
        f'#define MF_GUID "{guid(variables, fmi_version)}"',
        f'#define MF_MODEL_IDENTIFIER "{model_identifier}"',
        f"#define MF_FMI_VERSION {fmi_version}",
        f"#define MF_N_VARS {len(by_vr)}",
        f"#define MF_VR_USEMODE {mode.vr}",
        f"#define MF_USEMODE_START {int(mode.start)}",
        "",
        "static const MFVarInfo MF_VARS[MF_N_VARS] = {",
    ]
    for v in by_vr:
        fixed = 1 if v.variability == "fixed" else 0
        off = f"offsetof({structs[v.kind]}, {v.field})" if v.kind in structs else "0"
        lines.append(f"    {{{kinds[v.kind]}, {fixed}, {off}}}, /* {v.vr} {v.name} */")
    lines += ["};", "", "static const char *const MF_VAR_NAMES[MF_N_VARS] = {"]
    lines += [f'    "{v.name}",' for v in by_vr]
    lines += ["};", "", "static const MFInputs MF_INPUT_START = {"]
    lines += [f"    .{v.field} = {_c_double(v.start)}," for v in by_vr if v.kind == "input"]
    lines += ["};", "", "static const MFParams MF_PARAM_START = {"]
    lines += [f"    .{v.field} = {_c_double(v.start)}," for v in by_vr if v.kind == "param"]
    lines += ["};", "", "#endif /* MF_MODEL_GEN_H */", ""]
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
        '    <Category name="logAll" description="Every warning (no repetition limit)"/>',
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
) -> str:
    """``modelDescription.xml`` for FMI 2.0 (``fmi_version=2``) or 3.0 (``3``), ME + CS."""
    token = guid(variables, fmi_version)
    inputs = [v for v in variables if v.kind == "input"]
    outputs = [v for v in variables if v.kind == "output"]
    head = '<?xml version="1.0" encoding="UTF-8"?>'
    common = dict(
        modelName=model_name,
        description=description,
        generationTool=generation_tool,
        variableNamingConvention="flat",
    )
    if fmi_version == 2:
        lines = [head, f'<fmiModelDescription fmiVersion="2.0"{_attrs(guid=token, **common)}'
                       f' numberOfEventIndicators="0">']  # fmt: skip
        src = ["    <SourceFiles>"] + [f"      <File name={quoteattr(s)}/>" for s in sources] + ["    </SourceFiles>"]
        lines += [
            f"  <ModelExchange modelIdentifier={quoteattr(model_identifier)}"
            ' canNotUseMemoryManagementFunctions="true" canBeInstantiatedOnlyOncePerProcess="false">',
            *src,
            "  </ModelExchange>",
            f"  <CoSimulation modelIdentifier={quoteattr(model_identifier)}"
            ' canHandleVariableCommunicationStepSize="true" canNotUseMemoryManagementFunctions="true"'
            ' canBeInstantiatedOnlyOncePerProcess="false">',
            *src,
            "  </CoSimulation>",
        ]
        lines += _unit_definitions(variables, 2)
        lines += _log_categories()
        lines.append('  <DefaultExperiment startTime="0" stopTime="1"/>')
        lines.append("  <ModelVariables>")
        index: dict[int, int] = {}
        for i, v in enumerate(variables, start=1):
            index[v.vr] = i
            attrs = _attrs(
                name=v.name, valueReference=v.vr, description=v.description, causality=v.causality,
                variability=v.variability, initial=v.initial if v.kind != "input" else None,
            )  # fmt: skip
            inner = _attrs(unit=v.unit if v.type == "Real" else None, start=None if v.start is None else _fmt(v.start))
            lines.append(f"    <ScalarVariable{attrs}><{v.type}{inner}/></ScalarVariable> <!-- {i} -->")
        lines.append("  </ModelVariables>")
        deps = " ".join(str(index[v.vr]) for v in inputs)
        lines.append("  <ModelStructure>")
        lines.append("    <Outputs>")
        lines += [f'      <Unknown index="{index[v.vr]}" dependencies="{deps}"/>' for v in outputs]
        lines.append("    </Outputs>")
        lines.append("    <InitialUnknowns>")
        lines += [f'      <Unknown index="{index[v.vr]}" dependencies="{deps}"/>' for v in outputs]
        lines.append("    </InitialUnknowns>")
        lines.append("  </ModelStructure>")
        lines.append("</fmiModelDescription>")
        return "\n".join(lines) + "\n"

    if fmi_version != 3:
        raise ValueError(f"fmi_version must be 2 or 3, not {fmi_version!r}")
    lines = [head, f'<fmiModelDescription fmiVersion="3.0"{_attrs(instantiationToken=token, **common)}>']
    lines += [
        f"  <ModelExchange modelIdentifier={quoteattr(model_identifier)}"
        ' canBeInstantiatedOnlyOncePerProcess="false"/>',
        f"  <CoSimulation modelIdentifier={quoteattr(model_identifier)}"
        ' canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="false"'
        ' providesIntermediateUpdate="false" canReturnEarlyAfterIntermediateUpdate="false"/>',
    ]
    lines += _unit_definitions(variables, 3)
    lines += _log_categories()
    lines.append('  <DefaultExperiment startTime="0" stopTime="1"/>')
    lines.append("  <ModelVariables>")
    for v in variables:
        tag = "Float64" if v.type == "Real" else "Int32"
        attrs = _attrs(
            name=v.name, valueReference=v.vr, description=v.description, causality=v.causality,
            variability=v.variability, initial=v.initial if v.kind != "input" else None,
            unit=v.unit if v.type == "Real" else None, start=None if v.start is None else _fmt(v.start),
        )  # fmt: skip
        lines.append(f"    <{tag}{attrs}/>")
    lines.append("  </ModelVariables>")
    deps = " ".join(str(v.vr) for v in inputs)
    lines.append("  <ModelStructure>")
    lines += [f'    <Output valueReference="{v.vr}" dependencies="{deps}"/>' for v in outputs]
    lines += [f'    <InitialUnknown valueReference="{v.vr}" dependencies="{deps}"/>' for v in outputs]
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
    "OUTPUTS",
    "Variable",
    "build_description_xml",
    "guid",
    "model_description_xml",
    "model_header",
    "params_header",
    "variable_table",
]
