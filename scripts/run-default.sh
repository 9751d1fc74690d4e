#!/usr/bin/env bash
# The main job on the built-in default, no download needed: generates a dynamic sequence (two
# people walking in a synthetic room, camera moving along x/y/z; exact ground truth), runs
# DDL-SLAM on it and evaluates the trajectory. Usage: run-default.sh [OUT_DIR] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/default}"
frames="${2:-300}"
bin=build/release/apps/ddl_slam
mkdir -p "$out"
"$bin" synth --preset syn_walking_xyz --frames "$frames" --out "$out/syn_walking_xyz"
"$bin" run "$out/syn_walking_xyz" --out "$out/run" --save-inpainted
echo
echo "trajectory: $out/run/CameraTrajectory.txt, summary: $out/run/summary.json"
echo "evaluation: $out/run/eval/ (eval.json, plots), map: $out/run/map.ot, $out/run/map_top.png"
