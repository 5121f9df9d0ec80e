"""The textbook people detectors that mvtrack-detect is compared with on vtest.avi, each as the
OpenCV documentation and tutorials build it, on one core:

- mog2: cv::BackgroundSubtractorMOG2 (history 500, variance threshold 16, shadows detected and
  dropped), an opening (3x3) and a closing (5x5 ellipse), 8-connected components of at least
  MIN_AREA_PX pixels; the head is the middle of the component's top row, the box its bounds.
- knn: the same with cv::BackgroundSubtractorKNN (history 500, threshold 400, shadows).
- hog: cv::HOGDescriptor with its default people detector (Dalal and Triggs' 64x128 window),
  detectMultiScale with its defaults (stride 8, scale 1.05, grouping 2); the head is the box's
  top-centre (and, scored apart by vtest_eval as "hog, h/8", an eighth of the box lower: the
  training window's margin above the head).

Each returns, per frame, a list of (u, v, (x0, y0, x1, y1)) at full resolution.
"""
from __future__ import annotations

import cv2
import numpy as np

MIN_AREA_PX = 150  # full-resolution pixels: a person far away on vtest.avi covers about 600


class Subtraction:
    """Background subtraction, morphology, connected components: the textbook pipeline."""

    def __init__(self, kind: str):
        if kind == "mog2":
            self.bg = cv2.createBackgroundSubtractorMOG2(history=500, varThreshold=16, detectShadows=True)
        else:
            self.bg = cv2.createBackgroundSubtractorKNN(history=500, dist2Threshold=400, detectShadows=True)
        self.open = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))
        self.close = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))

    def __call__(self, frame: np.ndarray) -> list:
        fg = self.bg.apply(frame)
        _, fg = cv2.threshold(fg, 200, 255, cv2.THRESH_BINARY)  # shadows are 127
        fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, self.open)
        fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, self.close)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
        out = []
        for i in range(1, n):
            x, y, w, h, area = (int(s) for s in stats[i])
            if area < MIN_AREA_PX:
                continue
            xs = np.flatnonzero(labels[y, x:x + w] == i)
            out.append((x + float(xs.mean()), float(y), (x, y, x + w, y + h)))
        return out


class Hog:
    """Dalal-Triggs HOG with OpenCV's default people detector."""

    def __init__(self):
        self.hog = cv2.HOGDescriptor()
        self.hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())

    def __call__(self, frame: np.ndarray) -> list:
        rects, _ = self.hog.detectMultiScale(frame)
        return [(x + w / 2.0, float(y), (x, y, x + w, y + h)) for x, y, w, h in (tuple(map(int, r)) for r in rects)]


def make(kind: str):
    return Hog() if kind == "hog" else Subtraction(kind)
