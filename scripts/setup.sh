#!/usr/bin/env bash
# Sets up llm-grop from scratch in ./.venv: system packages, a portable
# llama-cpp-python build, and the package itself.  Usage: scripts/setup.sh [--dev]
set -euo pipefail
cd "$(dirname "$0")/.."

extras=""
[ "${1:-}" = "--dev" ] && extras="[dev]"

need_apt=()
command -v cmake >/dev/null || need_apt+=(cmake)
command -v g++ >/dev/null || need_apt+=(g++)
command -v make >/dev/null || need_apt+=(make)
python3 -c "import venv, ensurepip" 2>/dev/null || need_apt+=(python3-venv)
# MuJoCo renders offscreen through OSMesa (pictures and videos of the 3D simulator).
ldconfig -p 2>/dev/null | grep -q libOSMesa || need_apt+=(libosmesa6)
if [ -n "$extras" ]; then
    # The rating website's browser test drives Debian's Chromium; a browser is never
    # downloaded. Liberation fonts make its screenshots look as they do for users.
    [ -x /usr/bin/chromium ] || need_apt+=(chromium chromium-driver)
    dpkg -s fonts-liberation >/dev/null 2>&1 || need_apt+=(fonts-liberation)
fi
if [ ${#need_apt[@]} -gt 0 ]; then
    sudo_cmd=""
    [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
    echo "setup: installing system packages: ${need_apt[*]}"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need_apt[@]}" python3-dev
fi

python=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$python" -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip

# llama-cpp-python is built from source; the default -march=native build
# crashes on CPUs with AMX, so it is built portably into a wheelhouse of our
# own (pip's own cache may hold a native build).
wheelhouse="${LLM_GROP_WHEELHOUSE:-$HOME/.cache/llm-grop/wheels}"
llama_version="0.3.36"
if ! .venv/bin/python -c "import llama_cpp" 2>/dev/null; then
    mkdir -p "$wheelhouse"
    if ! ls "$wheelhouse"/llama_cpp_python-"$llama_version"-*.whl >/dev/null 2>&1; then
        echo "setup: building llama-cpp-python $llama_version portably (about 4 minutes)"
        CMAKE_ARGS="-DGGML_NATIVE=OFF -DGGML_AVX2=ON -DGGML_FMA=ON -DGGML_F16C=ON -DLLAVA_BUILD=OFF" \
            .venv/bin/python -m pip wheel -q --no-cache-dir --no-deps \
            "llama-cpp-python==$llama_version" -w "$wheelhouse"
    fi
    .venv/bin/python -m pip install -q "$wheelhouse"/llama_cpp_python-"$llama_version"-*.whl
fi

.venv/bin/python -m pip install -q -e ".$extras"
echo "setup: done; the command is .venv/bin/llm-grop"
