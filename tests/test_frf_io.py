"""FRF files: CSV and UFF 58 readers/writers (ident.frf_files)."""
from __future__ import annotations

import numpy as np
import pytest

from ident.errors import InputError
from ident.frf_files import FRFSet, read_frf, read_frf_csv, write_frf, write_frf_csv, write_frf_uff


def random_set(n=41, points=("1+Z", "7+Z", "12-Y"), seed=0, **kw):
    rng = np.random.default_rng(seed)
    f = 20.0 + 0.5 * np.arange(n)
    H = (rng.standard_normal((n, len(points))) + 1j * rng.standard_normal((n, len(points))))
    return FRFSet(f, H * 10.0 ** rng.uniform(-8, -3, len(points)), list(points), **kw)


def test_csv_round_trip_is_exact(tmp_path):
    s = random_set(quantity="mobility", excitation=2.5, reference="1+Z")
    p = tmp_path / "a.csv"
    write_frf_csv(p, s)
    r = read_frf(p)
    np.testing.assert_array_equal(r.freq_hz, s.freq_hz)
    np.testing.assert_array_equal(r.frf, s.frf)
    assert (r.points, r.quantity, r.excitation, r.reference) == (
        s.points, "mobility", 2.5, "1+Z")
    text = p.read_text().splitlines()
    assert text[3] == "freq_hz,re_1+Z,im_1+Z,re_7+Z,im_7+Z,re_12-Y,im_12-Y"


def test_uff_round_trip(tmp_path):
    s = random_set(quantity="accelerance", excitation=0.125, reference="3+X")
    p = tmp_path / "a.uff"
    write_frf_uff(p, s)
    r = read_frf(p)
    np.testing.assert_allclose(r.freq_hz, s.freq_hz, rtol=1e-12)
    np.testing.assert_allclose(r.frf, s.frf, rtol=1e-11)      # 12 significant digits
    assert (r.points, r.quantity, r.excitation, r.reference) == (
        s.points, "accelerance", 0.125, "3+X")
    # one data set 58 per point; the file is plain text
    assert p.read_text().count("\n    58") == 3


def test_uff_written_by_pyuff_directly(tmp_path):
    """A file made with pyuff alone (uneven abscissa, one time series that is not an
    FRF) reads as the FRFs it holds, abscissa to the format's 6 digits."""
    import pyuff

    rng = np.random.default_rng(1)
    f = np.sort(rng.uniform(100.0, 200.0, 30))
    H = rng.standard_normal((30, 2)) + 1j * rng.standard_normal((30, 2))
    sets = [dict(type=58, func_type=1, rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3,
                 x=np.arange(30.0), data=rng.standard_normal(30), abscissa_spacing=1,
                 id1="time", binary=0, orddenom_spec_data_type=0)]
    for j, (node, d) in enumerate([(5, 2), (9, -3)]):
        sets.append(dict(type=58, func_type=4, rsp_node=node, rsp_dir=d, ref_node=2,
                         ref_dir=3, x=f, data=H[:, j], abscissa_spacing=0,
                         ordinate_spec_data_type=12, orddenom_spec_data_type=13,
                         id1="frf", id3="excitation = 4", binary=0))
    p = tmp_path / "ext.unv"
    pyuff.UFF(str(p)).write_sets(sets, mode="overwrite")
    r = read_frf(p)
    assert r.points == ["5+Y", "9-Z"] and r.reference == "2+Z"
    assert r.quantity == "accelerance" and r.excitation == 4.0
    np.testing.assert_allclose(r.freq_hz, f, rtol=5e-6)
    np.testing.assert_allclose(r.frf, H, rtol=1e-10)


def test_format_sniffed_without_extension(tmp_path):
    s = random_set()
    write_frf_uff(tmp_path / "x.uff", s)
    write_frf_csv(tmp_path / "x.csv", s)
    (tmp_path / "u").write_bytes((tmp_path / "x.uff").read_bytes())
    (tmp_path / "c").write_bytes((tmp_path / "x.csv").read_bytes())
    np.testing.assert_allclose(read_frf(tmp_path / "u").frf, s.frf, rtol=1e-11)
    np.testing.assert_array_equal(read_frf(tmp_path / "c").frf, s.frf)
    write_frf(tmp_path / "y.csv", s)
    assert (tmp_path / "y.csv").read_text().startswith("freq_hz,")


def _csv(tmp_path, text, name="e.csv"):
    p = tmp_path / name
    p.write_text(text)
    with pytest.raises(InputError) as info:
        read_frf_csv(p)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"{p}:")
    return msg[len(str(p)) + 1:]


def test_csv_errors_name_line_and_column(tmp_path):
    ok = "freq_hz,re_1,im_1\n10,1,2\n11,1,2\n"
    assert _csv(tmp_path, "") == "1:1: empty file: expected a header line"
    assert _csv(tmp_path, "freq,re_1,im_1\n10,1,2\n11,1,2\n") == \
        "1:freq: first column must be 'freq_hz'"
    assert _csv(tmp_path, "freq_hz,re_1,im_2\n10,1,2\n11,1,2\n") == \
        "1:re_1: no matching column im_1"
    assert _csv(tmp_path, "freq_hz,re_1,im_1,mag_1\n").startswith("1:mag_1: unknown column")
    assert _csv(tmp_path, ok.replace("11,1,2", "11,x,2")) == "3:re_1: not a number: 'x'"
    assert _csv(tmp_path, ok.replace("11,1,2", "11,1,nan")) == \
        "3:im_1: not a finite number: 'nan'"
    assert _csv(tmp_path, ok.replace("11,1,2", "10,1,2")) == \
        "3:freq_hz: frequencies must be strictly increasing"
    assert _csv(tmp_path, ok.replace("11,1,2", "11,1")) == "3:3: row has 2 fields, header has 3"
    assert _csv(tmp_path, "# quantity = inertance\n" + ok).startswith(
        "1:quantity: must be one of receptance, mobility, accelerance")
    assert _csv(tmp_path, "# excitation = -1\n" + ok).startswith(
        "1:excitation: excitation must be a finite number > 0")
    assert _csv(tmp_path, "# level = 3\n" + ok).startswith("1:level: unknown key")
    assert _csv(tmp_path, "\n# quantity = mobility\n" + ok.replace("10,1,2", "0,1,2")) == \
        "4:freq_hz: frequency must be > 0 Hz, got 0"


