"""Compiled Jenkins-bank kernel (joints/kernel*.py) against a plain numpy update written
here from the definition: anchors bitwise equal, force and tangent within the
summation error bound of exactly rounded sums (math.fsum) for random shapes and the
SIMD block boundaries; broadcasting of the parameters, the stuck rule, non-finite
inputs, in-place commits and calls from compiled code bitwise equal to each other, and
the sums in the kernel's documented order, replayed in numpy bit for bit."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from joints.iwan import IwanParameters
from joints.jenkins import discretize, jenkins_update, jenkins_update_into
from joints.kernel import bank_update_kernel, reference_kernel
from joints.kernel_reference import INTERLEAVE, LANES, bank_update_reference

# around SIMD widths (4, 8 lanes), unrolled blocks (16, 32, 64) and numpy's 128 leaves
LENGTHS = [1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 31, 32, 33, 40, 63, 64, 65, 100, 127, 128,
           129, 255, 256, 257, 1000, 1031, 4099]
EPS = np.finfo(float).eps


def numpy_update(slip, anchor, k, phi):
    """The update by definition, in plain numpy (independent of the module)."""
    col = np.asarray(slip, float)[:, None]
    new = np.minimum(np.maximum(anchor, col - phi), col + phi)
    k_full = np.broadcast_to(k, new.shape)
    force = np.sum(np.ascontiguousarray((col - new) * k_full), axis=1)
    tangent = np.sum(np.ascontiguousarray(np.where(new == anchor, k_full, 0.0)), axis=1)
    return force, tangent, new


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def assert_bitwise(got, ref):
    for g, r in zip(got, ref):
        assert g.shape == r.shape
        np.testing.assert_array_equal(bits(g), bits(r))


def assert_matches_definition(got, slip, anchor, k, phi):
    """Anchors bit for bit as numpy's maximum/minimum (a zero anchor on an exact tie
    may carry the other sign: x86 max keeps the anchor, numpy the limit); each force
    and tangent within
    (n - 1) eps sum|terms| of the exactly rounded sum (Higham 2002, eq. 4.6: the bound
    for any summation order), the same bound numpy's pairwise sum obeys."""
    F, T, new = got
    F_np, T_np, new_np = numpy_update(slip, anchor, k, phi)
    np.testing.assert_array_equal(new, new_np)              # zeros of either sign
    nonzero = new_np != 0.0
    np.testing.assert_array_equal(bits(new[nonzero]), bits(new_np[nonzero]))
    n = new.shape[1]
    k_full = np.broadcast_to(k, new.shape)
    for j in range(new.shape[0]):
        terms = (slip[j] - new[j]) * k_full[j]
        stuck_k = np.where(new[j] == anchor[j], k_full[j], 0.0)
        assert abs(F[j] - math.fsum(terms)) <= (n - 1) * EPS * np.abs(terms).sum()
        assert abs(T[j] - math.fsum(stuck_k)) <= (n - 1) * EPS * stuck_k.sum()
        assert abs(F_np[j] - math.fsum(terms)) <= (n - 1) * EPS * np.abs(terms).sum()


def random_bank(rng, n_joints, n_sliders, per_joint_k, per_joint_phi):
    scale = 10.0 ** rng.uniform(-7, -3)
    k_shape = (n_joints, n_sliders) if per_joint_k else (n_sliders,)
    phi_shape = (n_joints, n_sliders) if per_joint_phi else (n_sliders,)
    k = rng.uniform(0.0, 1.0, k_shape) * 10.0 ** rng.uniform(2, 8)
    phi = np.sort(rng.uniform(0.0, scale, phi_shape), axis=-1)
    anchor = rng.normal(0.0, scale, (n_joints, n_sliders))
    slip = rng.normal(0.0, 2 * scale, n_joints)
    return slip, anchor, k, phi


