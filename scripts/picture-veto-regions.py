#!/usr/bin/env python3
"""Offline check of the picture veto (dynamics::drop_pictures, docs/dynamics.md "Pictures") on
the CNN masks a run saved: for every connected region of <run>/masks/cnn/*.png, is it a person
(at least half of it inside the sequence's dynamic_mask/) and would the rule drop it?

A re-implementation in Python of the C++ rule with its default settings, for measuring on saved
masks without re-running the pipeline; the flood is an iterated constrained dilation, so region
by region it matches the C++ breadth-first flood (8-neighbours, reach in steps). The masks must
come from a run with the veto off (`dynamic.picture_veto.enabled: false`, or a build before it)
and the default CNN schedule: only the masks of frames the network ran on (every second frame
from the first) are judged, as in the pipeline, and the reused masks between them are skipped.
Depth and ground truth are undistorted as the pipeline does it (camera.yaml's distortion,
nearest neighbour); the blank margin that leaves is no depth hole (--margin-is-hole: as before
stop 23). The flood budget (max_flood_pixels) is not modelled. It needs python3-opencv
and python3-numpy (apt). Slow: about 0.5-1 s per frame.

  python3 scripts/picture-veto-regions.py data/syn_static_loop out/loop/masks/cnn [--step 2]

Prints the true and false regions (and pixels) the rule drops.
"""
import argparse
import glob
import os
import re

import cv2
import numpy as np

CONT_M, CONT_Q, WIN, EDGE_M, EDGE_Q, MIN_NEAR = 0.03, 0.02, 3, 0.05, 0.03, 10


def read_list(path):
    out = {}
    if os.path.exists(path):
        for line in open(path):
            if line.startswith("#") or not line.strip():
                continue
            stamp, name = line.split()[:2]
            out[round(float(stamp), 4)] = name
    return out


def shifted(a, dy, dx, fill):
    """out[y, x] = a[y + dy, x + dx] (fill outside)."""
    out = np.full_like(a, fill)
    h, w = a.shape
    out[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)] = \
        a[max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)]
    return out


def near_side(depth, hole_px, area=None):
    valid = depth > 0
    k = 2 * WIN + 1
    farthest = cv2.dilate(depth, np.ones((k, k), np.uint8), borderType=cv2.BORDER_CONSTANT,
                          borderValue=0)
    near = valid & (farthest - depth > EDGE_M + EDGE_Q * depth * depth)
    if hole_px == 0:  # the first version: no hole rule
        return near
    h = 2 * hole_px + 1
    invalid = ~valid if area is None else ~valid & area  # the blank margin is no hole
    hole = cv2.erode(invalid.astype(np.uint8), np.ones((h, h), np.uint8),
                     borderType=cv2.BORDER_CONSTANT, borderValue=0)
    r = 2 * (hole_px + WIN) + 1
    beside = cv2.dilate(hole, np.ones((r, r), np.uint8)) > 0
    return near | (valid & beside)


