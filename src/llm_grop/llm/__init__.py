"""Language models behind one interface: text in, text out, with metadata.

Nothing here knows about tables or planning.
"""

from llm_grop.llm.base import LLM, BackendOptions, CallLog, SamplingParams
from llm_grop.llm.record import LLMCallRecord
from llm_grop.llm.registry import available_backends, create_llm, register_backend

__all__ = [
    "LLM",
    "BackendOptions",
    "CallLog",
    "LLMCallRecord",
    "SamplingParams",
    "available_backends",
    "create_llm",
    "register_backend",
]
