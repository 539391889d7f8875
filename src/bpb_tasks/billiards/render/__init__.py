"""What the billiards family draws: ``images`` (the three scene images) on ``canvas`` and
``palette``, encoded by ``png``; ``picture`` (the gallery picture) and ``stats_figures``."""
