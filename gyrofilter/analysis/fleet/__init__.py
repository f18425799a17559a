"""Characterise a fleet: many recordings at once, one table, and the units that stand out.

- ``work``: :func:`~gyrofilter.analysis.fleet.work.analyse_recording` ``(path, settings) ->
  result``, the per-file work of ``gyrofilter allan`` (Allan deviation and coefficients) or
  ``gyrofilter gap`` (the gap analysis, and the Allan coefficients of the same file). It reads the
  file and returns plain data (the reports as the single-file commands write them); a file that
  cannot be analysed gives a result with its ``error`` instead of an exception. Its numbers depend
  only on the file and the settings (the gap simulations use fixed streams for every file),
  never on where it runs.
- ``runner``: runs it in worker processes (:func:`~gyrofilter.analysis.fleet.runner.run_local`, a
  :class:`concurrent.futures.ProcessPoolExecutor`) or on a Dask distributed cluster
  (:func:`~gyrofilter.analysis.fleet.runner.run_dask`, ``Client.map``; the ``[cluster]`` extra,
  imported only there). Both yield ``(index, result)`` as files finish.
- ``table``: the statistics and the table: one row per recording and axis (a failed file: one row
  with the reason), the units that stand out (the flag rules), fleet.csv and fleet.md.
"""
