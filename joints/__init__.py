"""Joint constitutive laws behind one interface (:mod:`joints.law`): the four-parameter
Iwan model (Segalman 2005) and its describing function, its discretization into banks of
Jenkins (spring-slider) elements with their compiled state update, and Bouc-Wen.

Knows nothing of ``fe``, ``cases`` or ``viz``. SI units throughout.
"""
