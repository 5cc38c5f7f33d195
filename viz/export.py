"""Mesh export of beam mode shapes for ParaView: .vtu and .xdmf through meshio.

The strips are written either as their centroid lines (``geometry="lines"``: one point
per FE node, line cells) or as hexahedral slabs of their true thickness and width
(``geometry="slabs"``: the corner fibres, see :func:`viz.slab.slab_fields`). Every
mode ``k`` (1-based) becomes the point-data 3-vector ``mode_k`` = displacement
``(u_x, 0, u_z)`` in m (mode-shape units); in "lines" geometry ``rotation_k`` holds the
rotation ``theta = dw/dx`` (rad) as well. Cell data ``strip`` numbers the strips from 0.

Frequencies: every mode ``k`` comes with the point-data scalar ``frequency_hz_k`` (Hz,
the same at every point), in both formats, so any XDMF or VTU reader, ``meshio.read``
included, finds mode and frequency side by side (meshio writes and reads no XDMF field
data). The .vtu also holds them as a VTK ``<FieldData>`` array ``frequency_hz`` (ParaView
shows it under Field Data). :func:`read_modes` returns them.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from viz.slab import slab_fields

__all__ = ["EXPORT_SUFFIXES", "mode_mesh", "write_modes", "read_modes"]

EXPORT_SUFFIXES = (".vtu", ".xdmf")


def _line_block(strip, disp):
    x = np.asarray(strip.x, dtype=float)
    n = x.size
    points = np.column_stack([x, np.zeros(n), np.full(n, float(strip.z_center))])
    if disp is None:
        vec, rot = None, None
    else:
        u, w, th = (np.asarray(disp[k], dtype=float) for k in ("u", "w", "theta"))
        if not (u.shape == w.shape == th.shape == (n,)):
            raise ValueError(f"displacement arrays must have shape ({n},) like strip.x")
        vec = np.column_stack([u, np.zeros(n), w])
        rot = th
    cells = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    return points, cells, vec, rot


def _slab_block(strip, disp):
    f = slab_fields(strip, disp, subdivisions=1)
    m = f.x.size
    points = f.points.reshape(-1, 3)  # index 4 i + 2 j + k  (station, side, face)
    vec = None if disp is None else f.displacement.reshape(-1, 3)
    i = np.arange(m - 1)[:, None]
    # VTK hexahedron: bottom face (z0) counter-clockwise, then top face (z1)
    corner = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                       [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
    cells = 4 * (i + corner[None, :, 0]) + 2 * corner[None, :, 1] + corner[None, :, 2]
    return points, cells, vec, None


def mode_mesh(strips: Sequence, modes: Sequence[Sequence[Mapping]], geometry: str = "lines",
              frequencies_hz=None):
    """Build a :class:`meshio.Mesh` of the strips with every mode as point data.

    Parameters
    ----------
    strips : sequence of strip geometries
        Objects with ``x`` (n_nodes,), ``z_center``, ``thickness``, ``width`` (m).
    modes : sequence over modes of sequences over strips of mappings
        ``modes[k][s]`` = ``{'u', 'w', 'theta'}`` nodal arrays of strip ``s`` in mode
        ``k`` (m, m, rad; ``theta = dw/dx``).
    geometry : {"lines", "slabs"}
        Centroid lines (exact FE data) or hexahedral slabs (fibre displacements
        ``u - zeta theta``, Euler-Bernoulli).
    frequencies_hz : array_like, shape (n_modes,), optional
        Natural frequencies (Hz): point data ``frequency_hz_k`` (constant).

    Returns
    -------
    meshio.Mesh
        Point data ``mode_1..mode_K`` (n_points, 3), ``rotation_k`` for lines,
        ``frequency_hz_k`` if given; cell data ``strip``.
    """
    import meshio

    if geometry not in ("lines", "slabs"):
        raise ValueError(f"geometry must be 'lines' or 'slabs', got '{geometry}'")
    if not strips:
        raise ValueError("no strips to export")
    for k, mode in enumerate(modes, start=1):
        if len(mode) != len(strips):
            raise ValueError(f"mode {k} has {len(mode)} strip displacements, "
                             f"expected {len(strips)}")
    block = _line_block if geometry == "lines" else _slab_block
    points, cells, strip_id = [], [], []
    vecs = [[] for _ in modes]
    rots = [[] for _ in modes]
    offset = 0
    for s, strip in enumerate(strips):
        p, c, _, _ = block(strip, None)
        points.append(p)
        cells.append(c + offset)
        strip_id.append(np.full(len(c), s, dtype=np.int32))
        for k, mode in enumerate(modes):
            _, _, v, r = block(strip, mode[s])
            vecs[k].append(v)
            rots[k].append(r)
        offset += len(p)
    cell_type = "line" if geometry == "lines" else "hexahedron"
    point_data = {}
    n_points = sum(len(p) for p in points)
    for k in range(len(modes)):
        point_data[f"mode_{k + 1}"] = np.concatenate(vecs[k])
        if geometry == "lines":
            point_data[f"rotation_{k + 1}"] = np.concatenate(rots[k])
        if frequencies_hz is not None:
            point_data[f"frequency_hz_{k + 1}"] = np.full(n_points, float(frequencies_hz[k]))
    return meshio.Mesh(
        np.concatenate(points), [(cell_type, np.concatenate(cells))],
        point_data=point_data, cell_data={"strip": [np.concatenate(strip_id)]},
    )


def _add_vtu_field_data(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Insert a VTK ``<FieldData>`` block (ascii Float64 arrays) into a meshio .vtu."""
    tree = ET.parse(path)
    grid = tree.getroot().find("UnstructuredGrid")
    if grid is None:
        raise ValueError(f"{path}: not a VTK UnstructuredGrid file")
    fd = ET.Element("FieldData")
    for name, values in arrays.items():
        values = np.atleast_1d(np.asarray(values, dtype=np.float64))
        da = ET.SubElement(fd, "DataArray", type="Float64", Name=name,
                           NumberOfTuples=str(values.size), format="ascii")
        da.text = " ".join(repr(float(v)) for v in values)
    grid.insert(0, fd)
    tree.write(path, xml_declaration=True, encoding="utf-8")


