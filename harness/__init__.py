"""occbench harness: datasets, detection sources, runs, evaluation and reports."""
