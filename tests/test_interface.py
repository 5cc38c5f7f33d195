"""Kinematics of two stacked strips (fe.interface) against closed forms: rigid and
composite motions of the pair, an axial shift, unequal thicknesses, the normal gap and
the in-phase / out-of-phase energy split of two identical strips."""
import numpy as np
import pytest

from fe.beam import THETA, U, W
from fe.interface import (
    fibre_axial_displacement,
    normal_gap_rows,
    slip_coefficients,
    stacked_energy_split,
    stacked_strips,
    tangential_slip_rows,
)
from fe.mesh import DofMap

N = 6                      # nodes per strip
X = np.linspace(0.0, 0.3, N)


def _pair():
    lower = DofMap(N, 3, 0)
    upper = DofMap(N, 3, lower.stop)
    return lower, upper, upper.stop


def _vector(lower, upper, lo, up):
    """Global vector from per-strip dicts of nodal u, w, theta."""
    x = np.zeros(upper.stop)
    for dm, d in ((lower, lo), (upper, up)):
        for comp, key in ((U, "u"), (W, "w"), (THETA, "theta")):
            x[dm.dof(np.arange(N), comp)] = d.get(key, 0.0)
    return x


@pytest.mark.parametrize("h_up, h_lo", [(1e-3, 1e-3), (2e-3, 0.5e-3)])
def test_slip_of_bending_motions(h_up, h_lo):
    """Same rotation theta of both strips: each bending about its own centroid slips by
    (h_up + h_lo)/2 theta; bending as one section about the interface (u = -z theta,
    centroids at z = -h_lo/2 and +h_up/2) does not slip."""
    lower, upper, n = _pair()
    G = tangential_slip_rows(upper, lower, np.arange(N), h_up, h_lo, n)
    theta = np.linspace(0.1, 0.4, N)
    own = _vector(lower, upper, {"theta": theta}, {"theta": theta})
    np.testing.assert_allclose(G @ own, 0.5 * (h_up + h_lo) * theta, rtol=1e-14)
    one = _vector(lower, upper, {"u": 0.5 * h_lo * theta, "theta": theta},
                  {"u": -0.5 * h_up * theta, "theta": theta})
    np.testing.assert_allclose(G @ one, 0.0, atol=1e-18)
    # an axial shift a of the upper strip slides it by a; the lower one by -a
    np.testing.assert_allclose(G @ _vector(lower, upper, {}, {"u": 2e-6}), 2e-6)
    np.testing.assert_allclose(G @ _vector(lower, upper, {"u": 2e-6}, {}), -2e-6)
    assert slip_coefficients(h_up, h_lo) == [1.0, 0.5 * h_up, -1.0, 0.5 * h_lo]


def test_fibres_at_the_interface_give_the_slip():
    """The fibre displacement of the upper strip's bottom face minus the lower strip's
    top face is the slip of the rows, for any nodal motion."""
    lower, upper, n = _pair()
    h = 1e-3
    G = tangential_slip_rows(upper, lower, np.arange(N), h, h, n)
    rng = np.random.default_rng(3)
    lo = {k: rng.normal(size=N) for k in ("u", "w", "theta")}
    up = {k: rng.normal(size=N) for k in ("u", "w", "theta")}
    step = (fibre_axial_displacement(up["u"], up["theta"], -h / 2)
            - fibre_axial_displacement(lo["u"], lo["theta"], h / 2))
    np.testing.assert_allclose(G @ _vector(lower, upper, lo, up), step, rtol=1e-12)


def test_normal_gap_and_stack_geometry():
    lower, upper, n = _pair()
    Gn = normal_gap_rows(upper, lower, np.arange(1, N), n)
    w = np.linspace(1.0, 2.0, N)
    x = _vector(lower, upper, {"w": w}, {"w": 3 * w})
    np.testing.assert_allclose(Gn @ x, 2 * w[1:])
    lo, up = stacked_strips(X, 1e-3, 0.05)
    assert lo.z_center + lo.thickness / 2 == up.z_center - up.thickness / 2 == 0.0
    assert np.array_equal(lo.x, X) and lo.x is not up.x


def test_energy_split_of_identical_strips():
    """a = in-phase axial motion, d = out-of-phase bending: x_lo = a - d, x_up = a + d;
    with a mass matrix without axial-transverse coupling the cross terms vanish."""
    rng = np.random.default_rng(5)
    Ms = np.diag(rng.uniform(0.5, 2.0, 3 * N))
    a = np.zeros(3 * N)
    a[U::3] = rng.normal(size=N)
    d = np.zeros(3 * N)
    d[W::3], d[THETA::3] = rng.normal(size=N), rng.normal(size=N)
    split = stacked_energy_split(a - d, a + d, Ms)
    ea, ed = a @ Ms @ a, d @ Ms @ d
    assert split["in_phase_axial"] == pytest.approx(ea / (ea + ed), rel=1e-12)
    assert split["out_of_phase_bending"] == pytest.approx(ed / (ea + ed), rel=1e-12)
    assert split["in_phase_bending"] == split["out_of_phase_axial"] == 0.0
    assert stacked_energy_split(d, d, Ms)["in_phase_bending"] == pytest.approx(1.0)
