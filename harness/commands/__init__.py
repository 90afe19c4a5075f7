"""The commands of ``occbench`` (``occbench.commands.cli``): one module per subcommand.

Each parses its own command line and calls the library rooms (``occbench.pipeline``,
``occbench.sources``, ``occbench.sweeps``, ``occbench.metrics``, ``occbench.report``,
``occbench.fit``); nothing in the library imports a command.
"""
