"""jaxnet's validation suite: ``python -m validation`` writes ``validation/REPORT.md`` and its plots.

Each section is a module of this package (``TITLE``, ``run(report, quick)``); see :mod:`validation.report`.
The stand-alone benchmark scripts beside them (``bench_*.py``, ``*_cost.py``) print their own tables.
"""
