"""The thesis's studies and claim checks (orchestration: they run the registered methods).

One module per study or claim set: :mod:`~taopt.orchestration.studies.drift` (chapter 2, §2.5),
:mod:`~taopt.orchestration.studies.capability` (chapter 3, §3.7), :mod:`~taopt.orchestration.studies.comm` (chapter 4,
§4.4), :mod:`~taopt.orchestration.studies.delivery` (chapter 5, §5.5), and the executable claim checks
:mod:`~taopt.orchestration.studies.routing_claims`, :mod:`~taopt.orchestration.studies.capability_claims` and
:mod:`~taopt.orchestration.studies.comm_claims`. A regular package (not a namespace one), so the docstring
examples of its modules are collected by ``tests/orchestration/test_doctests.py``.
"""
