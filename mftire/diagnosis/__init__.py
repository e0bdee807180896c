"""Close the loop: find what a fitted Magic Formula misses, why, and how much adding it helps.

=================  ==========================================================
``candidates``     explanatory variables: data columns and derived quantities
``ranking``        grouped cross-validated score and permutation test per candidate
``effects``        map a candidate to model extensions, fit them, choose one
``holdout``        split data by operating condition
``diagnose``       the whole procedure and its result object
``report``         diagnosis.md, diagnosis.json and figures
=================  ==========================================================
"""
