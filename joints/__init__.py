"""Joint constitutive models: the four-parameter Iwan model (Segalman 2005), its
describing function, its discretization into a bank of Jenkins (spring-slider)
elements, and the compiled state update of such a bank.

Knows nothing of ``fe``, ``cases`` or ``viz``. SI units throughout.
"""
