"""How likely a scene's labels are to flip: ``annotation`` (the perturbed re-simulations),
``margins`` (the deterministic margins) and ``kernel`` (the perturbed copies, compiled)."""
