"""Local web apps: people answer the benchmark in the browser (``bpb human``) and runs are
browsed pair by pair (``bpb view``).

Both are Starlette apps served by uvicorn on 127.0.0.1 only, with Jinja2 templates rendered with
autoescaping; the apps themselves answer only requests addressed to 127.0.0.1 or localhost,
however they are served (:func:`bpb_core.web.serve.loopback_only`). Core knows no task: each
task that people can answer brings its own form widgets
(:class:`~bpb_core.capabilities.AnswersInBrowser`); answers are stored as a normal run through
the run-folder code, so ``bpb report`` puts people beside models. Starlette, uvicorn and Jinja2
come with the ``web`` extra (``pip install 'bpb[web]'``).
"""
