"""Benchmarks behind `bpb bench ...` (the simulator benchmark lives with the simulators)."""
