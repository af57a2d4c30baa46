"""Placeholder: being written."""


def solve_delivery(*args, **kwargs):
    raise NotImplementedError("solve_delivery is not written yet")
