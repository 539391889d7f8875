"""Run files (``--config``) and ``--model-arg``: parsed as documented, bad input named in one
line, and a resume with other model arguments refused."""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from bpb_core.cli.run_cmd import model_args, read_run_file
from bpb_core.errors import BadInput
from bpb_core.model_calls import AdapterOptions
from support.inprocess import Done, bpb

RunBpb = Callable[..., Done]
GOOD = """
[defaults]
timeout = 300
api_base = "http://127.0.0.1:1/v1"

[[adapter]]
spec = "litellm:gpt-5.4"
args = {reasoning_effort = "high"}
headers = {"x-team" = "physics"}
concurrency = 2

[[adapter]]
spec = "litellm:claude-opus-4.5"
api_base = "http://127.0.0.1:1"
label = "budget"
args = {thinking = {type = "enabled", budget_tokens = 8000}}
price = {input = 1e-6, output = 2e-6, cache_read = 1e-7}
"""


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> RunBpb:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


def test_run_file_gives_each_adapter_its_options(tmp_path: Path) -> None:
    path = tmp_path / "sweep.toml"
    path.write_text(GOOD)
    first, second = read_run_file(path, AdapterOptions(seed=3), {"max_tokens": 9000})
    assert first.spec == "litellm:gpt-5.4" and first.run == {"timeout": 300, "concurrency": 2}
    assert first.options.model_args == {
        "reasoning_effort": "high",
        "max_tokens": 9000,  # --model-arg applies to every adapter
        "extra_headers": {"x-team": "physics"},
    }
    assert first.options.api_base == "http://127.0.0.1:1/v1" and first.options.seed == 3
    assert second.options.api_base == "http://127.0.0.1:1" and second.options.label == "budget"
    assert second.options.model_args["thinking"] == {"type": "enabled", "budget_tokens": 8000}
    assert second.options.prices["claude-opus-4.5"]["cache_read"] == 1e-7


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ('[[adapter]]\nspec = "litellm:x"\ntemperature = 0', "unknown key 'temperature'"),
        ('[[adapter]]\nspec = "litellm:x"\ntimeout = "slow"', "adapter 1.timeout"),
        ('[[adapter]]\nspec = "litellm:x"\nconcurrency = 0', "adapter 1.concurrency"),
        ("[[adapter]]\nargs = {a = 1}", "adapter 1.spec"),
        ('[[adapter]]\nspec = "litellm:x"\nargs = 3', "adapter 1.args"),
        ("[defaults]\ntimeout = 3", "no [[adapter]]"),
        ('[adapters]\nspec = "x"', "unknown table 'adapters'"),
        ("[[adapter]\n", "not a readable TOML"),
        (
            '[[adapter]]\nspec = "litellm:x"\nheaders = {"x-team" = {a = 1}}',
            "adapter 1.headers.x-team: expected a string, got {'a': 1}",
        ),
        ('[defaults]\nheaders = {x = true}\n[[adapter]]\nspec = "litellm:x"', "headers.x"),
        ('adapter = ["litellm:x"]', "adapter 1: expected an [[adapter]] table, got 'litellm:x'"),
        ('adapter = [{spec = "litellm:x"}, 3]', "adapter 2: expected an [[adapter]] table"),
        ('defaults = 3\n[[adapter]]\nspec = "litellm:x"', "defaults: expected a [defaults]"),
        ('[[adapter]]\nspec = "litellm:x"\napi_base = 3', "adapter 1.api_base: expected a string"),
        ('[defaults]\nlabel = true\n[[adapter]]\nspec = "litellm:x"', "defaults.label: expected"),
        (
            '[[adapter]]\nspec = "litellm:x"\nargs = {temperature = nan}',
            "adapter 1.args.temperature: must be a finite number, got nan",
        ),
        (
            '[[adapter]]\nspec = "litellm:x"\nargs = {thinking = {budget_tokens = inf}}',
            "adapter 1.args.thinking.budget_tokens: must be a finite number, got inf",
        ),
        (
            '[defaults]\nargs = {stop = [1.0, -inf]}\n[[adapter]]\nspec = "litellm:x"',
            "defaults.args.stop[1]: must be a finite number, got -inf",
        ),
        (
            '[[adapter]]\nspec = "litellm:x"\nprice = {input = nan, output = 1e-6}',
            "adapter 1.price.input: must be a finite number >= 0, got nan",
        ),
    ],
)
def test_bad_run_files_name_the_field(tmp_path: Path, text: str, field: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(BadInput, match=r"bad\.toml") as caught:
        read_run_file(path, AdapterOptions(), {})
    assert field in str(caught.value) and "\n" not in str(caught.value)


def test_a_run_file_entry_that_is_not_a_table_is_one_line_exit_2(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path
) -> None:
    config = tmp_path / "sweep.toml"
    for text, field in [
        ('adapter = ["baseline:stasis"]', "adapter 1: expected an [[adapter]] table"),
        ('defaults = 3\n[[adapter]]\nspec = "baseline:stasis"', "defaults: expected a"),
    ]:
        config.write_text(text)
        done = run_bpb("run", "--data", str(dataset), "--out", str(tmp_path / "runs"),
                       "--config", str(config))  # fmt: skip
        assert done.returncode == 2, done.stderr
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"error: {config}: {field}"), lines
        assert not (tmp_path / "runs").exists()


