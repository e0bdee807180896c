"""Export a ``.tir`` tyre as a self-contained FMU (FMI 2.0 ME + CS, or FMI 3.0).

The FMU carries the Magic Formula as C code (``mftire/mf/c``, wrapped by ``mftire/fmu/c``), compiled
here with the system C compiler; no Python is needed to use it.  Layout::

    modelDescription.xml
    sources/            all C sources and headers (+ buildDescription.xml for FMI 3)
    binaries/linux64/<id>.so          (FMI 2.0)
    binaries/x86_64-linux/<id>.so     (FMI 3.0)

The variable table (:mod:`mftire.fmu.variables`) generates the XML, the GUID and
the C headers, so they cannot disagree.
"""

from __future__ import annotations

import os
from functools import partial
from pathlib import Path

from mftire.errors import MftireError
from mftire.fmu import variables as vt
from mftire.fmu.build import (  # noqa: F401 (re-exported)
    FMI_HEADERS,
    UNITY,
    FMUExportError,
    _load,
    _platform,
    check_export,
    compile_sources,
    export_identifier,
    find_compiler,
    model_identifier_for,
    package_fmu,
    source_files,
)
from mftire.fmu.documentation import documentation_files
from mftire.mf.extensions import ExtensionSet
from mftire.mf.family import PAC2002_CODE


def _table(flat: dict[str, float], use_mode: int, extensions: ExtensionSet | None) -> list[vt.Variable]:
    """The steady-state FMU's variable table (:func:`mftire.fmu.variables.variable_table`), an export error when
    the model extensions cannot be exported."""
    try:
        return vt.variable_table(flat, use_mode, extensions)
    except MftireError as exc:
        raise FMUExportError(f"the model extensions cannot be exported: {exc}") from None


def generate_sources(
    flat: dict[str, float],
    model_identifier: str,
    fmi_version: int,
    use_mode: int = vt.DEFAULT_USE_MODE,
    extensions: ExtensionSet | None = None,
) -> tuple[list[vt.Variable], dict[str, str]]:
    """The variable table and every file of ``sources/`` (name -> text).

    ``extensions`` is the model-extension configuration (:func:`mftire.fmu.variables.extension_spec`).
    """
    variables = _table(flat, use_mode, extensions)
    files = source_files("steady", fmi_version)
    files["mf_params.h"] = vt.params_header(variables, extensions)
    files["mf_ext_gen.h"] = vt.extension_header(variables, extensions)
    files["mf_model_gen.h"] = vt.model_header(variables, model_identifier, fmi_version)
    if fmi_version == 3:
        files["buildDescription.xml"] = vt.build_description_xml(model_identifier, [UNITY])
    return variables, files


def export_fmu(
    tir,
    output: str | os.PathLike,
    fmi_version: int = 2,
    *,
    model_identifier: str | None = None,
    use_mode: int = vt.DEFAULT_USE_MODE,
    compiler: str | None = None,
    transient: bool = False,
    thermal: bool | None = None,
) -> Path:
    """Export a tyre as an FMU.

    Parameters
    ----------
    tir : path, Tyre or mapping
        The ``.tir`` file (or an already loaded :class:`~mftire.tyre.Tyre`).
    output : path
        The ``.fmu`` file to write (atomically).
    fmi_version : 2 or 3
        FMI 2.0 (Model Exchange and Co-Simulation in one FMU) or FMI 3.0 (both too).
    model_identifier : str, optional
        C identifier of the binary; default the tyre's file name and a short hash of its parameters
        (``<name>_<8 hex digits>``), so that two tyres never collide.
    use_mode : int
        Start value of the ``useMode`` parameter (default 111).
    compiler : str, optional
        C compiler command; default ``$CC``, then cc, gcc, clang.
    transient : bool
        Export the transient tyre instead (wheel kinematics in, relaxation-length
        states; FMI 2.0 or 3.0): :func:`mftire.fmu.transient_export.write_transient_fmu`.
    thermal : bool, optional
        Transient only: the thermal block (None: when the file has ``[MFTIRE_THERMAL]``; True: required,
        an error without the section; False: left out).

    Returns
    -------
    Path of the written FMU.

    Raises
    ------
    FMUExportError
        No C compiler, a compile error, or a ``.tir`` that cannot be evaluated
        (including a ``[MFTIRE_EXTENSIONS]`` section the evaluator rejects).

    A ``[MFTIRE_EXTENSIONS]`` section is compiled in: its numeric keys become tunable
    parameters, the data variables its extensions read become extra inputs, and its
    string keys (variables, generic channel) are fixed (see ``docs/fmu.md``).
    """
    if thermal and not transient:
        raise FMUExportError("the thermal block is part of the transient tyre: export with transient=True "
                             "(mftire export-fmu --transient)")  # fmt: skip
    cc = check_export(fmi_version, use_mode, compiler)
    if transient:
        from mftire.fmu.transient_export import write_transient_fmu

        return write_transient_fmu(tir, output, fmi_version, cc, model_identifier, use_mode, thermal)
    flat, name, spec = _load(tir)
    ident = export_identifier(model_identifier, name, partial(_table, flat, use_mode, spec), fmi_version)
    variables, files = generate_sources(flat, ident, fmi_version, use_mode, spec)
    fmt = "PAC2002" if flat["FITTYP"] == PAC2002_CODE else f"FITTYP {int(flat['FITTYP'])}"
    description = f"Magic Formula tyre {name} ({fmt}) exported by mftire; ISO-W axes, SI units"
    if spec:
        description += f"; model extensions: {'; '.join(t.describe() for t in spec.terms)}"
    xml = vt.model_description_xml(variables, ident, fmi_version, model_name=name, description=description,
                                   sources=[UNITY])  # fmt: skip
    docs = documentation_files(model_name=name, model_identifier=ident, description=description, variables=variables,
                               flat=flat, fmi_version=fmi_version)  # fmt: skip
    return package_fmu(output, xml, files, ident, fmi_version, cc, docs)


__all__ = ["FMUExportError", "export_fmu", "find_compiler", "generate_sources", "compile_sources"]
