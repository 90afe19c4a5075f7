"""A warm server for single runs, as Gradle's and Bazel's daemons: ``occbench`` hands its
command to a preloaded process that forks a child per command (``client``: the console
script's fast path, standard library only; ``serve``: the server; ``job``: the forked
child; ``trust``: whether the server's code is still the installed code).

Importing this package imports nothing: the client must stay light."""
