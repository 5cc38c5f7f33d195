"""Mesh + mode-shape export (viz.export) and the ``iwanfe export`` command.

Round trips through meshio.read and through VTK's own readers (what ParaView uses); the
expected fibre displacements are recomputed here from the Euler-Bernoulli kinematics
``(u - zeta theta, 0, w)`` at each point's coordinates, independent of the point order.
"""
from __future__ import annotations

import numpy as np
import pytest

import cases.double_beam.model as db
from fe.interface import StripGeometry
from viz.export import mode_mesh, read_modes, write_modes

T, B, L = 1e-3, 0.05, 0.35


@pytest.fixture
def two_strips_three_modes():
    rng = np.random.default_rng(2024)
    x = np.sort(np.concatenate([[0.0, L], rng.uniform(0, L, 9)]))
    strips = [StripGeometry(x, -T / 2, T, B), StripGeometry(x, T / 2, T, B)]
    modes = [[{k: rng.normal(size=x.size) for k in ("u", "w", "theta")} for _ in strips]
             for _ in range(3)]
    freqs = np.array([9.04, 48.2, 121.5]) * rng.uniform(0.9, 1.1)
    return strips, modes, freqs


def _expected(points, strip_of_point, strips, mode):
    """Fibre displacement at each point from its own coordinates (nearest node in x)."""
    out = np.empty_like(points)
    for s, strip in enumerate(strips):
        sel = strip_of_point == s
        node = np.abs(points[sel, 0][:, None] - strip.x[None, :]).argmin(axis=1)
        assert np.allclose(strip.x[node], points[sel, 0])
        zeta = points[sel, 2] - strip.z_center
        d = mode[s]
        out[sel] = np.column_stack([d["u"][node] - zeta * d["theta"][node],
                                    np.zeros(node.size), d["w"][node]])
    return out


def _strip_of_point(mesh):
    cells, sid = mesh.cells[0].data, mesh.cell_data["strip"][0]
    owner = np.full(len(mesh.points), -1)
    for s in np.unique(sid):
        owner[np.unique(cells[sid == s])] = s
    assert np.all(owner >= 0)
    return owner


@pytest.mark.parametrize("suffix", [".vtu", ".xdmf"])
@pytest.mark.parametrize("geometry", ["lines", "slabs"])
def test_round_trip_through_meshio(tmp_path, two_strips_three_modes, suffix, geometry):
    strips, modes, freqs = two_strips_three_modes
    written = write_modes(tmp_path / f"m{suffix}", strips, modes, freqs, geometry=geometry)
    assert all(p.is_file() for p in written)
    mesh, f_read = read_modes(written[0])
    np.testing.assert_allclose(f_read, freqs, rtol=1e-15)
    n_nodes = sum(s.x.size for s in strips)
    n_el = sum(s.x.size - 1 for s in strips)
    assert mesh.cells[0].type == ("line" if geometry == "lines" else "hexahedron")
    assert len(mesh.points) == (n_nodes if geometry == "lines" else 4 * n_nodes)
    assert len(mesh.cells[0].data) == n_el
    owner = _strip_of_point(mesh)
    for k, mode in enumerate(modes, start=1):
        got = mesh.point_data[f"mode_{k}"]
        assert got.shape == (len(mesh.points), 3)
        np.testing.assert_allclose(got, _expected(mesh.points, owner, strips, mode),
                                   rtol=1e-13, atol=1e-15)
        if geometry == "lines":
            for sid, strip in enumerate(strips):
                sel = owner == sid
                node = np.abs(mesh.points[sel, 0][:, None] - strip.x[None, :]).argmin(axis=1)
                np.testing.assert_allclose(mesh.point_data[f"rotation_{k}"][sel],
                                           mode[sid]["theta"][node], rtol=1e-15)
    assert set(mesh.point_data) >= {"mode_1", "mode_2", "mode_3"}


