"""Case files whose interfaces cover part of a lap or lie side by side on one beam pair
(issue 20: these crashed with a Cholesky failure from a 1e-5 m sliver element), checked
against independent truth: adjacent interfaces equal the single interface they split
(the stiffness matrices are the same sum of springs), a part-tied lap lies between the
lap with only normal contact there and the fully tied lap (Rayleigh: adding stiffness
raises every eigenvalue), and a point snapped onto a neighbour's node equals the file
with the point exactly there."""
from __future__ import annotations

import numpy as np
import pytest

from casefile.build import build_model
from casefile.schema import read_case_file
from casefile.tables import CaseFileError

E, RHO, B, H, L = 70e9, 2700.0, 0.03, 0.005, 0.4
LAP = (0.16, 0.24)

JOINT = 'law = "iwan4"\nchi = -0.5\nbeta = 1.0\n'


def _lap(tmp_path, interfaces: list[str], extra: str = "", name="lap", rigid=3) -> np.ndarray:
    """First three elastic free-free frequencies (Hz) of a notched lap (BRB style) with
    the given [[interface]] bodies; ``rigid`` zero-frequency modes expected (a lap held
    only by frictionless contact adds a fourth: the halves slide along each other)."""
    text = f"""[case]
name = "{name}"
[[material]]
name = "al"
E = {E}
rho = {RHO}
[[beam]]
name = "left"
material = "al"
x = [0.0, {LAP[1]}]
width = {B}
thickness = {H}
[[beam.section]]
x = [{LAP[0]}, {LAP[1]}]
thickness = {H / 2}
z = {-H / 4}
[[beam]]
name = "right"
material = "al"
x = [{LAP[0]}, {L}]
width = {B}
thickness = {H}
[[beam.section]]
x = [{LAP[0]}, {LAP[1]}]
thickness = {H / 2}
z = {H / 4}
""" + "".join(f'[[interface]]\nbeams = ["left", "right"]\n{body}\n' for body in interfaces)
    text += extra + """
[mesh]
element_size = 0.005
"""
    p = tmp_path / f"{name}.toml"
    p.write_text(text)
    model = build_model(read_case_file(p)).model
    omega, _ = model.modes(10)
    assert np.all(omega[:rigid] < 1e-3 * omega[rigid])   # the rigid-body modes, no more
    return omega[rigid:rigid + 3] / (2 * np.pi)


def _itf(x0, x1, normal="tied", tangential="tied", more=""):
    return f'x = [{x0}, {x1}]\nnormal = "{normal}"\ntangential = "{tangential}"\n{more}'


def test_adjacent_tied_interfaces_equal_the_single_tied_interface(tmp_path):
    one = _lap(tmp_path, [_itf(*LAP)], name="one")
    three = _lap(tmp_path, [_itf(0.16, 0.18), _itf(0.18, 0.22), _itf(0.22, 0.24)], name="three")
    np.testing.assert_allclose(three, one, rtol=1e-8)    # round-off of the split sums


def test_adjacent_joint_interfaces_equal_the_joint_interface_they_split(tmp_path):
    """kt split by length, elements at the same positions: the shared end node takes half
    its share from each side, so the joint springs are the same."""
    kt = 2.0e9
    one = _lap(tmp_path, [_itf(*LAP, tangential="joint",
                               more=f"joint_elements = 17\nkt = {kt}\nfs = 100.0\n" + JOINT)],
               name="one")
    two = _lap(tmp_path, [_itf(0.16, 0.20, tangential="joint",
                               more=f"joint_elements = 9\nkt = {kt / 2}\nfs = 50.0\n" + JOINT),
                          _itf(0.20, 0.24, tangential="joint",
                               more=f"joint_elements = 9\nkt = {kt / 2}\nfs = 50.0\n" + JOINT)],
               name="two")
    np.testing.assert_allclose(two, one, rtol=1e-8)    # round-off of the split sums, ~2e-9


