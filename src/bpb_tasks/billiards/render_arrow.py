"""How long the cue velocity arrow of ``init.png`` may be: the longest arrow, at most the wanted
length, whose shaft stays on the cloth and off the pockets and whose head keeps a clearance.

A candidate length is checked at points every 5 mm along the arrow (:func:`_clear`). The check
tries the tip first (where a too-long arrow fails) and then proves the whole shaft clear from its
two ends (the shaft is straight, so it stays in the box its ends are in, and it is far from a
pocket whose distance to the segment is larger than the pocket circle); only when the proof is
not certain by a margin far above rounding error are the points checked one by one. The answer
is the same as checking every point, so the images do not change.
"""

from __future__ import annotations

import math

from bpb_tasks.billiards.render_canvas import CanvasSpec

Point = tuple[float, float]

ARROW_CLEARANCE = 0.012
"""Metres the arrow keeps from the cushions and from every pocket's edge."""
ARROW_MIN = 0.05
"""The shortest arrow drawn (metres beyond the ball), even where nothing longer fits."""
_SAFE = 1e-9
"""Metres of margin for the two-ends proof (rounding errors are about 1e-16 m)."""


def arrow_length(spec: CanvasSpec, pos: Point, direction: Point, wanted: float) -> float:
    """The longest arrow (metres beyond the cue ball's edge), at most ``wanted``, whose shaft
    and head stay on the cloth and off the pockets (down to :data:`ARROW_MIN`)."""
    length = wanted
    while length > ARROW_MIN and not _clear(spec, pos, direction, length):
        length -= 0.005
    return max(length, ARROW_MIN)


def _clear(spec: CanvasSpec, pos: Point, direction: Point, length: float) -> bool:
    """Whether the shaft stays on the cloth and off the pockets, and the head (its
    half-width plus :data:`ARROW_CLEARANCE`) too."""
    head = 10 * spec.scale / spec.ppm + ARROW_CLEARANCE  # the head's half-width, in metres
    r = spec.radius_m
    steps = max(2, math.ceil(length / 0.005))

    def point(k: int) -> Point:
        d = r * 1.15 + (length + r - r * 1.15) * k / steps
        return pos[0] + direction[0] * d, pos[1] + direction[1] * d

    tip = point(steps)
    if not _point_clear(spec, tip, head):
        return False
    first = point(0)
    if _surely_clear(spec, first, tip, head):
        return True
    return all(_point_clear(spec, point(k), 0.0) for k in range(steps))


def _point_clear(spec: CanvasSpec, p: Point, room: float) -> bool:
    """Whether ``p`` is ``room`` inside the cushions and ``room`` off every pocket circle."""
    x, y = p
    if not (room <= x <= spec.width_m - room and room <= y <= spec.height_m - room):
        return False
    limit = spec.pocket_radius_m + room
    for px, py in spec.pockets:
        dx, dy = x - px, y - py
        # hypot(dx, dy) >= |dx| and >= |dy|: only a pocket this close in x and y can be hit
        if -limit < dx < limit and -limit < dy < limit and math.hypot(dx, dy) < limit:
            return False
    return True


def _surely_clear(spec: CanvasSpec, a: Point, b: Point, head: float) -> bool:
    """Whether every point of segment ``a``-``b`` is clear (room 0), with :data:`_SAFE` to
    spare; ``False`` means "not proven", not "blocked"."""
    lo, hi = _SAFE, spec.width_m - _SAFE
    if not (lo <= min(a[0], b[0]) and max(a[0], b[0]) <= hi):
        return False
    hi = spec.height_m - _SAFE
    if not (lo <= min(a[1], b[1]) and max(a[1], b[1]) <= hi):
        return False
    limit = spec.pocket_radius_m + head + _SAFE
    return all(_segment_distance(a, b, c) > limit for c in spec.pockets)


def _segment_distance(a: Point, b: Point, c: Point) -> float:
    """Distance from ``c`` to the segment ``a``-``b``."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    cx, cy = c[0] - a[0], c[1] - a[1]
    norm = ex * ex + ey * ey
    t = 0.0 if norm == 0 else min(1.0, max(0.0, (cx * ex + cy * ey) / norm))
    return math.hypot(cx - t * ex, cy - t * ey)
