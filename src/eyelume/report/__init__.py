"""Report: pictures, plots and the HTML report. Thin: no physics.

This package is the only part of eyelume that imports matplotlib. Figures are built as
:class:`matplotlib.figure.Figure` objects rendered by the Agg canvas, never through pyplot's global
state, so report code is safe to call from worker processes and tests.

Modules
-------
plots
    :func:`~eyelume.report.plots.save_grey_png`, :func:`~eyelume.report.plots.save_irradiance_plot`,
    :func:`~eyelume.report.plots.save_layout` and :class:`~eyelume.report.plots.SectionCurve`.
"""
