"""The benchmarks ``prandtl-fmu bench`` runs (the command line's entry is in ``cli.py``):

* ``work_precision.py``: what accuracy costs in time, ``prandtl-fmu bench [--quick] [--out DIR] [--from-csv]``:
  every stepper, the FMU driven by FMPy and scipy's solvers on the regularized model, against ``exact``; then the
  paper's Table 1 (the order of convergence), beside the printed one. Writes work_precision.csv, table1.csv,
  work_precision.png, error_vs_h.png and report.md;
* ``paper.py``: its problem, the paper's section 8 scene with n branches (``paper_scene``), and the printed
  Table 1;
* ``networks.py``: what a chain of n nodes costs per step, ``prandtl-fmu bench --networks``. Writes
  network_scaling.csv, network_scaling.png and network_report.md.

They ship with the package, so that an installed copy measures itself. The repository's ``benchmarks/`` folder
holds the narrower measurements (one effect's cost, one FMU overhead, one platform), plain scripts run from a
checkout, each writing its own files under ``docs/bench`` or ``out/``.
"""
