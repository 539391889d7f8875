"""A billiards scene and where it comes from: ``model`` (the ``init.json`` model), ``config``
(the generation config), ``sampler`` (seeded scene draws) and ``calibrate`` (speed ranges)."""
