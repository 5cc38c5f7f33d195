"""Every input answered (issue 15): each row of the issue's table, the output-path rule,
the scheduler checks, help texts, ``--json`` everywhere, and the XDMF frequencies.

Truth: the issue's own table (what each input did before), the README's rules, and for
the numbers an independent computation (meshio's reader for the export, a socket that
never answers for the scheduler timeout).
"""
from __future__ import annotations

import contextlib
import io
import json
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from cli.main import COMMANDS, build_parser, main
from ident.frf_files import write_frf_uff
from runs.scheduler import check_scheduler, connect_client

ROOT = Path(__file__).resolve().parents[1]
MEASURED = str(ROOT / "cases/data/double_beam_measured.csv")
JOINT = ["joint", "--chi", "-0.5", "--kt", "1.1e5", "--fs", "400", "--beta", "4"]


def run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def refused(argv, *words):
    """Exit 2, nothing on stdout, one line on stderr holding ``words``."""
    rc, out, err = run(argv)
    assert rc == 2, (argv, rc, err)
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)
    return err


# ------------------------------------------------------------------------ the table


@pytest.mark.parametrize("extra, words", [
    (["--kt", "1e300"], ["K_T = 1e+300", "outside double precision"]),
    (["--fs", "1e-300"], ["F_S = 1e-300", "outside double precision"]),
    (["--amplitude", "1e300"], ["--amplitude", "1e+300", "underflows"]),
    (["--amplitude", "-1e-3"], ["--amplitude -0.001", "> 0"]),
])
def test_joint_rows(extra, words):
    refused(JOINT + extra, *words)


def test_identify_max_order_rows(tmp_path):
    from fuzz import frf_set

    path = tmp_path / "set.uff"
    write_frf_uff(path, frf_set(n_lines=200))
    for order in ("100000", "1000"):
        t0 = time.perf_counter()
        refused(["identify", str(path), "--max-order", order], f"--max-order {order}",
                "set.uff", "200 lines", "1..50")
        assert time.perf_counter() - t0 < 30   # no 149 GiB, no 300 s


@pytest.mark.parametrize("fraction, data_set", [(0.99, 2), (0.45, 1)])
def test_uff_cut_inside_a_data_set_rows(tmp_path, fraction, data_set):
    """A 2-point file cut at 99 % (inside data set 2) or 45 % (inside data set 1) gave
    fewer response points with exit 0; now refused with file, data set and what is
    missing."""
    from fuzz import frf_set

    whole = tmp_path / "whole.uff"
    write_frf_uff(whole, frf_set(n_lines=60, n_points=2))
    data = whole.read_bytes()
    cut = tmp_path / "cut.uff"
    cut.write_bytes(data[:int(fraction * len(data))])
    refused(["identify", str(cut)], "cut.uff", f"data set {data_set} (type 58)",
            "no closing '    -1' line")
    # a data set missing lines in the middle: refused with the count
    lines = data.split(b"\n")
    middle = tmp_path / "short.uff"
    middle.write_bytes(b"\n".join(lines[:20] + lines[25:]))
    refused(["identify", str(middle)], "short.uff", "data set 1", "of the 60 values")


def test_reproduce_band_row(tmp_path):
    """``--band 300 400`` ran the whole campaign, then a RuntimeError traceback; now
    refused before any work: no store is written."""
    out = tmp_path / "db"
    t0 = time.perf_counter()
    refused(["reproduce", "double-beam", "--band", "300", "400", "--out", str(out)],
            "--band 300 400", "must hold the measured mode")
    assert time.perf_counter() - t0 < 60 and not out.exists()


def test_scheduler_file_row(tmp_path):
    """``--scheduler nofile.json`` hung at 0/12; now refused in seconds."""
    t0 = time.perf_counter()
    refused(["reproduce", "lumped", "--scheduler", str(tmp_path / "nofile.json"), "--out",
             str(tmp_path / "l")], "--scheduler", "nofile.json", "does not exist")
    assert time.perf_counter() - t0 < 30 and not (tmp_path / "l").exists()


