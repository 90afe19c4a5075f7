"""One run, from config to run folder: the frame loop (``loop``), the tracker bank that feeds
every tracker (``bank``), the run in three steps (``experiment``: ``plan``, the bank,
``record``; the single-target ``protocols``), the warm-up before timing (``warmup``) and the
run folder's writer (``writer``, ``summary``). Turning config into objects is the room below
(``occbench.config``); re-running a finished run to draw it is the room above
(``occbench.replay``)."""
