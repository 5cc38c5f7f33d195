"""Meshes, DOF maps, sparse assembly, constraints and coupling elements."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fe.assembly import (
    assemble,
    coupling_rows,
    coupling_stiffness,
    expand,
    free_dofs,
    free_index,
    point_masses,
    restrict,
    restrict_columns,
)
from fe.beam import Section, frame_stiffness
from fe.mesh import DofMap, line_mesh, mesh_with_element_size, segmented_line_mesh


def test_segmented_mesh_keeps_breakpoints_and_tributary_lengths():
    m = segmented_line_mesh([0.0, 0.05, 0.33, 0.35], [5, 28, 4])
    assert m.n_elements == 37 and m.n_nodes == 38
    for b in (0.0, 0.05, 0.33, 0.35):
        m.node_at(b)
    assert m.tributary_length().sum() == pytest.approx(0.35)
    glue = m.nodes_in(0.33, 0.35)
    w = m.tributary_length(glue)
    np.testing.assert_allclose(w, [0.0025, 0.005, 0.005, 0.005, 0.0025])
    m2 = mesh_with_element_size([0.0, 0.05, 0.33], 0.005)
    assert np.max(m2.element_length) <= 0.005 + 1e-15 and m2.n_elements == 66
    with pytest.raises(ValueError):
        m.node_at(0.0123)
    with pytest.raises(ValueError):
        line_mesh([0.0, 0.1, 0.05])


def test_dofmap_numbering_is_node_major_with_offset():
    d = DofMap(n_nodes=4, dofs_per_node=3, offset=12)
    assert d.dof(2, 1) == 12 + 7 and d.stop == 24
    np.testing.assert_array_equal(d.element_dofs(np.array([[0, 1]])), [[12, 13, 14, 15, 16, 17]])
    with pytest.raises(ValueError):
        d.dof(4, 0)


def test_vectorized_assembly_equals_loop_assembly():
    rng = np.random.default_rng(3)
    mesh = line_mesh(np.sort(rng.uniform(0, 1, 9)))
    dm = DofMap(mesh.n_nodes)
    sec = Section(70e9, 2700.0, 0.05, 1e-3)
    Ke = frame_stiffness(mesh.element_length, sec.EA, sec.EI)
    dofs = dm.element_dofs(mesh.elements)
    K = assemble(Ke, dofs, dm.n_dofs).toarray()
    ref = np.zeros((dm.n_dofs, dm.n_dofs))
    for e in range(mesh.n_elements):
        ref[np.ix_(dofs[e], dofs[e])] += Ke[e]
    np.testing.assert_allclose(K, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_coupling_energy_is_sum_of_k_s_squared():
    rng = np.random.default_rng(7)
    n = 20
    dofs = rng.choice(n, size=(5, 3), replace=True)
    coef = rng.normal(size=(5, 3))
    k = rng.uniform(1, 10, 5)
    G = coupling_rows(dofs, coef, n)
    Kc = coupling_stiffness(G, k)
    x = rng.normal(size=n)
    s = np.array([np.sum(coef[i] * x[dofs[i]]) for i in range(5)])  # repeated DOFs add up
    assert 0.5 * x @ (Kc @ x) == pytest.approx(0.5 * np.sum(k * s**2), rel=1e-12)
    assert abs(Kc - Kc.T).max() <= 1e-14 * abs(Kc).max()


def test_springs_in_series_through_couplings():
    """Two DOFs, ground spring k1 on x0 and coupling k2 on x1 - x0: x1 = F (1/k1 + 1/k2)."""
    k1, k2, F = 3.0e5, 1.2e5, 7.0
    G = coupling_rows([[0, 1], [1, 0]], [[1.0, 0.0], [1.0, -1.0]], 2)
    K = coupling_stiffness(G, [k1, k2]).toarray()
    x = np.linalg.solve(K, [0.0, F])
    assert x[1] == pytest.approx(F * (1 / k1 + 1 / k2), rel=1e-12)


def test_constraints_restrict_and_expand():
    n = 6
    A = sp.csr_matrix(np.arange(36.0).reshape(6, 6))
    free = free_dofs(n, [0, 3])
    np.testing.assert_array_equal(free, [1, 2, 4, 5])
    np.testing.assert_array_equal(restrict(A, free).toarray(), A.toarray()[np.ix_(free, free)])
    G = sp.csr_matrix(np.eye(6)[:2])
    assert restrict_columns(G, free).shape == (2, 4)
    x = expand(np.array([1.0, 2.0, 3.0, 4.0]), free, n)
    np.testing.assert_array_equal(x, [0, 1, 2, 0, 3, 4])
    assert free_index(free, 4) == 2
    with pytest.raises(ValueError):
        free_index(free, 3)
    Mp = point_masses([2, 5], [0.1, 0.2], n)
    assert Mp.diagonal().sum() == pytest.approx(0.3)
