"""Commands that learn model parameters from annotated data: ``occbench fit <what>``."""
