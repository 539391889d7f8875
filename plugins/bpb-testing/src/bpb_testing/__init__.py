"""Test helpers for bpb and its plugins: a local OpenAI-compatible server with fault injection
(``python -m bpb_testing.fakeserver``)."""