def test_uff_errors(tmp_path):
    import pyuff

    p = tmp_path / "bad.uff"
    p.write_text("    -1\n    58\nthis is not a data set\n    -1\n")
    with pytest.raises(InputError, match="bad.uff: "):
        read_frf(p)
    sets = [dict(type=58, func_type=4, rsp_node=k, rsp_dir=3, ref_node=k, ref_dir=3,
                 x=np.arange(1.0, 11.0), data=np.ones(10, complex), abscissa_spacing=1,
                 binary=0, orddenom_spec_data_type=13) for k in (1, 2)]
    q = tmp_path / "two_refs.uff"
    pyuff.UFF(str(q)).write_sets(sets, mode="overwrite")
    with pytest.raises(InputError, match="2 references"):
        read_frf(q)
    with pytest.raises(InputError, match="no such file"):
        read_frf(tmp_path / "none.uff")


# ------------------------------------------------ header keys of a stepped-sine series

def test_series_header_keys_and_force_column_round_trip(tmp_path):
    """control, run_order, excitation, reference and the force column survive CSV
    exactly; UFF keeps the keys in an ID line (no force column there)."""
    s = random_set(quantity="accelerance", excitation=3.25e-3, reference="1+Z",
                   control="response", run_order=7)
    s.force = np.linspace(0.5, 2.0, s.freq_hz.size)
    p = tmp_path / "level.csv"
    write_frf_csv(p, s)
    text = p.read_text().splitlines()
    assert text[:5] == ["# quantity = accelerance", "# control = response", "# run_order = 7",
                        "# excitation = 0.00325", "# reference = 1+Z"]
    assert text[5].endswith(",force")
    r = read_frf(p)
    assert (r.control, r.run_order, r.excitation, r.reference) == ("response", 7, 3.25e-3, "1+Z")
    np.testing.assert_array_equal(r.force, s.force)
    np.testing.assert_array_equal(r.frf, s.frf)
    s.force = None
    write_frf_uff(tmp_path / "level.uff", s)
    u = read_frf(tmp_path / "level.uff")
    assert (u.control, u.run_order, u.excitation, u.reference, u.force) == (
        "response", 7, 3.25e-3, "1+Z", None)
    s.force = np.ones(s.freq_hz.size)
    with pytest.raises(ValueError, match="no force column"):
        write_frf_uff(tmp_path / "x.uff", s)


def test_uff_keys_in_any_id_line_and_reference_label(tmp_path):
    import pyuff

    f = np.linspace(70.0, 90.0, 41)
    sets = [dict(type=58, func_type=4, rsp_node=3, rsp_dir=3, ref_node=3, ref_dir=3, x=f,
                 data=np.exp(1j * f), abscissa_spacing=1, binary=0,
                 orddenom_spec_data_type=13, id1="bolted beam",
                 id2="control=Response run_order=4", id5="excitation=2e-3; reference=drive")]
    p = tmp_path / "k.unv"
    pyuff.UFF(str(p)).write_sets(sets, mode="overwrite")
    r = read_frf(p)
    assert (r.control, r.run_order, r.excitation, r.reference) == ("response", 4, 2e-3, "drive")


def test_series_header_errors(tmp_path):
    ok = "freq_hz,re_1,im_1\n10,1,2\n11,1,2\n"
    assert _csv(tmp_path, "# control = voltage\n" + ok) == \
        "1:control: control must be force or response, got 'voltage'"
    assert _csv(tmp_path, "# run_order = 2.5\n" + ok) == \
        "1:run_order: run_order must be an integer >= 1, got '2.5'"
    assert _csv(tmp_path, "# run_order = 0\n" + ok).startswith("1:run_order:")
    assert _csv(tmp_path, "freq_hz,re_1,im_1,force\n10,1,2,0.5\n11,1,2,0\n") == \
        "3:force: force must be > 0 N, got 0"
    assert _csv(tmp_path, "freq_hz,re_1,im_1,force,force\n10,1,2,1,1\n11,1,2,1,1\n") == \
        "1:force: duplicate column name"


def test_command_line_values_override_the_file(tmp_path):
    from ident.frf_header import with_overrides

    s = random_set(excitation=1.0, control="force", run_order=2, reference="1+Z")
    t = with_overrides(s, excitation=4.0, control="response", run_order=9, reference="7+Z")
    assert (t.excitation, t.control, t.run_order, t.reference) == (4.0, "response", 9, "7+Z")
    assert (s.excitation, s.control) == (1.0, "force")          # the file's set unchanged
    assert with_overrides(s).excitation == 1.0
    with pytest.raises(InputError, match="excitation must be"):
        with_overrides(s, excitation=-2.0)
    with pytest.raises(InputError, match="control must be"):
        with_overrides(s, control="amplitude")
