#!/usr/bin/env bash
# The main job on the built-in default (no download needed). Usage: run-default.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/default}"
bin=build/release/apps/ddl_slam
mkdir -p "$out"
"$bin" eval --gt examples/eval/groundtruth.txt --est examples/eval/estimate.txt \
  --json "$out/eval.json" --plot-dir "$out/plots"
echo "outputs in $out"
