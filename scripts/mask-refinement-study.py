#!/usr/bin/env python3
"""Offline study of the combined mask's edge refinement (dynamic.edge_refinement).

Reads the combined masks that a run saved (ddl_slam run SEQ --save-masks --out RUN, best with
`dynamic: {edge_refinement: {enabled: false}}` so they are the sources' union), refines them with
variants of the iterated guided filter of dynamics/mask_edge_refinement.cc (OpenCV's ximgproc,
as the C++ code) and prints the mean IoU of each against the sequence's ground-truth dynamic masks
(void pixels excluded, frames without people skipped, as ddl_slam's mask evaluation), and its
gain over the saved masks, per sequence:

  scripts/mask-refinement-study.py --step 6 data/suite/composite_fr1_rpy_walking out/comp \\
      data/suite/syn_desk_person out/desk

The ground-truth masks are read in the sequence's image grid and undistorted with its
camera.yaml (nearest neighbour) onto the grid of the saved masks, as ddl_slam undistorts frames.
docs/dynamics.md, "Edge refinement", has the table this prints. Needs python3-opencv (Debian's
is built with the contrib modules) and python3-numpy.
"""
import argparse
import os
import re

import cv2
import numpy as np

EPS = 1e-4 * 255.0 * 255.0  # dynamic.edge_refinement.eps in the 8-bit guide's units
THRESHOLD = 0.45


def refine(bgr, mask, radii_px, scale=0.5, guide='colour'):
    """The C++ refinement on the whole image: passes thresholded at `scale`."""
    h, w = mask.shape
    size = (int(round(w * scale)), int(round(h * scale)))
    image = bgr if guide == 'colour' else cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    small = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    soft = cv2.resize(mask.astype(np.float32), size, interpolation=cv2.INTER_AREA)
    for radius in radii_px:
        filtered = cv2.ximgproc.guidedFilter(small, soft, max(1, int(round(radius * scale))), EPS)
        soft = (filtered > THRESHOLD).astype(np.float32)
    return cv2.resize(filtered, (w, h), interpolation=cv2.INTER_LINEAR) > THRESHOLD


VARIANTS = {
    'one pass, 12 px': lambda b, m: refine(b, m, [12]),
    'one pass, 16 px': lambda b, m: refine(b, m, [16]),
    'one pass, 20 px': lambda b, m: refine(b, m, [20]),
    '16 px, then 8 px': lambda b, m: refine(b, m, [16, 8]),
    '16 px, then three of 8 px': lambda b, m: refine(b, m, [16, 8, 8, 8]),
    'the same at 0.375 (default)': lambda b, m: refine(b, m, [16, 8, 8, 8], scale=0.375),
    '16 px, then seven of 8 px': lambda b, m: refine(b, m, [16] + [8] * 7),
    'grey guide, 16 then 3x8 px': lambda b, m: refine(b, m, [16, 8, 8, 8], guide='grey'),
    'dilated by 2 px': lambda b, m: cv2.dilate(m.astype(np.uint8), cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (5, 5))) > 0,
}


def listing(path):
    if not os.path.exists(path):
        return []
    return [line.split() for line in open(path) if line.strip() and not line.startswith('#')]


def undistortion(seq):
    text = open(os.path.join(seq, 'camera.yaml')).read()
    value = lambda key: float(re.search(r'\b%s:\s*([-\d.eE+]+)' % key, text).group(1))
    k = np.array([[value('fx'), 0, value('cx')], [0, value('fy'), value('cy')], [0, 0, 1]])
    d = np.array([float(x) for x in
                  re.search(r'distortion:\s*\[([^\]]*)\]', text).group(1).split(',')])
    size = (int(value('width')), int(value('height')))
    mx, my = cv2.initUndistortRectifyMap(k, d, None, k, size, cv2.CV_32FC1)
    return lambda im, interp=cv2.INTER_NEAREST: cv2.remap(im, mx, my, interp,
                                                          borderMode=cv2.BORDER_CONSTANT)


def iou(mask, truth, void):
    mask, truth = mask & ~void, truth & ~void
    union = (mask | truth).sum()
    return (mask & truth).sum() / union if union else 1.0


def study(seq, run, step):
    und = undistortion(seq)
    rgb = dict(listing(os.path.join(seq, 'rgb.txt')))
    void = dict(listing(os.path.join(seq, 'void_mask.txt')))
    scores = {'saved': []}
    for index, (stamp, truth_file) in enumerate(listing(os.path.join(seq, 'dynamic_mask.txt'))):
        saved = os.path.join(run, 'masks', stamp + '.png')
        if index % step or not os.path.exists(saved):
            continue
        truth = und(cv2.imread(os.path.join(seq, truth_file), cv2.IMREAD_GRAYSCALE)) > 0
        if not truth.any():
            continue
        voids = (und(cv2.imread(os.path.join(seq, void[stamp]), cv2.IMREAD_GRAYSCALE)) > 0
                 if stamp in void else np.zeros_like(truth))
        bgr = und(cv2.imread(os.path.join(seq, rgb[stamp])), cv2.INTER_LINEAR)
        mask = cv2.imread(saved, cv2.IMREAD_GRAYSCALE) > 0
        scores['saved'].append(iou(mask, truth, voids))
        for name, variant in VARIANTS.items():
            scores.setdefault(name, []).append(iou(variant(bgr, mask), truth, voids))
    return {name: float(np.mean(values)) for name, values in scores.items() if values}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('pairs', nargs='+', help='SEQ RUN pairs: sequence folder, run output')
    parser.add_argument('--step', type=int, default=6, help='every STEP-th frame (default 6)')
    args = parser.parse_args()
    if len(args.pairs) % 2:
        parser.error('give sequence folders and run folders in pairs')
    for seq, run in zip(args.pairs[::2], args.pairs[1::2]):
        result = study(seq, run, args.step)
        if not result:
            print(f'{seq}: no saved mask of a frame with people in {run}/masks')
            continue
        base = result['saved']
        print(f'{os.path.basename(os.path.normpath(seq))}: saved masks {base:.4f}')
        for name, value in result.items():
            if name != 'saved':
                print(f'  {name:32s} {value:.4f} ({value - base:+.4f})')


if __name__ == '__main__':
    main()
