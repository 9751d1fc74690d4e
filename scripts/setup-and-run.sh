#!/usr/bin/env bash
# The README's first command: installs the dependencies (apt), builds the release preset and runs
# the main job on its built-in default, writing everything under out/default/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release
cmake --build --preset release -j "$(nproc)"
bash scripts/run-default.sh "${1:-out/default}"
