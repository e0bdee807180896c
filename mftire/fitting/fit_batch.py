"""``mftire fit --each``: one fit per input file as a task of :func:`mftire.batch.run_batch`."""

from __future__ import annotations

import os
import tempfile
import warnings
from dataclasses import dataclass
from typing import Any

from mftire.batch import InputFile, local_copy


@dataclass(frozen=True)
class FitFile:
    """``mftire fit`` of one input file: ``<name>.tir`` (and the report in ``<name>/`` with ``report``)."""

    template: Any  #: TirParameters
    stages: str | None
    weights: str | None
    alpha_star: bool
    fixed: tuple[str, ...]
    report: bool

    def __call__(self, item: InputFile, folder: str) -> list[str]:
        from mftire.errors import MftireInputError
        from mftire.fitting.fitter import fit_tir
        from mftire.iotools.tir import write_tir

        with tempfile.TemporaryDirectory(prefix="mftire-in-") as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit_tir([local_copy(item, tmp)], self.template, stages=self.stages, weights=self.weights,
                             alpha_star=self.alpha_star, fixed=list(self.fixed), progress=False)
        data = result.data
        if not any(s.status == "fitted" or (s.channel in data.columns and data[s.channel].notna().any())
                   for s in result.stages):
            raise MftireInputError("no stage could be fitted (no force or moment channel with data)")
        write_tir(result.parameters, os.path.join(folder, item.name + ".tir"))
        if self.report:
            from mftire.fitting.fit_report import write_report

            write_report(result, os.path.join(folder, item.name))
        rms = ", ".join(f"{s.channel} {s.rms:.4g}" for s in result.stages if s.status == "fitted")
        return [f"{item.name}.tir: {len(dict.fromkeys(result.identified))} coefficients fitted ({rms})"]
