"""Errors that the CLI reports as one line with exit status 2."""


class InputError(ValueError):
    """Bad user input (file content, option value). The message is shown as is."""