def test_part_tied_lap_lies_between_contact_only_and_fully_tied(tmp_path):
    """Interface over the middle of the lap only (ends open): tying it raises every
    frequency above the same lap with frictionless contact there, and tying the ends
    too raises them further (the fully tied lap, which equals the monolithic beam)."""
    ends_open = [_itf(0.18, 0.22, tangential="free")]
    lower = _lap(tmp_path, ends_open, name="lower", rigid=4)
    part = _lap(tmp_path, [_itf(0.18, 0.22)], name="part")
    full = _lap(tmp_path, [_itf(0.16, 0.18), _itf(0.18, 0.22), _itf(0.22, 0.24)], name="full")
    assert np.all(lower < part) and np.all(part < full)
    beta_l = np.array([4.7300407449, 7.8532046241, 10.9956078380])
    monolithic = beta_l**2 / (2 * np.pi * L**2) * np.sqrt(E * H**2 / (12 * RHO))
    np.testing.assert_allclose(full, monolithic, rtol=2e-3)
    assert part[0] < 0.97 * full[0]      # the open lap ends do soften the first mode


def test_lap_with_stiff_stuck_joints_equals_the_monolithic_beam(tmp_path):
    """Normal contact tied and joint elements 1e3 times stiffer than the layers over the
    whole lap: the uniform strip's free-free frequencies (beta L = 4.7300, 7.8532,
    10.9956) within 1e-3 and below them (the joints are finite). Springs on the gap at the
    nodes alone let the layers turn against each other there: 2.4 % low at every mesh."""
    joints = _itf(*LAP, tangential="joint",
                  more="joint_elements = 33\nkt = 1e12\nfs = 100.0\n" + JOINT)
    f = _lap(tmp_path, [joints], name="stuck")
    beta_l = np.array([4.7300407449, 7.8532046241, 10.9956078380])
    monolithic = beta_l**2 / (2 * np.pi * L**2) * np.sqrt(E * H**2 / (12 * RHO))
    np.testing.assert_allclose(f, monolithic, rtol=1e-3)
    assert np.all(f < monolithic)


def test_a_point_next_to_a_joint_shares_its_node(tmp_path):
    """A mass 1e-5 m from a joint element (the crash of issue 20) is put on the joint's
    node: the model equals the one with the mass exactly there."""
    joint = _itf(*LAP, tangential="joint",
                 more="joint_elements = 9\nkt = 1e9\nfs = 100.0\n" + JOINT)
    x_joint = 0.16 + 4 * 0.01

    def mass(x):
        return f'[[mass]]\nbeam = "right"\nx = {x}\nmass = 0.02\nlabel = "bolt"\n'
    near = _lap(tmp_path, [joint], mass(x_joint + 1e-5), name="near")
    exact = _lap(tmp_path, [joint], mass(x_joint), name="exact")
    np.testing.assert_allclose(near, exact, rtol=1e-12)


def test_range_ends_closer_than_the_snap_distance_are_refused(tmp_path):
    with pytest.raises(CaseFileError, match=r"\[interface\.1\] x: .* from interface\.0\.x"):
        _lap(tmp_path, [_itf(0.16, 0.20), _itf(0.20001, 0.24)], name="gap")


def test_shipped_patch_layout_builds():
    """The shipped BRB (stuck bolt patch, open lap ends) has exactly three rigid-body
    modes and stuck-stiffness shares summing to 1."""
    built = build_model(read_case_file("cases/brb/brb.toml"))
    omega, _ = built.model.modes(6)
    assert np.all(omega[:3] < 1e-3 * omega[3])
    assert sum(j["share"] for j in built.joint_table) == pytest.approx(1.0, rel=1e-12)


BOLTED_LAP = """[case]
name = "al-lap"
[[material]]
name = "al6061"
E = 69e9
rho = 2700.0
[[beam]]
name = "left"
material = "al6061"
x = [0.0, 0.250]
width = 0.040
thickness = 0.008
[[beam]]
name = "right"
material = "al6061"
x = [0.190, 0.440]
width = 0.040
thickness = 0.008
z = 0.008
[[interface]]
beams = ["left", "right"]
x = [0.190, 0.250]
normal = "{normal}"
tangential = "joint"
joints_at = [0.205, 0.235]
law = "iwan4"
kt = 2.0e7
[[mass]]
beam = "left"
x = 0.0
mass = 0.005
label = "force-gauge"
[mesh]
element_size = 0.004
"""


