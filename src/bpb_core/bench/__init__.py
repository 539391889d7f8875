"""``bpb bench sim``: simulators of one scene family side by side, speed against error.

:mod:`~bpb_core.bench.sim` calls the family's hooks checked, builds the simulators and
measures; :mod:`~bpb_core.bench.sim_report` writes the markdown section and the plot. They
reach scene families and simulators through the registry only, so the benchmark measures
whatever plugins are installed. Nothing here prints; the CLI shows the results. The other
benchmarks are scripts in the checkout's ``benchmarks/`` folder.
"""
