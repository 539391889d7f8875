"""bpb's version (one place; recorded in datasets, runs and ``bpb --version``)."""

__version__ = "0.1.0"
