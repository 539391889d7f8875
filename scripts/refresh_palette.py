"""Write the default canvas's palette again (``src/bpb_tasks/billiards/render_palette.json``).

Usage: ``python scripts/refresh_palette.py``, after changing the style, the canvas drawing or the
sample the palette is cut from (``tests/tasks/billiards/test_palette.py`` says when). The file
only saves computing: a process whose key differs computes the same palette itself.
"""

from __future__ import annotations

from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import SHIPPED, ship

if __name__ == "__main__":
    ship(CanvasSpec.from_config(DatasetConfig()))
    print(f"wrote {SHIPPED}")
