#!/usr/bin/env python3
"""Write a jerky version of a TUM-layout sequence: abrupt changes of the camera's speed.

The source frames are taken in a repeating pattern of segments COUNTxSTEP (COUNT frames, each
STEP source frames after the previous one) and stamped again at the source's median frame
interval. With the pattern 40x1,20x3 the camera moves at its own speed for 40 frames, then three
times as fast for 20, and so on: its velocity triples and drops back within one frame interval,
which a constant-velocity motion model (and its prior, docs/tracking.md) does not predict.

The new folder links the source's rgb/ and depth/ (and camera.yaml, accelerometer-free) and
writes associations.txt, rgb.txt, depth.txt and groundtruth.txt. Each frame keeps the time
between its RGB and depth images. Its ground truth is the source's ground-truth pose nearest to
the source RGB stamp (within 10 ms; frames without one get none, as in TUM's own files).

With --keep-stamps the frames keep their own stamps instead (and groundtruth.txt is the source's,
linked): --pattern 1x2 gives every second frame, a 15 Hz stream from a 30 Hz one.

With --glitch-every N every Nth frame is stamped 1 ms after the frame before it (its depth stamp
moves with it), as a camera driver's timestamp glitch would: the image is still the one taken a
whole interval later. With --keep-stamps its ground truth is then looked up at the wrong stamp
too, which both runs of a comparison share.

Usage:
  scripts/resample-sequence.py SOURCE_DIR OUT_DIR --pattern 40x1,20x3
  scripts/resample-sequence.py SOURCE_DIR OUT_DIR --pattern 1x3 --keep-stamps
  scripts/resample-sequence.py SOURCE_DIR OUT_DIR --pattern 1x1 --keep-stamps --glitch-every 50
The source needs associations.txt (ddl_slam synth writes one; for a TUM download, TUM's
associate.py rgb.txt depth.txt > associations.txt) and groundtruth.txt. Standard library only.
"""
import argparse
import bisect
import os
import statistics
import sys


def fail(message):
    print(f"resample-sequence: {message}", file=sys.stderr)
    sys.exit(2)


def read_rows(path, min_fields):
    rows = []
    try:
        with open(path) as f:
            for number, line in enumerate(f, 1):
                if line.startswith("#") or not line.strip():
                    continue
                fields = line.split()
                if len(fields) < min_fields:
                    fail(f"{path}:{number}: expected {min_fields} fields, found {len(fields)}")
                try:
                    float(fields[0])
                except ValueError:
                    fail(f"{path}:{number}: timestamp '{fields[0]}' is not a number")
                rows.append(fields)
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    if not rows:
        fail(f"{path}: no entries")
    return rows