@pytest.mark.parametrize("n_sliders", LENGTHS)
def test_definition_across_block_boundaries(n_sliders):
    rng = np.random.default_rng(n_sliders)
    for n_joints, pk, pp in ((1, False, False), (3, True, False), (5, False, True),
                             (2, True, True)):
        slip, anchor, k, phi = random_bank(rng, n_joints, n_sliders, pk, pp)
        before = anchor.copy()
        got = jenkins_update(slip, anchor, k, phi)
        assert_matches_definition(got, slip, anchor, k, phi)
        np.testing.assert_array_equal(anchor, before)  # pure
        # committing in place (the solvers' path) gives bitwise the same numbers
        state = anchor.copy()
        fo, to = np.empty(n_joints), np.empty(n_joints)
        jenkins_update_into(slip, state, k, phi, state, fo, to)
        assert_bitwise((fo, to, state), got)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 7), st.integers(1, 400), st.booleans(), st.booleans(),
       st.integers(0, 2**32 - 1))
def test_definition_random_shapes(n_joints, n_sliders, pk, pp, seed):
    rng = np.random.default_rng(seed)
    slip, anchor, k, phi = random_bank(rng, n_joints, n_sliders, pk, pp)
    assert_matches_definition(jenkins_update(slip, anchor, k, phi), slip, anchor, k, phi)


def test_same_bank_same_bits_at_any_address():
    """What bitwise-reproducible sweeps rely on: the same bank gives the same bits
    wherever its arrays lie in memory (SIMD alignment) and on every call."""
    rng = np.random.default_rng(5)
    slip, anchor, k, phi = random_bank(rng, 3, 203, True, False)

    def at(arr, offset):
        buf = np.zeros(arr.size + 8)
        view = buf[offset:offset + arr.size].reshape(arr.shape)
        view[...] = arr
        return view

    ref = jenkins_update(slip, anchor, k, phi)
    for offset in range(8):
        state = at(anchor, offset)
        fo, to = np.empty(3), np.empty(3)
        bank_update_kernel(slip, state, at(k, 7 - offset), at(phi, offset)[None, :], state,
                           fo, to)
        assert_bitwise((fo, to, state), ref)


def test_parameter_broadcasting_gives_identical_numbers():
    rng = np.random.default_rng(11)
    slip, anchor, k, phi = random_bank(rng, 6, 333, False, False)
    ref = jenkins_update(slip, anchor, k, phi)
    for kk, pp in ((np.tile(k, (6, 1)), phi), (k, np.tile(phi, (6, 1))),
                   (k[None, :], phi[None, :]), (np.tile(k, (6, 1)), np.tile(phi, (6, 1)))):
        assert_bitwise(jenkins_update(slip, anchor, kk, pp), ref)
    # a joint alone gives the bits it has in the bank
    for j in (0, 5):
        alone = jenkins_update(slip[j:j + 1], anchor[j:j + 1], k, phi)
        assert_bitwise(alone, (ref[0][j:j + 1], ref[1][j:j + 1], ref[2][j:j + 1]))


def documented_order_sum(terms):
    """The kernel's summation order (joints/kernel_reference.py, comment above LANES),
    in numpy: lane m of accumulator u takes the blocks 16 b + 8 u (+ m), a last odd
    block goes to accumulator 0; accumulator 0 + 1 lane by lane, a tree over the 8
    lanes; plus, when n mod 8 >= 4, the tree of the next 4 terms; plus the n mod 4 last
    terms summed in order."""
    n = terms.size
    nb = n // LANES
    acc = np.zeros((INTERLEAVE, LANES))
    for b in range(nb // INTERLEAVE):
        for u in range(INTERLEAVE):
            acc[u] = acc[u] + terms[(INTERLEAVE * b + u) * LANES:(INTERLEAVE * b + u + 1) * LANES]
    if nb % INTERLEAVE:
        acc[0] = acc[0] + terms[(nb - 1) * LANES:nb * LANES]
    v = acc[0] + acc[1]
    total = ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]))
    half = terms[nb * LANES:nb * LANES + 4] if n % LANES >= 4 else np.zeros(4)
    total = total + ((half[0] + half[1]) + (half[2] + half[3]))
    tail = 0.0
    for x in terms[n - n % 4:]:
        tail = tail + x
    return total + tail


