"""``mftire diagnose --each``: one diagnosis per input file as a task of :func:`mftire.batch.run_batch`."""

from __future__ import annotations

import os
import tempfile
import warnings
from dataclasses import dataclass
from typing import Any

from mftire.batch import InputFile, local_copy


@dataclass(frozen=True)
class DiagnoseFile:
    """``mftire diagnose`` of one input file into ``<name>/``; the fitted tyre is ``tyres[name]`` or ``tyre``."""

    tyres: dict  #: output name -> TirParameters (a folder of fitted .tir files), or {} for ``tyre``
    tyre: Any
    holdout: Any
    n_perm: int
    seed: int

    def __call__(self, item: InputFile, folder: str) -> list[str]:
        from mftire.diagnosis.diagnose import diagnose
        from mftire.diagnosis.report import write_report
        from mftire.iotools.loaders import load_sweep_files
        from mftire.tyre import Tyre

        tyre = Tyre(self.tyres[item.name] if self.tyres else self.tyre)
        with tempfile.TemporaryDirectory(prefix="mftire-in-") as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data, _ = load_sweep_files([local_copy(item, tmp)])
            result = diagnose(data, tyre, self.holdout, n_perm=self.n_perm, seed=self.seed, progress=False)
            doc = write_report(result, os.path.join(folder, item.name))
        return [f"{item.name}/: {doc['summary'].splitlines()[0] if doc.get('summary') else ''}"]