def parse_pattern(text):
    segments = []
    for part in text.split(","):
        try:
            count, step = (int(v) for v in part.lower().split("x"))
        except ValueError:
            fail(f"--pattern: '{part}' is not COUNTxSTEP (e.g. 40x1)")
        if count < 1 or step < 1:
            fail(f"--pattern: '{part}': count and step must be at least 1 (a repeated frame "
                 "would pair one image twice)")
        segments.append((count, step))
    return segments


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("source", help="TUM-layout sequence folder")
    parser.add_argument("out", help="folder to write (created; its listed files are replaced)")
    parser.add_argument("--pattern", required=True, help="segments COUNTxSTEP, e.g. 40x1,20x3")
    parser.add_argument("--keep-stamps", action="store_true",
                        help="keep each frame's own stamps (a lower frame rate, not a jerk)")
    parser.add_argument("--glitch-every", type=int, default=0, metavar="N",
                        help="stamp every Nth frame 1 ms after the one before (0: none)")
    args = parser.parse_args()
    if args.glitch_every < 0 or args.glitch_every == 1:
        fail("--glitch-every: N must be 0 (none) or at least 2 (the first frame has no "
             "frame before it)")
    segments = parse_pattern(args.pattern)

    assoc = read_rows(os.path.join(args.source, "associations.txt"), 4)
    truth = read_rows(os.path.join(args.source, "groundtruth.txt"), 8)
    truth_stamps = [float(r[0]) for r in truth]
    if len(assoc) < 2:
        fail(f"{args.source}/associations.txt: needs at least two frames")
    interval = statistics.median(float(b[0]) - float(a[0]) for a, b in zip(assoc, assoc[1:]))
    if interval <= 0.0:
        fail(f"{args.source}/associations.txt: stamps do not increase")

    chosen, i = [], 0
    while i < len(assoc):
        for count, step in segments:
            for _ in range(count):
                if i >= len(assoc):
                    break
                chosen.append(i)
                i += step

    os.makedirs(args.out, exist_ok=True)
    for name in ("rgb", "depth", "camera.yaml"):
        src = os.path.abspath(os.path.join(args.source, name))
        dst = os.path.join(args.out, name)
        if os.path.exists(src) and not os.path.lexists(dst):
            os.symlink(src, dst)

    t0 = float(assoc[0][0])
    without_truth = 0
    paths = {n: os.path.join(args.out, n + ".txt")
             for n in ("associations", "rgb", "depth", "groundtruth")}
    if os.path.lexists(paths["groundtruth"]):
        os.remove(paths["groundtruth"])
    if args.keep_stamps:  # the source's ground truth holds for the same stamps
        os.symlink(os.path.abspath(os.path.join(args.source, "groundtruth.txt")),
                   paths["groundtruth"])
    truth_lines = []  # re-stamped ground truth (not with --keep-stamps)
    with open(paths["associations"], "w") as fa, open(paths["rgb"], "w") as fr, \
            open(paths["depth"], "w") as fd:
        fr.write("# timestamp filename\n")
        fd.write("# timestamp filename\n")
        previous_t = previous_t_depth = None
        glitches = 0
        for k, j in enumerate(chosen):
            rgb_stamp, rgb_file, depth_stamp, depth_file = assoc[j][:4]
            t = t0 + k * interval if not args.keep_stamps else float(rgb_stamp)
            glitch = args.glitch_every and k % args.glitch_every == args.glitch_every - 1
            if glitch:
                t = previous_t + 0.001
                glitches += 1
            source_t = float(rgb_stamp)
            if not args.keep_stamps or t != source_t:
                t_depth = t + (float(depth_stamp) - float(rgb_stamp))
                if glitch and t_depth <= previous_t_depth:
                    # Depth taken earlier than the last frame's: keep the glitched depth stamp
                    # after the last one (1 ms after it).
                    t_depth = previous_t_depth + 0.001
                rgb_stamp, depth_stamp = f"{t:.6f}", f"{t_depth:.6f}"
            if not args.keep_stamps:
                p = bisect.bisect_left(truth_stamps, source_t)
                near = min((q for q in (p - 1, p) if 0 <= q < len(truth_stamps)),
                           key=lambda q: abs(truth_stamps[q] - source_t))
                if abs(truth_stamps[near] - source_t) > 0.01:
                    without_truth += 1
                else:
                    truth_lines.append(f"{rgb_stamp} " + " ".join(truth[near][1:8]) + "\n")
            previous_t, previous_t_depth = float(rgb_stamp), float(depth_stamp)
            fa.write(f"{rgb_stamp} {rgb_file} {depth_stamp} {depth_file}\n")
            fr.write(f"{rgb_stamp} {rgb_file}\n")
            fd.write(f"{depth_stamp} {depth_file}\n")
    if not args.keep_stamps:
        with open(paths["groundtruth"], "w") as fg:
            fg.write(f"# resampled from {os.path.abspath(args.source)} "
                     f"with --pattern {args.pattern}\n")
            fg.write("# timestamp tx ty tz qx qy qz qw\n")
            fg.writelines(truth_lines)
    stamps = ("own stamps, the source's ground truth" if args.keep_stamps
              else f"stamped every {interval * 1000:.1f} ms, {without_truth} without ground truth")
    if args.glitch_every:
        stamps += f", {glitches} stamped 1 ms after the frame before"
    print(f"{args.out}: {len(chosen)} frames from {chosen[-1] + 1} source frames, {stamps}")


if __name__ == "__main__":
    main()