def read_camera(path):
    """fx fy cx cy, distortion, size and depth_factor from a sequence's camera.yaml."""
    text = open(path).read()
    def number(key):
        return float(re.search(rf"^\s*{key}:\s*([-+0-9.eE]+)", text, re.M).group(1))
    dist = [float(x) for x in re.search(r"distortion:\s*\[([^\]]*)\]", text).group(1).split(",")]
    K = np.array([[number("fx"), 0, number("cx")], [0, number("fy"), number("cy")], [0, 0, 1]])
    return K, np.array(dist), (int(number("width")), int(number("height"))), number("depth_factor")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("sequence")
    ap.add_argument("cnn_masks")
    ap.add_argument("--step", type=int, default=1, help="every n-th frame the network ran on")
    ap.add_argument("--first-frame", type=int, default=0, help="the run's --first-frame")
    ap.add_argument("--interval", type=int, default=2, help="dynamic.segmentation_interval")
    ap.add_argument("--reach", type=int, default=80, help="picture_veto.reach_px")
    ap.add_argument("--hole-px", type=int, default=4, help="picture_veto.hole_px; 0 = no hole rule")
    ap.add_argument("--margin-is-hole", action="store_true",
                    help="count undistortion's blank margin as a depth hole (builds before stop 23)")
    args = ap.parse_args()
    assoc, index = {}, {}
    for line in open(os.path.join(args.sequence, "associations.txt")):
        if not line.startswith("#") and line.strip():
            f = line.split()
            key = round(float(f[0]), 4)
            assoc[key] = f[3]
            index[key] = len(index)
    K, dist, size, depth_factor = read_camera(os.path.join(args.sequence, "camera.yaml"))
    undistort = None
    sensor_area = None  # where an undistorted pixel has a stored pixel (Undistorter::source_area)
    if np.any(dist != 0):
        undistort = cv2.initUndistortRectifyMap(K, dist, None, K, size, cv2.CV_32FC1)
        if not args.margin_is_hole:
            sensor_area = cv2.remap(np.full((size[1], size[0]), 255, np.uint8), undistort[0],
                                    undistort[1], cv2.INTER_NEAREST,
                                    borderMode=cv2.BORDER_CONSTANT, borderValue=0) > 0
    truth = read_list(os.path.join(args.sequence, "dynamic_mask.txt"))
    steps = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
    rows = []
    fresh = []
    for path in sorted(glob.glob(os.path.join(args.cnn_masks, "*.png"))):
        key = round(float(os.path.basename(path)[:-4]), 4)
        if (index[key] - args.first_frame) % args.interval == 0:
            fresh.append((path, key))
    for path, key in fresh[::args.step]:
        mask = cv2.imread(path, cv2.IMREAD_GRAYSCALE) > 0
        depth = cv2.imread(os.path.join(args.sequence, assoc[key]),
                           cv2.IMREAD_UNCHANGED).astype(np.float32) / depth_factor
        gt = cv2.imread(os.path.join(args.sequence, truth[key]), cv2.IMREAD_GRAYSCALE)
        if undistort is not None:
            depth = cv2.remap(depth, undistort[0], undistort[1], cv2.INTER_NEAREST,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=0)
            gt = cv2.remap(gt, undistort[0], undistort[1], cv2.INTER_NEAREST,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        gt = gt > 0
        valid = depth > 0
        near = near_side(depth, args.hole_px, sensor_area)
        tolerance = CONT_M + CONT_Q * depth * depth
        # neighbour_ok[s][p]: p may be reached from p + s (the tolerance is that of p + s).
        neighbour_ok = {s: np.abs(depth - shifted(depth, s[0], s[1], 0))
                        < shifted(tolerance, s[0], s[1], 0) for s in steps}
        count, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
        for label in range(1, count):
            region = labels == label
            reached = region & valid
            if not reached.any():
                continue
            for _ in range(args.reach):
                if (reached & near).sum() >= MIN_NEAR:
                    break
                grown = np.zeros_like(reached)
                for s in steps:
                    grown |= shifted(reached, s[0], s[1], False) & neighbour_ok[s]
                grown &= valid & ~reached
                if not grown.any():
                    break
                reached |= grown
            area = int(region.sum())
            rows.append((area, (region & gt).sum() / area >= 0.5, int((reached & near).sum()) < MIN_NEAR))
    rows = np.array(rows, dtype=np.int64).reshape(-1, 3)
    person, dropped = rows[:, 1] == 1, rows[:, 2] == 1
    print(f"{os.path.basename(os.path.normpath(args.sequence))}: "
          f"true regions dropped {(person & dropped).sum()} of {person.sum()} "
          f"({rows[person & dropped, 0].sum()} of {rows[person, 0].sum()} px); "
          f"false regions dropped {(~person & dropped).sum()} of {(~person).sum()} "
          f"({rows[~person & dropped, 0].sum()} of {rows[~person, 0].sum()} px)")


if __name__ == "__main__":
    main()
