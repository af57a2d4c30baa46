"""Placeholder: being written (see the issue tracker). Registers nothing yet."""
