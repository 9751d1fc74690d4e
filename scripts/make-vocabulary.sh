#!/usr/bin/env bash
# Trains DDL-SLAM's default ORB vocabulary (docs/vocabulary.md) with `ddl_slam vocab train`.
#
# Training images (none from the TUM evaluation sequences):
#   - the 599 CCP photographs of people in streets, <shared>/data/people/ccp/images (Apache-2.0);
#   - the real photographs among Debian opencv-doc's example images (listed below): indoor office
#     and desk scenes (left*/right* calibration shots, home, stuff, box_in_scene, rubberwhale),
#     buildings, objects, aerial views. Left out: drawings, renders and synthetic graphics, the
#     basketball photos (segmentation test images) and the four posters of the synthetic scene
#     generator (board, fruits, starry_night, graf1), so no evaluation texture is trained on.
#
# Usage: scripts/make-vocabulary.sh [--ddl-slam PATH] [--levels 5|6] [--out FILE] [--threads N]
# Environment: DDL_SHARED_DIR (default ../shared relative to the repository).
set -euo pipefail
cd "$(dirname "$0")/.."

ddl_slam=build/release/apps/ddl_slam
levels=5
out=""
threads=2
while [ $# -gt 0 ]; do
  case "$1" in
    --ddl-slam) ddl_slam="$2"; shift 2 ;;
    --levels) levels="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
    *) echo "make-vocabulary: unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -n "$out" ] || out="vocab/ddl_orb_k10_l${levels}.dvoc"
shared="${DDL_SHARED_DIR:-../shared}"
ccp="$shared/data/people/ccp/images"
opencv_data=/usr/share/doc/opencv-doc/examples/data

[ -x "$ddl_slam" ] || { echo "make-vocabulary: $ddl_slam not found; build it first" >&2; exit 2; }
[ -d "$ccp" ] || { echo "make-vocabulary: $ccp not found (set DDL_SHARED_DIR)" >&2; exit 2; }
[ -d "$opencv_data" ] || { echo "make-vocabulary: $opencv_data not found (apt-get install opencv-doc)" >&2; exit 2; }

opencv_photos=(
  aero1.jpg aero3.jpg aloeL.jpg aloeR.jpg apple.jpg baboon.jpg box.png box_in_scene.png
  building.jpg butterfly.jpg chicky_512.png ela_original.jpg home.jpg
  left.jpg left01.jpg left02.jpg left03.jpg left04.jpg left05.jpg left06.jpg left07.jpg
  left08.jpg left09.jpg left11.jpg left12.jpg left13.jpg left14.jpg
  right.jpg right01.jpg right02.jpg right03.jpg right04.jpg right05.jpg right06.jpg right07.jpg
  right08.jpg right09.jpg right11.jpg right12.jpg right13.jpg right14.jpg
  leuvenA.jpg leuvenB.jpg licenseplate_motion.jpg messi5.jpg orange.jpg rubberwhale1.png
  rubberwhale2.png squirrel_cls.jpg stuff.jpg sudoku.png
)
list="$(mktemp --suffix=.txt)"
trap 'rm -f "$list"' EXIT
for f in "${opencv_photos[@]}"; do
  [ -f "$opencv_data/$f" ] || { echo "make-vocabulary: missing $opencv_data/$f" >&2; exit 2; }
  echo "$opencv_data/$f" >> "$list"
done

mkdir -p "$(dirname "$out")"
"$ddl_slam" vocab train --images "$ccp" "$list" --features 1000 --k 10 --levels "$levels" \
  --seed 1 --threads "$threads" --out "$out"
"$ddl_slam" vocab info "$out"
