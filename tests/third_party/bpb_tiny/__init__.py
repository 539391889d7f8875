"""bpb-tiny: a third-party scene family for bpb, kept small enough to read in one sitting.

The ``slider`` family is one point puck on a straight track ``[0, L]``: it decelerates at a
constant ``mu*g`` and bounces elastically off the walls at both ends. The ``slider-exact``
simulator gives its outcome in closed form, the ``slider_stop`` task asks where the puck is at
the horizon and how many times it hit a wall, and the ``slider_errors`` diagnostic summarises the
answers. Nothing in bpb's core knows any of it: everything arrives through :mod:`bpb_tiny.hooks`,
the package's single ``bpb`` entry point.
"""
