"""Commands that learn model parameters from annotated data: ``python -m harness.fit <what>``."""
