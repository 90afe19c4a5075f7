"""One run, from config to run folder: build (``build``, ``config_check``), the frame loop
(``loop``), the run and its scoring (``experiment``, ``protocols``), the warm-up before
timing (``warmup``) and the run folder (``rundir``, ``writer``, ``summary``)."""