def test_modes_element_size_row():
    refused(["modes", "--element-size", "1e-5"], "--element-size 1e-05", "round-off")


def test_export_to_a_missing_root_folder_row(tmp_path):
    target = Path("/nonexistent-iwanfe-test")
    assert not target.exists()
    refused(["export", "--out", str(target / "m.vtu")], "--out", "does not exist")
    assert not target.exists()


@pytest.mark.parametrize("command", ["estimate", "identify", "diagnose"])
def test_binary_garbage_rows(tmp_path, command):
    path = tmp_path / "garbage.csv"
    path.write_bytes(bytes(np.random.default_rng(3).integers(0, 256, 3000, dtype=np.uint8)))
    refused([command, str(path)], str(path), "not a")


# ------------------------------------------------------------------------ output paths


def test_output_path_rule(tmp_path):
    from cli import validate

    # files: the folder must exist, nothing is created
    refused(JOINT + ["--plot", str(tmp_path / "no" / "loops.png")], "does not exist")
    assert not (tmp_path / "no").exists()
    with pytest.raises(ValueError, match="is a folder"):
        validate.output_file(tmp_path, "--out")
    # folders: created with parents below an existing folder, never in the root
    assert validate.output_dir(tmp_path / "a" / "b", "--out") == tmp_path / "a" / "b"
    assert not (tmp_path / "a").exists()            # checked, not created
    with pytest.raises(ValueError, match="filesystem root"):
        validate.output_dir("/nonexistent-iwanfe-test/out", "--out")
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="not a folder"):
        validate.output_dir(tmp_path / "f", "--out")
    for argv in (["convergence"], ["diagnose", MEASURED], ["uncertainty"],
                 ["reproduce", "lumped"]):
        refused(argv + ["--out", "/nonexistent-iwanfe-test/out"], "--out", "filesystem root")


# ------------------------------------------------------------------------ scheduler


def test_scheduler_checks_are_bounded_in_time(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ConnectionError, match="not a dask scheduler file"):
        check_scheduler(str(bad))
    with pytest.raises(ConnectionError, match="port in 1-65535"):
        check_scheduler("tcp://127.0.0.1:99999")
    with pytest.raises(ConnectionError, match="cannot connect"):
        check_scheduler("tcp://127.0.0.1:9")
    # a peer that accepts and never answers: the handshake times out, one line
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    port = server.getsockname()[1]
    t0 = time.perf_counter()
    with pytest.raises(ConnectionError, match="no answer within 1 s"):
        connect_client(f"tcp://127.0.0.1:{port}", timeout=1.0)
    assert time.perf_counter() - t0 < 15
    # one that answers with something else than dask
    talker = socket.socket()
    talker.bind(("127.0.0.1", 0))
    talker.listen(4)

    def greet():
        conn, _ = talker.accept()
        conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")
    threading.Thread(target=greet, daemon=True).start()
    with pytest.raises(ConnectionError, match="does not speak the dask protocol"):
        check_scheduler(f"tcp://127.0.0.1:{talker.getsockname()[1]}", timeout=1.0)
    server.close()
    talker.close()


def test_scheduler_without_workers_is_refused():
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None,
                      protocol="tcp://", host="127.0.0.1") as cluster:
        t0 = time.perf_counter()
        with pytest.raises(ConnectionError, match="has no worker"):
            connect_client(cluster.scheduler_address, timeout=1.0)
        assert time.perf_counter() - t0 < 15


# ------------------------------------------------------------------------ help, --json


def _help_texts():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return {name: p.format_help() for name, p in sub.choices.items()}


def test_help_prints_each_default_once():
    texts = _help_texts()
    assert set(texts) == set(COMMANDS)
    for name, text in texts.items():
        flat = " ".join(text.split())
        assert "%%" not in flat, name
        assert "(default: None)" not in flat and "(default: True)" not in flat, name
        assert "(default: False)" not in flat, name
        for piece in flat.split("(default")[1:]:   # no option says its default twice
            assert "default" not in piece.split(")")[0], (name, piece[:80])
    assert "0.5 %" in " ".join(texts["modes"].split())


