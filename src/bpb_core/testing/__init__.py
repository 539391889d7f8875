"""Test and benchmark helpers: a local OpenAI-compatible server with fault injection."""
