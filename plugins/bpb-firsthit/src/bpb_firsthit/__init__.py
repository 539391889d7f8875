"""bpb-firsthit: the example task plugin that docs/plugins.md walks through."""

__version__ = "0.1.0"