def test_every_command_has_json():
    for name, text in _help_texts().items():
        assert "--json" in text, name


def test_export_json_and_xdmf_frequencies_read_by_meshio(tmp_path):
    import meshio

    out = tmp_path / "m.xdmf"
    rc, stdout, err = run(["export", "--out", str(out), "--modes", "4", "--json"])
    assert rc == 0, err
    report = json.loads(stdout)
    freqs = [m["frequency_hz"] for m in report["modes"]]
    assert report["files"] == [str(out), str(out.with_suffix(".h5"))]
    mesh = meshio.read(out)                 # meshio itself, not iwanfe's reader
    got = [float(mesh.point_data[f"frequency_hz_{k}"][0]) for k in range(1, 5)]
    assert got == freqs
    assert all(np.all(mesh.point_data[f"frequency_hz_{k}"] == got[k - 1]) for k in range(1, 5))
    # the frequencies are the model's own eigenvalues (independent eigen-solution)
    from cases.double_beam import model as db

    omega, _ = db.build_double_beam(db.DoubleBeamConfig()).modes(4)
    np.testing.assert_allclose(got, omega / (2 * np.pi), rtol=1e-6)
    assert report["modes"][3]["kind"] == "in-phase bending"


def test_negative_numbers_are_values():
    rc, out, _ = run(JOINT + ["--amplitude", "1e-3", "--json"])
    assert rc == 0
    assert json.loads(out)["amplitudes"][0]["amplitude"] == 1e-3
    refused(["joint", "--chi", "-1e-300", "--kt", "1.1e5", "--fs", "400", "--beta", "4",
             "--amplitude", "-inf"], "--amplitude -inf")


def test_failure_that_is_not_the_inputs_fault_is_one_line(monkeypatch):
    import cases.iwan_joint

    def broken(*args, **kwargs):
        raise RuntimeError("solver did not converge\nsecond line")

    monkeypatch.setattr(cases.iwan_joint, "joint_summary", broken)
    import cli.commands.joint as joint_cmd
    monkeypatch.setattr(joint_cmd, "joint_summary", broken)
    rc, out, err = run(JOINT)
    assert rc == 1 and err.count("\n") == 1
    assert "RuntimeError: solver did not converge" in err and "IWANFE_TRACEBACK" in err


def test_a_library_failure_is_internal_not_bad_input(capsys):
    """A ValueError raised inside scipy (an optimizer's inconsistent bounds, issue 19) or
    numpy's LinAlgError is the program's failure: exit 1, one line; the project's own
    ValueError and InputError stay exit 2."""
    import numpy as np
    from scipy.optimize import least_squares

    from cli.main import run_guarded
    from ident.errors import InputError

    def bad_bounds():
        least_squares(lambda x: x, [0.0], bounds=([1.0], [0.0]))

    def singular():
        np.linalg.cholesky(np.array([[1.0, 2.0], [2.0, 1.0]]))

    def own_check():      # the project's own check, raised in joints/iwan.py
        from joints.iwan import IwanParameters
        IwanParameters(chi=0.5, K_T=1e5, F_S=1.0, beta=1.0)

    def test_code_check():  # a ValueError raised outside the project's packages
        raise ValueError("not the project's")

    def input_error():
        raise InputError("levels.csv:3:2: not a number")

    assert run_guarded(bad_bounds) == 1
    assert "iwanfe: failed: ValueError" in capsys.readouterr().err
    assert run_guarded(singular) == 1
    assert "LinAlgError" in capsys.readouterr().err
    assert run_guarded(own_check) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("iwanfe: error: ") and "chi" in err and "\n" not in err
    assert run_guarded(test_code_check) == 1
    capsys.readouterr()
    assert run_guarded(input_error) == 2
