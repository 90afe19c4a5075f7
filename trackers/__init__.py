"""Multi-person trackers that survive occlusions, and the front end they share.

`trackers` never imports `harness`: a tracker is fed frames and detections and returns
tracks; it reads no files and no config dicts.
"""
