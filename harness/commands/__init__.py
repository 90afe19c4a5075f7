"""The commands of ``occbench`` (``harness.commands.cli``): one module per subcommand.

Each parses its own command line and calls the library rooms (``harness.pipeline``,
``harness.sources``, ``harness.sweeps``, ``harness.metrics``, ``harness.report``,
``harness.fit``); nothing in the library imports a command.
"""
