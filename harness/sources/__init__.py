"""Detection sources, what every ``detector=`` config builds: the interface (``base``), the
sources read from the dataset's annotations (``annotations``: noisy ground truth, public
detections) and the front end's detectors on pixels (``frontend``)."""
