"""Placeholder: being written."""


def solve_routing(*args, **kwargs):
    raise NotImplementedError("solve_routing is not written yet")