def test_an_adapter_without_option_sets_labelled_twice_is_told_to_be_given_once(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path
) -> None:
    config = tmp_path / "sweep.toml"
    config.write_text(
        '[defaults]\nspec = "baseline:stasis"\n[[adapter]]\nlabel = "a"\n[[adapter]]\nlabel = "b"\n'
    )
    done = run_bpb("run", "--data", str(dataset), "--out", str(tmp_path / "runs"),
                   "--config", str(config))  # fmt: skip
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "given twice; this adapter does not name its runs by label" in lines[0]
    assert "add a label" not in lines[0]  # both have one: that advice could not help
    assert not (tmp_path / "runs").exists()


def test_model_args_parse_json_values_and_nest_dotted_keys() -> None:
    items = ["reasoning_effort=high", "max_tokens=16000", "thinking.budget_tokens=8000",
             "thinking.type=enabled", 'stop=["END"]', "extra_headers.x-a=1"]  # fmt: skip
    parsed = model_args(items)
    assert parsed == {
        "reasoning_effort": "high",
        "max_tokens": 16000,
        "thinking": {"budget_tokens": 8000, "type": "enabled"},
        "stop": ["END"],
        "extra_headers": {"x-a": 1},
    }
    for bad in ("noequals", "=1", "a..b=1"):
        with pytest.raises(BadInput, match="--model-arg"):
            model_args([bad])
    # JSON has no NaN or infinity: sent, every call failed slowly as an api_error
    for bad, where in [("temperature=NaN", "temperature"), ("top_p=Infinity", "top_p"),
                       ("thinking.budget_tokens=-Infinity", "thinking.budget_tokens"),
                       ("stop=[1, NaN]", "stop[1]")]:  # fmt: skip
        with pytest.raises(BadInput, match=rf"--model-arg '{re.escape(bad)}': {re.escape(where)} "):
            model_args([bad])


KEYS = st.from_regex(r"[a-z_][a-z0-9_-]{0,11}", fullmatch=True)
FINITE = st.floats(allow_nan=False, allow_infinity=False)  # JSON has neither: refused
VALUES = st.one_of(st.integers(), st.booleans(), st.text(max_size=20), FINITE)


@given(st.dictionaries(KEYS, VALUES, max_size=5))
def test_model_args_round_trip_any_json_value(args: dict[str, object]) -> None:
    items = [f"{key}={json.dumps(value)}" for key, value in args.items()]
    assert model_args(items) == args


@pytest.mark.slow
def test_resume_with_other_model_arguments_is_refused(
    run_bpb: RunBpb, dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from support.fake_openai import fake_server

    monkeypatch.setenv("OPENAI_API_KEY", "sk-bpbtest-0123456789abcdefSECRET")
    with fake_server(dataset) as server:
        base = ["run", "--data", str(dataset), "--out", str(tmp_path), "--limit", "1",
                "--api-base", server.api_base, "--adapter", "litellm:openai/fake"]  # fmt: skip
        first = run_bpb(*base, "--model-arg", "top_p=0.5")
        assert first.returncode == 0, first.stderr
        folder = tmp_path / "litellm_openai_fake_top_p=0.5"
        manifest = json.loads((folder / "run.json").read_text())
        assert manifest["adapter_settings"]["model_args"] == {"top_p": 0.5}
        # Same folder name through an explicit label, other arguments: refused, nothing sent.
        sent = server.stats()["total"]
        config = tmp_path / "other.toml"
        config.write_text(
            f'[[adapter]]\nspec = "litellm:openai/fake"\nlabel = "top_p=0.5"\n'
            f'api_base = "{server.api_base}"\nargs = {{top_p = 0.9}}\n'
        )
        again = run_bpb("run", "--data", str(dataset), "--out", str(tmp_path), "--limit", "1",
                        "--config", str(config))  # fmt: skip
        assert again.returncode == 2 and "adapter_settings" in again.stderr
        assert server.stats()["total"] == sent
