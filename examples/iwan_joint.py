"""One four-parameter Iwan joint (Segalman 2005): describing function against the loop.

The exact first-harmonic stiffnesses (``joints.describing``, incomplete-Beta closed
forms) are compared with a second, independent route: the area of the Masing loop
(``joints.iwan.steady_loop``, paper eq. 10) integrated numerically. In micro-slip
the dissipation per cycle is ``pi A^2 k_quadrature`` and grows as ``A^(chi+3)``
(Segalman 2005, eq. 25); above ``phi_max`` the joint macro-slips.

Run: ``python examples/iwan_joint.py``. SI units: m, N, N/m, J.
"""
import numpy as np
from scipy.integrate import trapezoid

from joints.describing import describing_function
from joints.iwan import IwanParameters, steady_loop

joint = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
print(f"phi_max = {joint.phi_max:.4e} m (slip where macro-slip starts)")

amplitudes = np.array([1e-4, 1e-3, 2e-3, 1e-2])
k_in, k_quad = describing_function(joint, amplitudes)


def loop_area(amplitude, n_points=200001):
    """Dissipation per cycle (J) as the area enclosed by the steady loop, trapezoidal."""
    _, u, force = steady_loop(joint, amplitude, n_points)
    return abs(trapezoid(force, u))


loop = np.array([loop_area(a) for a in amplitudes])
print(" A (m)      k_in (N/m)   D from DF (J)  D from loop (J)  rel. diff")
for a, ki, kq, d in zip(amplitudes, k_in, k_quad, loop):
    d_df = np.pi * a**2 * kq
    print(f"{a:.1e}  {ki:11.1f}  {d_df:13.5e}  {d:15.5e}  {abs(d_df - d) / d:9.1e}")

# the micro-slip power law: D ~ A^(chi+3) between the two lowest amplitudes
slope = np.log(loop[1] / loop[0]) / np.log(amplitudes[1] / amplitudes[0])
print(f"log-slope of D over 1e-4..1e-3 m: {slope:.6f} (chi + 3 = {joint.chi + 3:.6f})")
