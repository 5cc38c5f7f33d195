"""From modal parameters to joint parameters and model form: the estimator (paper
eq. 33-37, 43-46, corrected; ``estimate`` and the modules it calls) and the model-form
diagnosis (``diagnose`` and its ``diagnosis_*`` modules).

Imports ``ident``, ``runs``, ``fe`` and ``joints``, never ``cases``: an FE model comes
in as an argument (:mod:`inverse.fe_reference`). SI units throughout.
"""
