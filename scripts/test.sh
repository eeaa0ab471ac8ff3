#!/usr/bin/env bash
# Sets up llm-grop with its test tools from scratch, then runs the linter and the tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --dev
.venv/bin/ruff check src tests benchmarks
.venv/bin/python -m pytest -q "$@"
