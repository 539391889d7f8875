"""The JSON Schemas published in docs/schemas match the models, and dataset files validate."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bpb_core.errors import BadInput
from bpb_core.validated_files import read_model
from bpb_tasks.billiards.scene.model import Scene, scene_json_schema
from bpb_tasks.billiards.truth.final import FinalState, final_json_schema
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


WRONG_TYPES = [  # (file, field path, value): each one pydantic used to coerce
    ("init.json", ("balls", 1, "id"), "1"),
    ("init.json", ("balls", 0, "id"), True),
    ("init.json", ("balls", 2, "id"), 2.0),
    ("init.json", ("balls", 0, "pos", 0), "1.0"),
    ("init.json", ("horizon",), "3"),
    ("init.json", ("scene_id",), 7),
    ("init.json", ("physics", "mu"), False),
    ("final.json", ("q1", 0, "id"), "1"),
    ("final.json", ("predictions", 1, "id"), 1.0),
    ("final.json", ("predictions", 1, "pos", 1), "0.5"),
    ("final.json", ("events", 0, "ids", 0), "0"),
    ("final.json", ("events", 0, "t"), "0.1"),
    ("final.json", ("stability", "stable"), "true"),
    ("final.json", ("stability", "samples"), 64.0),
    ("final.json", ("stability", "q3_stable"), 1),
    ("final.json", ("simulator",), 1),
]


@pytest.mark.parametrize(("name", "loc", "value"), WRONG_TYPES, ids=lambda v: str(v))
def test_a_wrong_typed_field_of_a_scene_file_is_refused_naming_it(
    small_dataset: Path, tmp_path: Path, name: str, loc: tuple[Any, ...], value: Any
) -> None:
    data = json.loads((small_dataset / "h3" / "scene_0001" / name).read_text())
    *outer, last = loc
    target = data
    for key in outer:
        target = target[key]
    target[last] = value
    path = tmp_path / name
    path.write_text(json.dumps(data))
    model = Scene if name == "init.json" else FinalState
    with pytest.raises(BadInput) as caught:
        read_model(path, model)
    field = "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in loc).lstrip(".")
    assert str(caught.value).startswith(f"{path}: {field}: Input should be a valid ")


def test_the_dataset_cards_examples_load(tmp_path: Path) -> None:
    """The hand-written init.json, final.json and config examples of docs/dataset-card.md are
    valid (their ``"..."`` list entries left out)."""
    import re

    from bpb_tasks.billiards.scene.config import load_config

    card = (DOCS / "dataset-card.md").read_text()
    blocks = re.findall(r"```(json|toml)\n(.*?)```", card, re.S)
    files = [re.sub(r',\s*"\.\.\."', "", body) for kind, body in blocks if kind == "json"]
    scene = Scene.model_validate_json(files[0])  # as bpb reads the files
    truth = FinalState.model_validate_json(files[1])
    assert scene.balls[0].vel == (-0.6725, 0.8251) and truth.stability is not None
    (config,) = [body for kind, body in blocks if kind == "toml"]
    (tmp_path / "c.toml").write_text(config)
    assert load_config(tmp_path / "c.toml").image.px_per_m == 800.0
