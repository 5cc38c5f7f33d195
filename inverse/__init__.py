"""From modal parameters to joint parameters and model form: the estimator (paper
eq. 33-37, 43-46, corrected), diagnosis, uncertainty.

Imports ``ident``, ``runs``, ``fe`` and ``joints``. SI units throughout.
"""