def test_slab_cells_fill_the_true_volume(two_strips_three_modes):
    """Every hexahedron has positive volume and together they make 2 L t b."""
    import pyvista as pv

    strips, modes, _ = two_strips_three_modes
    grid = pv.from_meshio(mode_mesh(strips, modes, "slabs"))
    vol = grid.compute_cell_sizes(length=False, area=False)["Volume"]
    h = np.concatenate([np.diff(s.x) for s in strips])
    np.testing.assert_allclose(np.sort(vol), np.sort(h * T * B), rtol=1e-12)
    assert grid.volume == pytest.approx(2 * L * T * B, rel=1e-12)


def test_vtk_readers_see_modes_and_frequencies(tmp_path, two_strips_three_modes):
    """What ParaView reads: VTK's XML reader (field data too) and its XDMF reader."""
    import pyvista as pv
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

    strips, modes, freqs = two_strips_three_modes
    vtu = write_modes(tmp_path / "m.vtu", strips, modes, freqs, geometry="slabs")[0]
    grid = pv.read(vtu)
    np.testing.assert_allclose(grid.field_data["frequency_hz"], freqs)
    mesh, _ = read_modes(vtu)
    np.testing.assert_allclose(grid.point_data["mode_2"], mesh.point_data["mode_2"])

    xdmf = write_modes(tmp_path / "m.xdmf", strips, modes, freqs, geometry="lines")[0]
    reader = vtkXdmfReader()
    reader.SetFileName(str(xdmf))
    reader.Update()
    out = pv.wrap(reader.GetOutputDataObject(0))
    assert out.n_points == sum(s.x.size for s in strips)
    mesh, _ = read_modes(xdmf)
    np.testing.assert_allclose(out.point_data["mode_3"], mesh.point_data["mode_3"])


def test_bad_input(tmp_path, two_strips_three_modes):
    strips, modes, freqs = two_strips_three_modes
    with pytest.raises(ValueError, match="unknown export format '.vtk'"):
        write_modes(tmp_path / "m.vtk", strips, modes, freqs)
    with pytest.raises(ValueError, match="2 frequencies for 3 modes"):
        write_modes(tmp_path / "m.vtu", strips, modes, freqs[:2])
    with pytest.raises(ValueError, match="geometry"):
        mode_mesh(strips, modes, "points")
    with pytest.raises(ValueError, match="mode 1 has 1 strip"):
        mode_mesh(strips, [modes[0][:1]])


# --------------------------------------------------------------------- CLI


def test_cli_export_bad_suffix(capsys):
    from cli.main import main

    assert main(["export", "--case", "double-beam", "--out", "modes.vtk"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out modes.vtk: must end in .vtu or .xdmf" in err
    assert main(["export", "--out", "modes.vtu", "--modes", "0"]) == 2
    assert "--modes 0: must be in 1..39" in capsys.readouterr().err


@pytest.mark.parametrize("suffix", [".vtu", ".xdmf"])
def test_cli_export_double_beam(tmp_path, capsys, suffix):
    from cli.main import main

    out = tmp_path / f"db{suffix}"
    assert main(["export", "--case", "double-beam", "--out", str(out), "--modes", "4"]) == 0
    printed = capsys.readouterr().out
    assert "4 modes" in printed
    mesh, freqs = read_modes(out)
    # independent check: the Python model's eigen-solution (the case file's model equals
    # it to 2e-7: the calibrated grip's last digits), and the case model's displacements
    # (its strips start at the strip end, the clamped part included)
    omega_py, _ = db.build_double_beam(db.DoubleBeamConfig()).modes(4)
    np.testing.assert_allclose(freqs, omega_py / (2 * np.pi), rtol=1e-6)
    from cases.registry import resolve_case

    model = resolve_case("double-beam").fe_model()
    omega, shapes = model.modes(4)
    owner = _strip_of_point(mesh)
    for k in range(4):
        disp = model.strip_displacements(shapes[:, k])
        got = mesh.point_data[f"mode_{k + 1}"]
        want = _expected(mesh.points, owner, model.strips, disp)
        # eigenvectors are defined up to sign
        sign = np.sign(np.sum(got * want)) or 1.0
        np.testing.assert_allclose(sign * got, want, atol=1e-5 * np.abs(want).max())
