"""One run, from config to run folder: build (``build``, ``config_check``), the frame loop
(``loop``), the tracker bank that feeds every tracker (``bank``), the run in three steps
(``experiment``: ``plan``, the bank, ``record``; the single-target ``protocols``), the warm-up
before timing (``warmup``) and the run folder (``rundir``, ``writer``, ``summary``)."""
