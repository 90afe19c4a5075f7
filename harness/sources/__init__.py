"""Detection sources, what every ``detector=`` config builds: the interface (``base``), the
sources read from the dataset's annotations (``annotations``: noisy ground truth, public
detections), the front end's detectors on pixels (``frontend``) and the front-end cache that
keeps their outputs per sequence (``cache``)."""
