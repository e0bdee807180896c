"""``mftire export-fmu TIR --output tyre.fmu [--fmi-version 2|3]``."""

from __future__ import annotations

import argparse


def _cmd_export_fmu(args: argparse.Namespace) -> int:
    from mftire.fmu.export import export_fmu
    from mftire.iotools.output import OutputPlan

    OutputPlan([args.tir], args.force).file(args.output)
    path = export_fmu(
        args.tir,
        args.output,
        fmi_version=args.fmi_version,
        model_identifier=args.model_identifier,
        use_mode=args.mode,
        compiler=args.cc,
        transient=args.transient or args.thermal,
        **({"thermal": True} if args.thermal else {}),
    )
    transient = args.transient or args.thermal
    kind = f"FMI {args.fmi_version}.0 Model Exchange + Co-Simulation" + (", transient" if transient else "")
    if args.thermal:
        kind += ", thermal block"
    print(f"mftire export-fmu: wrote {path} ({kind})")
    return 0


def add_parser(subparsers) -> None:
    """Register the ``export-fmu`` sub-command."""
    p = subparsers.add_parser(
        "export-fmu",
        help="export a .tir as a self-contained FMU (C code compiled with the system C compiler)",
        description="Export a .tir as an FMU carrying the Magic Formula as compiled C code "
        "(no Python needed by the importer). Default: FMI 2.0 with Model Exchange and Co-Simulation.",
    )
    p.add_argument("tir", metavar="TIR", help="the .tir property file")
    p.add_argument("--output", "-o", required=True, help="the .fmu file to write")
    p.add_argument("--fmi-version", type=int, choices=(2, 3), default=2, help="FMI version (default 2)")
    p.add_argument("--mode", type=int, default=111,
                   help="start value of useMode, the FMU's one mode parameter (default 111)")  # fmt: skip
    p.add_argument("--model-identifier",
                   help="C identifier of the binary (default: the file name and a short hash of the parameters)")
    p.add_argument("--transient", action="store_true",
                   help="transient tyre: wheel kinematics in (Fz, Vx, Vy, omega, ...), relaxation-length slip "
                   "states, low-speed model (FMI 2.0 or 3.0; see docs/transient.md)")  # fmt: skip
    p.add_argument("--thermal", action="store_true",
                   help="the transient tyre with its thermal block (implies --transient; the .tir must have a "
                   "[MFTIRE_THERMAL] section, made by mftire fit-thermal). Without this flag a .tir with the "
                   "section exported --transient gets the thermal block too")  # fmt: skip
    p.add_argument("--cc", help="C compiler command (default: $CC, then cc, gcc, clang)")
    from mftire.cli_options import add_force_option

    add_force_option(p)
    p.set_defaults(func=_cmd_export_fmu)
