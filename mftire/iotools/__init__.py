"""Readers and writers, the lowest layer of mftire above the parameter table (imports nothing above it).

Thin readers and writers, each mapping names through one table: ``.tir`` tyre property files
(:mod:`~mftire.iotools.tir`, re-exported here; value checks in :mod:`~mftire.iotools.tir_checks`),
the sweep table (:mod:`~mftire.iotools.sweeps`: schema, column aliases, validation,
:func:`~mftire.iotools.sweeps.fit_rows`), TYDEX (:mod:`~mftire.iotools.tydex`), raw rig time
series (:mod:`~mftire.iotools.rig`), the shared loaders (:mod:`~mftire.iotools.loaders`), the unit
table (:mod:`~mftire.iotools.units`), the label columns (:mod:`~mftire.iotools.columns`), the keys
the evaluator reads (:mod:`~mftire.iotools.evaluator_keys`, generated), atomic writes
(:mod:`~mftire.iotools.atomic`) and the output policy (:mod:`~mftire.iotools.output`).  Grouping and
segmentation are sweep analysis: :mod:`mftire.segmentation`.
"""

from mftire.iotools import tir
from mftire.iotools.tir import *  # noqa: F403 (the .tir reader's public names, re-exported)

__all__ = list(tir.__all__)
