"""The orchestration layer (docs/architecture.md, "Layers"): it wires the core and the methods.

* :mod:`~taopt.orchestration.pipeline` — :func:`taopt.solve`, the one entry point, and
  :func:`taopt.available_methods`;
* :mod:`~taopt.orchestration.solving` — ``taopt solve FILE`` and ``taopt verify``;
* :mod:`~taopt.orchestration.study` and :mod:`~taopt.orchestration.studyio` — the study runner
  (scenarios × methods → one resumable CSV, on any executor);
* :mod:`~taopt.orchestration.studies` — the thesis's studies and claim checks, one module each;
* :mod:`~taopt.orchestration.demo` — ``taopt demo``;
* :mod:`~taopt.orchestration.cli` — the ``taopt`` command line.

It may import everything; the core (the rest of :mod:`taopt`) never imports it, and the method
packages :mod:`taopt.models` and :mod:`taopt.heuristics` do not either.
"""
