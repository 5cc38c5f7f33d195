"""Drawing: matplotlib plots, off-screen pyvista renders, meshio export.

Draws what it is given; computes no physics.
"""
