"""The one-mode diagnosis (``docs/formats/diagnosis.md`` v2): :func:`diagnose`.

Modules: ``causes/`` (the catalogue, one file per cause), ``models`` (the base model and
the design of any set of causes), ``fit`` (batched least squares), ``cv`` (held-out
errors and predictions), ``noise`` (the noise of the one-mode data through
:mod:`inverse.judge`), ``params``, ``separability``, ``run`` (:func:`diagnose`),
``report``, ``text``.
"""