@pytest.mark.parametrize("n_sliders", [1, 3, 4, 5, 7, 8, 9, 11, 12, 13, 15, 16, 20, 23, 24, 25,
                                       100, 1031])
def test_sums_follow_the_documented_order_bit_for_bit(n_sliders):
    """The order is fixed by the kernel's IR, not left to the compiler: a numpy replay
    of it gives the same bits (this is what makes every executor, every compilation,
    cached or fresh, and every SIMD width give the same numbers)."""
    rng = np.random.default_rng(100 + n_sliders)
    slip, anchor, k, phi = random_bank(rng, 3, n_sliders, True, False)
    F, T, new = jenkins_update(slip, anchor, k, phi)
    for j in range(3):
        terms = (slip[j] - new[j]) * k[j]
        stuck_k = np.where(new[j] == anchor[j], k[j], 0.0)
        assert bits(F[j]) == bits(documented_order_sum(terms))
        assert bits(T[j]) == bits(documented_order_sum(stuck_k))


@pytest.mark.parametrize("n_sliders", [1, 3, 4, 5, 7, 8, 9, 12, 15, 16, 17, 23, 24, 25, 33,
                                       40, 100, 257])
def test_reference_loop_gives_the_kernels_bits(n_sliders):
    """The plain reference loop (joints/kernel_reference.py), run as plain Python and
    compiled by numba (the fallback), gives bitwise the kernel's force, tangent and
    anchors, shared or per-joint parameters, in place or not; and its sums are the
    numpy replay of the documented order (an independent third writing of it)."""
    rng = np.random.default_rng(300 + n_sliders)
    for pk, pp in ((True, False), (False, True)):
        slip, anchor, k, phi = random_bank(rng, 3, n_sliders, pk, pp)
        anchor[0, 0] = slip[0] - np.atleast_2d(phi)[0, 0]          # on its limit
        k2, phi2 = np.atleast_2d(k), np.atleast_2d(phi)
        ref = [np.empty_like(anchor), np.empty(3), np.empty(3)]
        bank_update_reference(slip, anchor, k2, phi2, *ref)
        F, T, new = jenkins_update(slip, anchor, k, phi)
        assert_bitwise((ref[1], ref[2], ref[0]), (F, T, new))
        state = anchor.copy()
        fo, to = np.empty(3), np.empty(3)
        reference_kernel(slip, state, k2, phi2, state, fo, to)
        assert_bitwise((fo, to, state), (F, T, new))
        terms = (slip[2] - new[2]) * k2[-1]
        assert bits(ref[1][2]) == bits(documented_order_sum(terms))


def test_stuck_means_anchor_unchanged_and_full_tangent():
    """Anchors within the limits: every slider sticks, anchor_new is anchor bit for bit
    and the tangent is the sum of all stiffnesses; sliders pushed beyond their limit
    end exactly at the limit and leave the tangent."""
    p = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
    d = discretize(p, 200)
    rng = np.random.default_rng(2)
    slip = rng.normal(0.0, p.phi_max, 3)
    anchor = slip[:, None] + rng.uniform(-0.999, 0.999, (3, 200)) * d.slip_limit
    F, T, new = jenkins_update(slip, anchor, d.stiffness, d.slip_limit)
    np.testing.assert_array_equal(bits(new), bits(anchor))
    assert np.all(T == T[0])
    assert abs(T[0] - math.fsum(d.stiffness)) <= 199 * EPS * p.K_T
    assert T[0] == pytest.approx(p.K_T, rel=1e-13)
    # move the slip by twice the largest limit: every slider slips to its limit
    s2 = slip + 2.0 * p.phi_max
    F2, T2, new2 = jenkins_update(s2, anchor, d.stiffness, d.slip_limit)
    np.testing.assert_array_equal(new2, s2[:, None] - d.slip_limit)
    assert np.all(T2 == 0.0)
    # saturated force: sum k phi (within summation rounding)
    np.testing.assert_allclose(F2, np.dot(d.stiffness, d.slip_limit), rtol=1e-13)


