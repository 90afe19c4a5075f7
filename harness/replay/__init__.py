"""Re-running a run to draw it: the annotated video of a sequence (``video``), one person's
trajectories over the frames (``trajectories``) and a tracker's tracking graph frame by frame
(``graph``). This room runs trackers again through the pipeline's bank; ``occbench.report``
below it only reads finished run folders."""
