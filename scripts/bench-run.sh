#!/usr/bin/env bash
# Repeated-run benchmark of `ddl_slam run`: runs one sequence N times with the same arguments and
# prints a Markdown table of the figures the issues ask for (ATE/RPE, frames tracked, keyframes,
# per-stage medians from summary.json, frames per second, wall time, peak resident memory), then
# the median over the runs. Report the machine load (printed first) beside the figures.
#
#   scripts/bench-run.sh [-n RUNS] [-b BINARY] [-o OUTDIR] SEQUENCE [-- ddl_slam run options...]
#   scripts/bench-run.sh -n 3 ../shared/data/tum/rgbd_dataset_freiburg1_rpy -- --no-dynamic
#   scripts/bench-run.sh -n 3 data/syn_walking_xyz -- --mode threaded --max-frames 300
set -euo pipefail

runs=3
binary=build/release/apps/ddl_slam
outdir=out/bench-run
while getopts "n:b:o:h" opt; do
  case "$opt" in
    n) runs=$OPTARG ;;
    b) binary=$OPTARG ;;
    o) outdir=$OPTARG ;;
    h | *)
      sed -n 2,10p "$0"
      exit 2
      ;;
  esac
done
shift $((OPTIND - 1))
[[ $# -ge 1 ]] || { echo "bench-run.sh: missing SEQUENCE (see -h)" >&2; exit 2; }
sequence=$1
shift
[[ ${1:-} == "--" ]] && shift
[[ -x $binary ]] || { echo "bench-run.sh: $binary not found or not executable (build first)" >&2; exit 2; }
[[ -d $sequence ]] || { echo "bench-run.sh: sequence folder $sequence not found" >&2; exit 2; }
[[ $runs =~ ^[1-9][0-9]*$ ]] || { echo "bench-run.sh: -n must be a positive integer, got '$runs'" >&2; exit 2; }

echo "load before the runs: $(cut -d' ' -f1-3 /proc/loadavg) ($(nproc) cores)"
echo "command: $binary run $sequence --out $outdir/run<i> $*"
for ((i = 1; i <= runs; ++i)); do
  dir=$outdir/run$i
  rm -rf "$dir"
  mkdir -p "$dir"
  /usr/bin/time -f "%e %M" -o "$dir.time" "$binary" run "$sequence" --out "$dir" "$@" \
    >"$dir.log" 2>&1 || { echo "run $i failed, see $dir.log" >&2; tail -5 "$dir.log" >&2; exit 1; }
done

python3 - "$outdir" "$runs" <<'PY'
import json, statistics, sys
outdir, runs = sys.argv[1], int(sys.argv[2])

def get(d, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d or d[k] is None:
            return None
        d = d[k]
    return d

rows = []
for i in range(1, runs + 1):
    d = json.load(open(f"{outdir}/run{i}/summary.json"))
    wall_s, rss_kb = open(f"{outdir}/run{i}.time").read().split()
    t = d.get("timing_ms", {})
    med = lambda k: get(t, k, "median_ms")
    rows.append({
        "ate_m": get(d, "evaluation", "ate", "rmse_m"),
        "rpe_m_s": get(d, "evaluation", "rpe", "trans_rmse_m_per_s"),
        "rpe_deg_s": get(d, "evaluation", "rpe", "rot_rmse_deg_per_s"),
        "tracked": f'{get(d, "statistics", "frames_tracked")}/{get(d, "statistics", "frames")}',
        "keyframes": get(d, "statistics", "keyframes_created"),
        "loops": get(d, "statistics", "loops_closed"),
        "tracking_ms": med("tracking"),
        "features_ms": med("tracking.features"),
        "segmentation_ms": med("segmentation"),
        "geometry_ms": med("geometry_check"),
        "frame_ms": med("frame_total"),
        "fps": d.get("frames_per_second"),
        "tracking_fps": d.get("tracking_frames_per_second"),
        "wall_s": float(wall_s),
        "peak_mb": int(rss_kb) / 1024.0,
    })

cols = list(rows[0].keys())
fmt = lambda v: "-" if v is None else (str(int(v)) if isinstance(v, float) and v.is_integer() else
                                       f"{v:.4f}" if isinstance(v, float) and v < 1 else
                                       f"{v:.1f}" if isinstance(v, float) else str(v))
print("| run | " + " | ".join(cols) + " |")
print("|---" * (len(cols) + 1) + "|")
for i, r in enumerate(rows, 1):
    print(f"| {i} | " + " | ".join(fmt(r[c]) for c in cols) + " |")
medians = {}
for c in cols:
    vals = [r[c] for r in rows if isinstance(r[c], (int, float))]
    medians[c] = statistics.median(vals) if vals and len(vals) == len(rows) else None
print("| **median** | " + " | ".join(fmt(medians[c]) if medians[c] is not None else "" for c in cols) + " |")
json.dump({"runs": rows, "median": medians}, open(f"{outdir}/bench.json", "w"), indent=2)
print(f"written: {outdir}/bench.json")
PY
echo "load after the runs: $(cut -d' ' -f1-3 /proc/loadavg)"