def test_initial_state_signed_zeros_and_ties():
    """Zero slip on zero anchors (the virgin state) and anchors exactly on a limit:
    the numbers of numpy's update (signs of zero aside), zero force, full tangent."""
    n = 37
    k = np.linspace(1.0, 2.0, n)
    phi = np.linspace(0.5, 1.5, n)
    for slip in (np.array([0.0, -0.0]), np.array([1.0, -1.0])):
        for anchor in (np.zeros((2, n)), -np.zeros((2, n)),
                       slip[:, None] - phi, slip[:, None] + phi):
            got = jenkins_update(slip, anchor, k, phi)
            assert_matches_definition(got, slip, anchor, k, phi)
            if np.all(slip == 0.0) and np.all(anchor == 0.0):     # virgin state
                np.testing.assert_array_equal(got[0], 0.0)
                assert np.all(np.abs(got[1] - math.fsum(k)) <= (n - 1) * EPS * k.sum())


def test_non_finite_inputs():
    """Infinite limits never slip; NaN anchors stay NaN (their force is NaN); an
    infinite slip gives numpy's numbers; a NaN bound (NaN slip, or an infinite slip on
    an infinite limit: inf - inf) gives a NaN force and leaves the anchor where it was
    (numpy would poison it)."""
    rng = np.random.default_rng(9)
    n = 45
    k = rng.uniform(1, 2, n)
    phi = np.sort(rng.uniform(0.1, 1.0, n))
    phi_inf = phi.copy()
    phi_inf[-3:] = np.inf                       # sliders that never slip
    slip = np.array([np.nan, np.inf, -np.inf, 0.3, 0.2])
    anchor = rng.normal(0, 1, (5, n))
    anchor[3, ::4] = np.nan                     # a poisoned state
    anchor[4, ::5] = np.inf
    for ph in (phi, phi_inf):
        F, T, new = jenkins_update(slip, anchor, k, ph)
        with np.errstate(invalid="ignore"):
            F_np, T_np, new_np = numpy_update(slip, anchor, k, ph)
            nan_bound = np.isnan(slip[:, None] - ph) | np.isnan(slip[:, None] + ph)
        np.testing.assert_array_equal(new[~nan_bound], new_np[~nan_bound])
        np.testing.assert_array_equal(bits(new[nan_bound]), bits(anchor[nan_bound]))
        np.testing.assert_array_equal(np.isnan(F[1:]), np.isnan(F_np[1:]))
        if not nan_bound[1:3].any():
            np.testing.assert_array_equal(T[1:3], T_np[1:3])
        np.testing.assert_array_equal(bits(new[0]), bits(anchor[0]))
        assert np.isnan(F[0]) and np.all(np.isnan(F[1:3]))
    assert np.all(new[1, -3:] == anchor[1, -3:])              # phi = inf: stuck


def test_into_matches_pure_and_commits_in_place():
    rng = np.random.default_rng(4)
    slip, anchor, k, phi = random_bank(rng, 4, 300, True, False)
    F, T, new = jenkins_update(slip, anchor, k, phi)
    out = np.empty_like(anchor)
    F2, T2 = jenkins_update_into(slip, anchor, k, phi, out)
    assert_bitwise((F2, T2, out), (F, T, new))
    state = anchor.copy()
    fo, to = np.empty(4), np.empty(4)
    r = jenkins_update_into(slip, state, k, phi, state, fo, to)
    assert r[0] is fo and r[1] is to
    assert_bitwise((fo, to, state), (F, T, new))


