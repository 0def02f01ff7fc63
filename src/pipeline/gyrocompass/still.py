"""Where a detected dwell's tool is still: its ends cut back to where the MD rests.

A dwell is found where the frame angle and the smoothed MD stay within their tolerances
(:mod:`~pipeline.gyrocompass.readings`). A tool arriving at a stop or leaving it creeps
within the MD tolerance for seconds (a few centimetres, decelerating or accelerating): the
dwell takes those samples in, and with them accelerations and housing spin a tool at rest
does not read. The samples of a dwell where the tool rests are found from its odometer MD:

- the *level* is the median MD over the dwell (m) and the odometer noise σ the MAD of its
  sample-to-sample steps (σ·√2, scaled to a standard deviation);
- the MD is averaged over windows of ``w`` samples: as few as bring ``REST_SIGMAS`` σ/√w
  down to ``REST_FLOOR`` (an exact odometer: 1), at most the detection's ``md_smoothing``
  window; a window is *at rest* when its mean is within ``REST_SIGMAS`` σ/√w (at least
  ``REST_FLOOR``) of the level;
- a sample is *still* when every window of ``w`` samples holding it (within the recording)
  is at rest, and the tool is still from the dwell's first still sample to its last.

A dwell bounded by frame moves, its MD at rest, keeps its samples (to a noise excursion of
``REST_SIGMAS`` σ at an end); one bounded by travel ends where the odometer can tell the
tool is not moving, half an averaging window inside where the mean leaves the level. The
numbers depend only on the odometer MD from ``w`` − 1 samples before the dwell to ``w`` − 1
after it (the whole-table and the streamed readings take the same)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]

REST_SIGMAS = 4.0
"""A window's mean MD off the level by more than this many of its σ: the tool moved."""
REST_FLOOR = 0.001
"""m: the least MD offset that tells motion from rest (an odometer's resolution), and the
noise the averaging window brings σ down to when it can."""
MAD_SIGMA = 1.4826
"""σ per median absolute deviation of normal noise."""


def still_span(md: FloatArray, start: int, end: int, window: int) -> tuple[int, int]:
    """First and end (exclusive) sample of the still part of the dwell of samples
    [``start``, ``end``) of the odometer ``md`` (m), averaging windows of at most ``window``
    samples (module docstring); (``start``, ``start``) when no sample is still."""
    level = float(np.median(md[start:end]))
    steps = np.abs(np.diff(md[start:end]))
    sigma = MAD_SIGMA * float(np.median(steps)) / np.sqrt(2.0) if steps.size else 0.0
    w = int(min(window, max(1.0, np.ceil((REST_SIGMAS * sigma / REST_FLOOR) ** 2))))
    band = max(REST_SIGMAS * sigma / np.sqrt(w), REST_FLOOR)
    lo, hi = max(start - w + 1, 0), min(end + w - 1, md.size)
    sums = np.concatenate([[0.0], np.cumsum(md[lo:hi] - level)])
    moved = np.abs(sums[w:] - sums[:-w]) > band * w  # the window of samples [lo + j, lo + j + w)
    count = np.concatenate([[0], np.cumsum(moved)])
    held = np.arange(start - lo, end - lo)  # windows j in [i − w + 1, i] hold sample i
    first, last = (np.clip(held + k, 0, moved.size) for k in (1 - w, 1))
    still = count[last] == count[first]
    if not still.any():
        return start, start
    return start + int(np.argmax(still)), end - int(np.argmax(still[::-1]))


def still_spans(
    md: FloatArray, starts: IndexArray, ends: IndexArray, window: int
) -> tuple[IndexArray, IndexArray]:
    """:func:`still_span` of each dwell [``starts``, ``ends``) of ``md``: first and end
    samples."""
    spans = [
        still_span(md, a, b, window) for a, b in zip(starts.tolist(), ends.tolist(), strict=True)
    ]
    first, end = np.array(spans, dtype=np.intp).reshape(-1, 2).T
    return first, end