def write_modes(path, strips: Sequence, modes: Sequence[Sequence[Mapping]],
                frequencies_hz=None, geometry: str = "lines") -> list[Path]:
    """Write the strips and their mode shapes to ``.vtu`` or ``.xdmf``.

    Parameters
    ----------
    path : str or Path
        Output file; its suffix picks the format (``.vtu`` or ``.xdmf``).
    strips, modes, geometry
        As in :func:`mode_mesh`.
    frequencies_hz : array_like, shape (n_modes,), optional
        Natural frequencies, Hz: point data ``frequency_hz_k`` (and .vtu field data
        ``frequency_hz``).

    Returns
    -------
    list of Path
        The files written (``.xdmf`` comes with its ``.h5``).
    """
    import meshio

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise ValueError(
            f"unknown export format '{path.suffix or path.name}': use one of "
            + ", ".join(EXPORT_SUFFIXES)
        )
    freqs = None
    if frequencies_hz is not None:
        freqs = np.asarray(frequencies_hz, dtype=float).ravel()
        if freqs.size != len(modes):
            raise ValueError(f"{freqs.size} frequencies for {len(modes)} modes")
    mesh = mode_mesh(strips, modes, geometry, freqs)
    if not path.parent.is_dir():
        raise ValueError(f"{path}: folder {path.parent} does not exist")
    if suffix == ".vtu":
        meshio.write(path, mesh, file_format="vtu")
        if freqs is not None:
            _add_vtu_field_data(path, {"frequency_hz": freqs})
        return [path]
    meshio.write(path, mesh, file_format="xdmf")
    return [path, path.with_suffix(".h5")]


def read_modes(path):
    """Read a file written by :func:`write_modes` (``meshio.read`` and the point data
    ``frequency_hz_k``).

    Returns
    -------
    mesh : meshio.Mesh
    frequencies_hz : ndarray or None
    """
    import meshio

    mesh = meshio.read(Path(path))
    n = sum(1 for name in mesh.point_data if name.startswith("mode_"))
    names = [f"frequency_hz_{k}" for k in range(1, n + 1)]
    if n and all(name in mesh.point_data for name in names):
        freqs = [float(np.asarray(mesh.point_data[name]).ravel()[0]) for name in names]
    else:
        freqs = mesh.field_data.get("frequency_hz")
    return mesh, None if freqs is None else np.asarray(freqs, dtype=float)
