#!/usr/bin/env bash
# Downloads the real TUM RGB-D sequences of the DDL-SLAM paper's Table 1 (freiburg3, dynamic
# scenes) and prints the `ddl_slam bench` command that computes Tables 1-3 on them
# (docs/evaluation.md, "Benchmark: ddl_slam bench"). Needs internet access and about 2.5 GB of
# disk (archives are removed after extraction unless --keep-archives).
#
# Sequences (TUM RGB-D benchmark, Sturm et al., IROS 2012, CC BY 4.0):
#   rgbd_dataset_freiburg3_walking_xyz, _walking_static, _walking_rpy, _walking_halfsphere,
#   rgbd_dataset_freiburg3_sitting_static
# and with --all also the other sequences the synthetic presets mirror (docs/synthetic.md):
#   rgbd_dataset_freiburg3_sitting_halfsphere, rgbd_dataset_freiburg2_desk_with_person
# from https://cvg.cit.tum.de/rgbd/dataset/freiburgN/<name>.tgz (the official download location;
# the older host vision.in.tum.de serves the same paths and is tried when the first one fails).
#
# Usage: scripts/download-tum.sh [--out DIR] [--all] [--keep-archives] [--dry-run] [--ddl-slam PATH]
#   --out DIR         where the sequence folders go (default: data/tum in the repository; a
#                     relative DIR is taken from the folder you run the script in)
#   --all             also the two sequences above that are not in the paper's Table 1
#   --keep-archives   keep the .tgz files next to the folders
#   --dry-run         print the URLs and the bench command, download nothing
#   --ddl-slam PATH   the binary shown in the bench command (default build/release/apps/ddl_slam)
# A sequence whose folder already holds its lists and the last image each names is not downloaded
# again (a folder left half unpacked is).
set -euo pipefail
caller_dir="$PWD"
repo="$(cd "$(dirname "$0")/.." && pwd)"

out="$repo/data/tum"
all=0
keep=0
dry_run=0
ddl_slam="$repo/build/release/apps/ddl_slam"
from_caller() {  # a path as given on the command line, absolute
  case "$1" in /*) echo "$1" ;; *) echo "$caller_dir/$1" ;; esac
}
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$(from_caller "$2")"; shift 2 ;;
    --all) all=1; shift ;;
    --keep-archives) keep=1; shift ;;
    --dry-run) dry_run=1; shift ;;
    --ddl-slam) ddl_slam="$(from_caller "$2")"; shift 2 ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    *) echo "download-tum: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done

sequences=(
  rgbd_dataset_freiburg3_walking_xyz
  rgbd_dataset_freiburg3_walking_static
  rgbd_dataset_freiburg3_walking_rpy
  rgbd_dataset_freiburg3_walking_halfsphere
  rgbd_dataset_freiburg3_sitting_static
)
if [ "$all" = 1 ]; then
  sequences+=(rgbd_dataset_freiburg3_sitting_halfsphere rgbd_dataset_freiburg2_desk_with_person)
fi
hosts=(https://cvg.cit.tum.de https://vision.in.tum.de)

fetch() {  # fetch URL FILE
  if command -v curl > /dev/null; then
    curl --fail --location --retry 3 --continue-at - --output "$2" "$1"
  elif command -v wget > /dev/null; then
    wget --tries=3 --continue --output-document="$2" "$1"
  else
    echo "download-tum: neither curl nor wget is installed" >&2
    exit 1
  fi
}

complete() {  # complete DIR: its lists, and the last image each of them names
  local dir="$1" list last
  [ -f "$dir/groundtruth.txt" ] || return 1
  for list in rgb.txt depth.txt; do
    [ -f "$dir/$list" ] || return 1
    last="$(grep -v '^#' "$dir/$list" | awk 'NF >= 2 { f = $2 } END { print f }')"
    [ -n "$last" ] && [ -f "$dir/$last" ] || return 1
  done
}

[ "$dry_run" = 1 ] || mkdir -p "$out"
for name in "${sequences[@]}"; do
  dir="$out/$name"
  if complete "$dir"; then
    echo "$name: already in $dir"
    continue
  fi
  archive="$out/$name.tgz"
  freiburg="${name#rgbd_dataset_}"
  freiburg="${freiburg%%_*}"  # freiburg1, freiburg2 or freiburg3
  if [ "$dry_run" = 1 ]; then
    echo "$name: ${hosts[0]}/rgbd/dataset/$freiburg/$name.tgz -> $dir"
    continue
  fi
  ok=0
  for host in "${hosts[@]}"; do
    url="$host/rgbd/dataset/$freiburg/$name.tgz"
    echo "$name: downloading $url"
    if fetch "$url" "$archive"; then
      ok=1
      break
    fi
    echo "download-tum: $url failed, trying the next host" >&2
  done
  if [ "$ok" = 0 ]; then
    echo "download-tum: could not download $name (no internet access?)" >&2
    exit 1
  fi
  if ! tar -xzf "$archive" -C "$out"; then
    # A download that saved an error page (or was cut) would be resumed onto, never replaced.
    rm -f "$archive"
    echo "download-tum: $archive is not a complete .tgz archive; removed it, run again" >&2
    exit 1
  fi
  if ! complete "$dir"; then
    echo "download-tum: $archive did not unpack into $dir with its lists and images" >&2
    exit 1
  fi
  [ "$keep" = 1 ] || rm -f "$archive"
done

# Shell-quoted, so that the commands below can be pasted even where a path holds a space.
q_bin="$(printf '%q' "$ddl_slam")"
q_out="$(printf '%q' "$out")"
q_res="$(printf '%q' "$repo/out/bench-tum")"
cat <<MSG

The sequences are in $out. Tables 1-3 (ATE, RPE translational and rotational, ORB-SLAM2 column =
--no-dynamic, improvement in %; each folder's camera follows from its name, freiburg3 -> tum3):

  $q_bin bench --suite $q_out --out $q_res

or a selection:

  $q_bin bench --out $q_res \\
      --sequences $q_out/rgbd_dataset_freiburg3_walking_xyz $q_out/rgbd_dataset_freiburg3_sitting_static

Results: $repo/out/bench-tum/tables.md and tables.json (docs/evaluation.md). The real sequences have no
ground-truth masks, so the mask table stays empty.
MSG
