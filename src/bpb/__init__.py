"""bpb inside Inspect AI: the ``bpb`` namespace of Inspect's registry.

With ``pip install 'bpb[inspect]'``, Inspect finds bpb's tasks through its ``inspect_ai`` entry
point (:mod:`bpb._registry`), so ``inspect eval bpb/q1 --model ... -T data=DIR`` works. The
tasks are built on bpb's embedding API (:mod:`bpb_core.library`): bpb's prompts and images,
bpb's parsers and scorers. See docs/inspect.md. ``bpb_core`` never imports this package.
"""
