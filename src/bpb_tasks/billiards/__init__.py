"""The built-in ``billiards`` scene family: ``scene`` (model, config, sampling, calibration),
``truth``, ``stability``, ``render`` and ``vision``; ``family`` ties them together."""