def _bolted_lap(tmp_path, normal: str, sizes) -> list[np.ndarray]:
    """Free-free modes (Hz) of an outside user's two-bolt aluminium lap on each mesh."""
    import dataclasses

    p = tmp_path / f"lap-{normal}.toml"
    p.write_text(BOLTED_LAP.format(normal=normal))
    cf = read_case_file(p)
    out = []
    for h in sizes:
        omega, _ = build_model(dataclasses.replace(cf, element_size=h)).model.modes(9)
        out.append(omega / (2 * np.pi))
    return out


def test_tied_lap_converges_under_mesh_refinement(tmp_path):
    """Second meshes as truth: the first mode's steps shrink at every halving, and 4 mm is
    within 1e-5 of 0.5 mm. With the rotation tie a fixed stiffness per unit length its 70
    um boundary layer was resolved more and more: 213.9448, 213.9439, 213.9422, 213.9384
    Hz, growing steps."""
    f1 = np.array([f[f > 1.0][0]
                   for f in _bolted_lap(tmp_path, "tied", [0.004, 0.002, 0.001, 0.0005])])
    steps = np.abs(np.diff(f1))
    assert np.all(steps[1:] < 0.7 * steps[:-1]), f1
    np.testing.assert_allclose(f1[0], f1[-1], rtol=1e-5)


def test_open_lap_spectrum_is_the_same_on_every_mesh(tmp_path):
    """Open normal, two bolts: 5 rigid-body modes (the two layers' u and w rigid motions,
    the bolts' slips all equal on them), then the two layers' first bending modes, the
    same on every mesh (the 4 mm mesh as truth; the layers are uniform between nodes).
    At 1.2 mm a sixth zero mode replaced the 634 Hz one, at 1 mm it was 635.18 Hz."""
    meshes = _bolted_lap(tmp_path, "open", [0.004, 0.0015, 0.0012, 0.001])
    for f in meshes:
        assert np.sum(f < 1.0) == 5
        np.testing.assert_allclose(f[5:7], meshes[0][5:7], rtol=1e-6)


GLUED_STACK = """[case]
name = "glued-steel-freefree"
[[material]]
name = "steel"
E = 210e9
rho = 7850.0
[[beam]]
name = "bottom"
material = "steel"
x = [0.0, 0.400]
width = 0.020
thickness = 0.004
[[beam]]
name = "top"
material = "steel"
x = [0.0, 0.400]
width = 0.020
thickness = 0.004
z = 0.004
[[interface]]
beams = ["bottom", "top"]
x = [0.0, 0.400]
normal = "tied"
tangential = "joint"
joint_elements = 5
law = "iwan4"
kt = {kt}
[mesh]
element_size = 0.005
"""


def test_very_stiff_glue_gives_the_stiff_limit_or_one_line_naming_kt(tmp_path):
    """An outside user's glued steel stack: kt = 1e16 N/m failed with a bare Cholesky
    error (484-th leading minor). Truth: the stiff limit, which kt = 1e15 reaches to 1e-6
    (the frequencies move as the glue-slip share, 1e-7 at 1e15, which falls as 1/kt); kt =
    1e18 (a joint element 7e7 times the stiffest strip element) is refused in one line
    naming [interface.0] kt."""
    def modes(kt):
        p = tmp_path / f"glued-{kt:g}.toml"
        p.write_text(GLUED_STACK.format(kt=kt))
        model = build_model(read_case_file(p)).model
        omega, shapes = model.modes(8)
        return omega / (2 * np.pi), model.glue_slip_participation(shapes[:, 3])

    f15, p15 = modes(1e15)
    f16, p16 = modes(1e16)
    assert np.all(f16[:3] < 1.0) and np.all(f15[:3] < 1.0)        # 3 rigid-body modes
    np.testing.assert_allclose(f16[3:], f15[3:], rtol=1e-6)
    assert p16 == pytest.approx(p15 / 10, rel=1e-2)
    with pytest.raises(CaseFileError, match=r"\[interface\.0\] kt: 1e\+18 N/m .* 7\.4e\+07 times"):
        modes(1e18)
