"""Thin adapters around outside (PyPI) trackers, so they run in the harness on exactly the
same detections as ours.

Each module wraps one library in a class with ``reset()`` and
``update(frame, detections, foreground=None) -> list[Track]``: our ``Detections`` (xywh,
0-based, float64, with scores) are converted to the library's input and its output back to
``Track`` records. The library is imported in the constructor, so importing this package
never needs it; a missing library raises ``ImportError`` saying how to install it:

    pip install -e ".[outside]"                               # motpy (and rich for norfair)
    pip install --no-deps norfair==2.3.0 ocsort==0.0.2       # pins numpy<2 / scipy==1.9.3

norfair and ocsort are installed without their dependencies because their metadata pins
numpy<2 (norfair) or scipy==1.9.3, lap, filterpy==1.4.5 (ocsort), which would downgrade
numpy, OpenCV and pandas; their code runs on the project's numpy 2 (tested).

Run them beside ours on the same detections: ``python -m occbench tracker=everyone`` (ours
plus all outside trackers, conf/tracker/everyone.yaml), or pick with a multirun, e.g.
``python -m occbench -m tracker=baseline,reta,pbm,bytetrack,ocsort,norfair,motpy``.

Identities are renumbered 1, 2, ... in order of first report, per adapter instance: some
libraries draw ids from a class-level counter (OC-SORT) or from ``uuid4`` (motpy), which
would make result files depend on what else ran in the process.

Modules:
    norfair: ``NorfairTracker`` (tryolabs norfair, IoU distance on the two box corners).
    motpy: ``MotpyTracker`` (wmuron motpy, Kalman box tracker with IoU matching).
    ocsort: ``OCSortTracker`` (Cao et al. 2023, official code as packaged by ``ocsort``).
    boxmot: ``BoxmotTracker`` (BoxMOT's motion-only trackers: BoT-SORT, ByteTrack, OC-SORT,
        DeepOCSORT, HybridSORT, BoostTrack, OccluBoost, SFSORT; no ReID, no camera-motion
        compensation; extra ``boxmot``).

ByteTrack (``bytetrack`` in the configs) is our own re-implementation of BYTE and lives in
``occbench.trackers.bytetrack``, not here.
"""

from __future__ import annotations

from occbench.trackers.outside._common import MissingLibrary
from occbench.trackers.outside.boxmot import BoxmotTracker
from occbench.trackers.outside.motpy import MotpyTracker
from occbench.trackers.outside.norfair import NorfairTracker
from occbench.trackers.outside.ocsort import OCSortTracker

__all__ = ["BoxmotTracker", "MissingLibrary", "MotpyTracker", "NorfairTracker", "OCSortTracker"]
