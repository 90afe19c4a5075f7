"""The errors the harness's rooms share: raised in one room, caught or reported in another."""


class RunError(RuntimeError):
    """A run that cannot start or go on: bad config, unbuilt tracker, unreadable dataset."""


class ConfigError(ValueError):
    """A config value of the wrong type or outside its range; the message names the key."""
