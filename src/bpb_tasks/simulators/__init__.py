"""Physics simulators: the exact event-driven ``analytic`` one and fixed-step ``pymunk``."""
