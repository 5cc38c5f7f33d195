"""Joint constitutive models: the four-parameter Iwan model (Segalman 2005) and its
discretization into a bank of Jenkins (spring-slider) elements.

Knows nothing of ``fe``, ``cases`` or ``viz``. SI units throughout.
"""
