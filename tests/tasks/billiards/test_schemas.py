"""The JSON Schemas published in docs/schemas match the models, and dataset files validate."""

from __future__ import annotations

import json
from pathlib import Path

from bpb_tasks.billiards.scene import Scene, scene_json_schema
from bpb_tasks.billiards.truth import FinalState, final_json_schema
from support.paths import DOCS

SCHEMAS = DOCS / "schemas"


def test_committed_schemas_match_the_code() -> None:
    # Regenerate as docs/dataset-card.md says (scene_json_schema, final_json_schema)
    assert json.loads((SCHEMAS / "init.schema.json").read_text()) == scene_json_schema()
    assert json.loads((SCHEMAS / "final.schema.json").read_text()) == final_json_schema()


def test_generated_files_round_trip_through_the_models(small_dataset: Path) -> None:
    init = small_dataset / "h3" / "scene_0001" / "init.json"
    final = small_dataset / "h3" / "scene_0001" / "final.json"
    scene = Scene.model_validate_json(init.read_bytes())
    truth = FinalState.model_validate_json(final.read_bytes())
    assert (scene.model_dump_json(indent=2) + "\n").encode() == init.read_bytes()
    assert (truth.model_dump_json(indent=2) + "\n").encode() == final.read_bytes()
    assert [p.id for p in truth.predictions] == list(range(7))
    assert [q.id for q in truth.q1] == list(range(1, 7))
