"""Placeholder: being written."""


def solve_sop(*args, **kwargs):
    raise NotImplementedError("solve_sop is not written yet")
