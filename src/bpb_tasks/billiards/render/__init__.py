"""What the billiards family draws: ``images`` (the three scene images, and the gallery picture)
on ``canvas`` and ``palette``, encoded by ``png``; and ``stats_figures``."""
