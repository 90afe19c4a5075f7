"""Many runs: sweep folders and their jobs (``jobs``, ``gather``), the fingerprints that make a
resume safe (``fingerprint``), Optuna tuning (``tune``), the Hydra callbacks and plugin checks
(``callbacks``, ``plugins``) and the generalisation table (``generalisation``)."""