def test_into_rejects_bad_outputs():
    slip, anchor, k, phi = random_bank(np.random.default_rng(0), 2, 10, False, False)
    with pytest.raises(ValueError, match="out_anchor"):
        jenkins_update_into(slip, anchor, k, phi, np.empty((2, 9)))
    with pytest.raises(ValueError, match="out_anchor"):
        jenkins_update_into(slip, anchor, k, phi, np.empty((10, 2)).T)
    with pytest.raises(ValueError, match="out_force"):
        jenkins_update_into(slip, anchor, k, phi, np.empty((2, 10)), np.empty(3))


def test_non_contiguous_and_other_dtypes():
    rng = np.random.default_rng(8)
    slip, anchor, k, phi = random_bank(rng, 3, 50, True, True)
    ref = jenkins_update(slip, anchor, k, phi)
    phi_strided = np.repeat(phi, 2, axis=1)[:, ::2]
    assert not phi_strided.flags.c_contiguous
    got = jenkins_update(list(slip), np.asfortranarray(anchor), np.asfortranarray(k),
                         phi_strided)
    assert_bitwise(got, ref)
    wide = np.zeros((3, 100))
    wide[:, ::2] = anchor                      # strided view
    assert_bitwise(jenkins_update(slip, wide[:, ::2], k, phi), ref)
    s64 = slip.astype(np.float32).astype(float)
    a64 = anchor.astype(np.float32).astype(float)
    got32 = jenkins_update(slip.astype(np.float32), anchor.astype(np.float32), k, phi)
    assert_bitwise(got32, jenkins_update(s64, a64, k, phi))


def test_broadcast_shapes_outside_the_contract_use_numpy_broadcasting():
    rng = np.random.default_rng(3)
    k = rng.uniform(1, 2, 20)
    phi = rng.uniform(0.1, 1, 20)
    anchor = rng.normal(0, 1, (1, 20))     # one state row shared by three slips
    slip = np.array([0.1, -0.4, 2.0])
    F, T, new = jenkins_update(slip, anchor, k, phi)
    assert new.shape == (3, 20)
    for j in range(3):
        got = jenkins_update(slip[j:j + 1], anchor, k, phi)
        np.testing.assert_array_equal(bits(got[2]), bits(new[j:j + 1]))
        np.testing.assert_allclose(got[0], F[j:j + 1], rtol=0, atol=20 * EPS * 2 * 20)
        np.testing.assert_allclose(got[1], T[j:j + 1], rtol=0, atol=20 * EPS * 2 * 20)


@njit
def _march(slips, anchor, k, phi):
    n_steps, n_joints = slips.shape
    force = np.empty((n_steps, n_joints))
    tangent = np.empty((n_steps, n_joints))
    for t in range(n_steps):
        bank_update_kernel(slips[t], anchor, k, phi, anchor, force[t], tangent[t])
    return force, tangent


def test_kernel_called_from_compiled_loop_matches_python_loop():
    p = IwanParameters(chi=-0.6, K_T=8e5, F_S=150.0, beta=2.0)
    d = discretize(p, 150)
    theta = np.linspace(0, 6 * np.pi, 301)
    slips = np.sin(theta)[:, None] * np.array([0.4, 1.3]) * p.phi_max
    anchor = np.zeros((2, 150))
    F_py, T_py = [], []
    for s in slips:
        F, T, anchor = jenkins_update(s, anchor, d.stiffness, d.slip_limit)
        F_py.append(F)
        T_py.append(T)
    state = np.zeros((2, 150))
    F_c, T_c = _march(slips, state, d.stiffness[None, :], d.slip_limit[None, :])
    assert_bitwise((F_c, T_c, state), (np.array(F_py), np.array(T_py), anchor))
    # the joint driven beyond phi_max saturates (zero tangent) at its turning points,
    # where its force is +-sum k phi = +-F_S (midpoint rule, within 1e-4 at n = 150)
    assert T_c[:, 1].min() == 0.0 and T_c[:, 0].min() > 0.0
    assert np.abs(F_c[:, 1]).max() == pytest.approx(p.F_S, rel=1e-4)
