"""The failure gallery: the worst answered scenes, with truth and prediction drawn on the scene.

Each case draws, with Pillow, on the dataset's ``trajectory.png`` (or ``init.png``): a yellow
ring where each ball truly ends, a red ring and cross where the model put it, and a line between
them. The table-to-pixel mapping comes from the image geometry recorded in ``dataset.json``
(``config.image``); when the image or the geometry is missing, a plain table is drawn instead.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
from PIL import Image, ImageDraw, ImageFont

from bpb_core.layout import MANIFEST, SceneKey
from bpb_core.results.reading import read_truth
from bpb_core.results.tables import TOTAL_WEIGHTS, scene_scores

TRUTH_COLOUR = (255, 212, 0)
PRED_COLOUR = (235, 30, 70)
LINK_COLOUR = (255, 255, 255)


@dataclass(frozen=True)
class Canvas:
    """Maps table metres to image pixels."""

    left: float
    top: float
    ppm: float
    height_m: float

    def to_px(self, x: float, y: float) -> tuple[float, float]:
        """Pixel of table point ``(x, y)`` (y up on the table, down in the image)."""
        return self.left + x * self.ppm, self.top + (self.height_m - y) * self.ppm


@dataclass(frozen=True)
class Case:
    """One gallery entry: which run and scene, its scores, what was wrong, and the image."""

    run: str
    scene_id: str
    horizon: float
    scores: dict[str, float]
    wrong_q1: list[str] = field(default_factory=list)
    wrong_q2: list[str] = field(default_factory=list)
    q3_errors: list[str] = field(default_factory=list)
    png: bytes = b""


def worst_cases(units: pd.DataFrame, count: int = 8) -> pd.DataFrame:
    """Up to ``count`` answered (run, scene) pairs with the lowest total score.

    Runs take turns (models before baselines, each run's worst scene first), so one bad run
    does not fill the gallery; only scenes answered in every task and not fully right qualify.
    """
    wide = _scene_totals(units)
    wide = wide[wide["total"] < 1.0].sort_values(["total", "scene_id"], kind="stable")
    wide["turn"] = wide.groupby("run", observed=True).cumcount()
    ranked = wide.sort_values(["turn", "baseline", "total", "run"], kind="stable")
    return ranked.head(count).drop(columns="turn").reset_index(drop=True)


def _scene_totals(units: pd.DataFrame) -> pd.DataFrame:
    scenes = scene_scores(units)
    wide = scenes.pivot_table(
        index=["run", "baseline", "horizon", "index", "scene_id"],
        columns="task",
        values="score",
        observed=True,
    )
    wide.columns.name = None
    answered = scenes.assign(ok=scenes["status"].isin(["ok", "parse_error"]))
    all_ok = answered.groupby(["run", "horizon", "index"], observed=True)["ok"].all()
    wide = wide.reset_index()
    keys = pd.MultiIndex.from_frame(wide[["run", "horizon", "index"]])
    wide = wide[all_ok.reindex(keys).fillna(False).to_numpy(dtype=bool)].copy()
    tasks = [t for t in TOTAL_WEIGHTS if t in wide.columns]
    weights = sum(TOTAL_WEIGHTS[t] for t in tasks)
    wide["total"] = sum(TOTAL_WEIGHTS[t] * wide[t] for t in tasks) / weights
    return wide


def build_cases(units: pd.DataFrame, runs: dict[str, Path], count: int = 8) -> list[Case]:
    """Gallery cases for the worst scenes; ``runs`` maps run label to its dataset folder."""
    cases = []
    for row in worst_cases(units, count).to_dict(orient="records"):
        run, sid = str(row["run"]), str(row["scene_id"])
        rows = units[(units["run"] == run) & (units["scene_id"] == sid)]
        key = SceneKey(float(row["horizon"]), int(row["index"]))
        scores = {t: float(row[t]) for t in (*TOTAL_WEIGHTS, "total") if t in row}
        case = _describe(rows, run, sid, key.horizon, scores)
        png = overlay(runs[run], key, rows[rows["task"] == "q3"])
        cases.append(Case(**{**case.__dict__, "png": png}))
    return cases


def _describe(
    rows: pd.DataFrame, run: str, sid: str, horizon: float, scores: dict[str, float]
) -> Case:
    wrong = rows[~rows["correct"]]

    def said(r: Any) -> str:
        return "no answer" if pd.isna(r.pred) else f"said {r.pred}"

    q1 = [
        f"ball {r.unit}: {said(r)}, truth {r.truth}"
        for r in wrong[wrong["task"] == "q1"].itertuples()
    ]
    q2 = [
        f"{r.unit}: {said(r)}, truth {r.truth}" for r in wrong[wrong["task"] == "q2"].itertuples()
    ]
    q3 = [_q3_text(r) for r in wrong[wrong["task"] == "q3"].itertuples()]
    return Case(run, sid, horizon, scores, q1, q2, q3)


def _q3_text(r: Any) -> str:
    if r.truth == "null" or r.pred != "pos":
        truth = "pocketed" if r.truth == "null" else f"({r.truth_x:.3f}, {r.truth_y:.3f})"
        pred = {"null": "pocketed", "?": "invalid"}.get(str(r.pred), "no answer")
        pred = f"({r.pred_x:.3f}, {r.pred_y:.3f})" if r.pred == "pos" else pred
        return f"ball {r.unit}: predicted {pred}, truth {truth}"
    return f"ball {r.unit}: off by {r.distance:.3f} m ({r.distance / r.radius:.1f} R)"


def canvas_of(dataset: Path, image: Image.Image) -> Canvas | None:
    """The mapping of the dataset's images, if ``dataset.json`` records it and the size fits."""
    try:
        config = json.loads((dataset / MANIFEST).read_text(encoding="utf-8"))["config"]
        im, table = config.get("image", {}), config.get("table", {})
        ppm = float(im.get("px_per_m", 600.0))
        left, right = int(im.get("margin_left", 116)), int(im.get("margin_right", 48))
        top, bottom = int(im.get("margin_top", 84)), int(im.get("margin_bottom", 96))
        width, height = float(table.get("width", 2.0)), float(table.get("height", 1.0))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    size = (left + round(width * ppm) + right, top + round(height * ppm) + bottom)
    return Canvas(left, top, ppm, height) if image.size == size else None


def _base_image(dataset: Path, key: SceneKey) -> tuple[Image.Image, Canvas]:
    for name in ("trajectory.png", "init.png"):
        path = key.dir(dataset) / name
        if path.is_file():
            with Image.open(path) as img:
                image = img.convert("RGB")
            canvas = canvas_of(dataset, image)
            if canvas is not None:
                return image, canvas
    return _plain_table(dataset, key)


def _plain_table(dataset: Path, key: SceneKey) -> tuple[Image.Image, Canvas]:
    scene, _ = read_truth(dataset, key)
    width, height, ppm, margin = scene.table.width, scene.table.height, 400.0, 40
    canvas = Canvas(margin, margin, ppm, height)
    size = (round(width * ppm) + 2 * margin, round(height * ppm) + 2 * margin)
    image = Image.new("RGB", size, (245, 245, 240))
    draw = ImageDraw.Draw(image)
    draw.rectangle((margin, margin, size[0] - margin, size[1] - margin), fill=(30, 110, 60))
    r_pocket = scene.pockets.radius * ppm
    for cx, cy in scene.pockets.centers:
        px, py = canvas.to_px(cx, cy)
        draw.ellipse(
            (px - r_pocket, py - r_pocket, px + r_pocket, py + r_pocket), fill=(20, 20, 20)
        )
    r = scene.physics.ball_radius * ppm
    for ball in scene.balls:
        px, py = canvas.to_px(*ball.pos)
        draw.ellipse((px - r, py - r, px + r, py + r), fill=(250, 250, 250), outline=(0, 0, 0))
        draw.text((px, py), str(ball.id), fill=(0, 0, 0), anchor="mm", font=_font(int(r * 1.2)))
    return image, canvas


def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(max(size, 8))


def overlay(dataset: Path, key: SceneKey, q3: pd.DataFrame) -> bytes:
    """PNG of the scene with true (yellow) and predicted (red) final positions of every ball."""
    image, canvas = _base_image(dataset, key)
    draw = ImageDraw.Draw(image)
    radius = float(q3["radius"].iloc[0]) if len(q3) else 0.028575
    r = radius * canvas.ppm
    width = max(2, round(r / 6))
    font = _font(max(12, round(r * 0.9)))
    for row in q3.to_dict(orient="records"):
        _mark(draw, canvas, {str(k): v for k, v in row.items()}, r, width, font)
    framed = _with_legend(image, _font(max(14, round(image.width / 70))))
    buffer = io.BytesIO()
    framed.save(buffer, format="PNG", optimize=False)
    return buffer.getvalue()


def _mark(
    draw: ImageDraw.ImageDraw,
    canvas: Canvas,
    row: dict[str, Any],
    r: float,
    width: int,
    font: ImageFont.FreeTypeFont | ImageFont.ImageFont,
) -> None:
    def point(x: float, y: float) -> tuple[float, float] | None:
        return None if math.isnan(x) or math.isnan(y) else canvas.to_px(x, y)

    truth = point(float(row["truth_x"]), float(row["truth_y"]))
    pred = point(float(row["pred_x"]), float(row["pred_y"]))
    unit = str(row["unit"])
    if truth and pred:
        draw.line((*truth, *pred), fill=LINK_COLOUR, width=max(1, width // 2))
    if truth:
        tx, ty = truth
        draw.ellipse((tx - r, ty - r, tx + r, ty + r), outline=TRUTH_COLOUR, width=width)
        draw.text((tx + r, ty - r), unit, fill=TRUTH_COLOUR, font=font)
    if pred:
        x, y, d = pred[0], pred[1], r * 0.6
        draw.ellipse((x - r, y - r, x + r, y + r), outline=PRED_COLOUR, width=width)
        draw.line((x - d, y - d, x + d, y + d), fill=PRED_COLOUR, width=width)
        draw.line((x - d, y + d, x + d, y - d), fill=PRED_COLOUR, width=width)
        draw.text((x + r, y + r * 0.2), unit, fill=PRED_COLOUR, font=font)


def _with_legend(
    image: Image.Image, font: ImageFont.FreeTypeFont | ImageFont.ImageFont
) -> Image.Image:
    """``image`` below a band that explains the marks (so nothing of the scene is covered)."""
    band = round(font.size * 2.2) if isinstance(font, ImageFont.FreeTypeFont) else 30
    framed = Image.new("RGB", (image.width, image.height + band), (24, 28, 36))
    framed.paste(image, (0, band))
    draw = ImageDraw.Draw(framed)
    y = band // 2
    x = 16
    r = band // 4
    draw.ellipse((x, y - r, x + 2 * r, y + r), outline=TRUTH_COLOUR, width=3)
    draw.text((x + 3 * r, y), "true final position", fill=TRUTH_COLOUR, font=font, anchor="lm")
    x += framed.width // 3
    draw.ellipse((x, y - r, x + 2 * r, y + r), outline=PRED_COLOUR, width=3)
    draw.line((x + r * 0.4, y - r * 0.6, x + r * 1.6, y + r * 0.6), fill=PRED_COLOUR, width=3)
    draw.text((x + 3 * r, y), "predicted position", fill=PRED_COLOUR, font=font, anchor="lm")
    x += framed.width // 3
    draw.line((x, y, x + 2 * r, y), fill=LINK_COLOUR, width=2)
    draw.text((x + 3 * r, y), "error", fill=LINK_COLOUR, font=font, anchor="lm")
    return framed
