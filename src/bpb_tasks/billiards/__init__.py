"""The built-in ``billiards`` scene family: sampling, speed calibration, rendering and stats."""
