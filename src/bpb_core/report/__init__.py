"""Reports: tables, charts, exports and a self-contained HTML page from run folders.

Import :func:`bpb_core.report.build.build_report` for the whole thing; this package imports
pandas and, when charts are drawn, matplotlib.
"""
