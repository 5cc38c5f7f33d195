"""The wheel built by ``pip wheel .``: it holds every package and module of the source
tree and every other file below them (the shipped case files and their measured
tables), the build prints no setuptools warning about packages absent from the
configuration, it declares the project's dependencies, and, installed in a fresh
virtual environment (the dependencies taken from this one), its ``iwanfe`` command runs
from there: ``joint``, ``case check`` on every shipped case and the main job
(``loop --case double-beam``).

Truth: the source tree itself (every folder with ``__init__.py``, every module, the files
of ``cases/data``) and, for the installed command, the closed form of the four-parameter
Iwan joint (Segalman 2005: phi_max, R, S, micro-slip dissipation
``4 R A^(chi+3) / ((chi+2)(chi+3))``) with the in-phase first harmonic integrated by
quadrature over the sliders, each an elastic-perfectly-plastic element whose
first-harmonic stiffness is ``(theta - sin(2 theta)/2) / pi``, ``cos theta = 1 - 2 phi/A``
(Caughey 1960): an integral the code under test does not compute this way.

The pins (``constraints.txt``, what ``make install/run/test`` install and CI tests): every
dependency, test extra and build requirement of ``pyproject.toml`` has one ``==`` line, and
each pinned version lies in the range ``pyproject.toml`` allows (truth: the ranges as
``packaging`` reads them, PEP 440/508).
"""
from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("joints", "fe", "runs", "ident", "inverse", "viz", "synthetic", "casefile", "feloop",
            "cases", "cli")
# setuptools' message when a folder holding shipped files is not a configured package
ABSENT = re.compile(r"absent from the .?packages.? configuration|Package would be ignored")
# what the build does not need: environments, build products, caches, outputs
IGNORE = shutil.ignore_patterns(".git", ".venv", "build", "dist", "*.egg-info", "results",
                                "__pycache__", "*.pyc", ".pytest_cache", ".hypothesis")


def _build_deps_present() -> bool:
    """setuptools >= 77 (PEP 639 license field) and wheel importable here."""
    if importlib.util.find_spec("wheel") is None:
        return False
    try:
        import setuptools
    except ImportError:
        return False
    return int(setuptools.__version__.split(".")[0]) >= 77


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """Wheel built from a copy of the source tree (no stale build/ of an earlier build can
    leak into it); returns (path, build log)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=IGNORE)
    cmd = [sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-v",
           "-w", str(tmp / "dist")]
    if _build_deps_present():
        cmd.append("--no-build-isolation")
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-3000:]
    (path,) = (tmp / "dist").glob("iwanfe-*.whl")
    return path, log


def _source_files():
    """(modules, package folders, data files) of the packages, relative posix paths: a
    data file is any other file below a package (case files, their tables, READMEs),
    caches and compiled files aside."""
    modules, packages, data = set(), set(), set()
    for top in PACKAGES:
        for f in (ROOT / top).rglob("*"):
            if "__pycache__" in f.parts or not f.is_file() or f.suffix == ".pyc":
                continue
            rel = f.relative_to(ROOT).as_posix()
            if f.suffix == ".py":
                modules.add(rel)
                if f.name == "__init__.py":
                    packages.add(f.parent.relative_to(ROOT).as_posix())
            else:
                data.add(rel)
    return modules, packages, data


def test_source_tree_has_the_shipped_case_files():
    """The files the wheel test expects include the shipped cases (a glob that found
    nothing would make it vacuous)."""
    from cases.registry import CASE_FILES

    _, _, data = _source_files()
    for path in CASE_FILES.values():
        assert Path(path).relative_to(ROOT).as_posix() in data
    assert "cases/data/double_beam_measured.csv" in data


def test_wheel_holds_every_package_module_and_data_file(wheel):
    path, _ = wheel
    names = set(zipfile.ZipFile(path).namelist())
    modules, packages, data = _source_files()
    assert set(PACKAGES) <= packages and "cli/commands" in packages
    missing_packages = sorted(p for p in packages if f"{p}/__init__.py" not in names)
    assert not missing_packages, f"packages not in the wheel: {missing_packages}"
    missing_modules = sorted(modules - names)
    assert not missing_modules, f"modules not in the wheel: {missing_modules}"
    missing_data = sorted(data - names)
    assert not missing_data, f"data files not in the wheel: {missing_data}"
    # and nothing else: no module absent from the tree, no stray folder
    extra = sorted(n for n in names if not n.startswith("iwanfe-")
                   and n not in modules and n not in data)
    assert not extra, f"files in the wheel that the source tree does not ship: {extra}"


def test_build_prints_no_absent_package_warning(wheel):
    _, log = wheel
    hits = [line.strip() for line in log.splitlines() if ABSENT.search(line)]
    assert not hits, "setuptools warns:\n" + "\n".join(hits)


def _iwan_closed_form(chi, K_T, F_S, beta, A):
    """Segalman (2005) parameters and the micro-slip first harmonic (A < phi_max)."""
    c = beta + (chi + 1.0) / (chi + 2.0)
    phi_max = F_S * (1.0 + beta) / (K_T * c)
    R = F_S * (chi + 1.0) / (phi_max ** (chi + 2.0) * c)
    S = F_S * beta / (phi_max * c)
    D = 4.0 * R * A ** (chi + 3.0) / ((chi + 2.0) * (chi + 3.0))

    def lost(x):      # stiffness an element of slip force x A loses: 1 - (th - sin 2th/2)/pi
        th = np.arccos(1.0 - 2.0 * x)
        return 1.0 - (th - 0.5 * np.sin(2.0 * th)) / np.pi

    # sliders of slip force phi = x A < A slip, density R phi^chi: weight x^chi
    integral = quad(lost, 0.0, 1.0, weight="alg", wvar=(chi, 0.0), epsabs=0, epsrel=1e-13)[0]
    k_in = K_T - R * A ** (chi + 1.0) * integral
    return {"phi_max": phi_max, "R": R, "S": S, "dissipation_per_cycle": D,
            "stiffness_quadrature": D / (np.pi * A ** 2), "stiffness_in_phase": k_in}


def test_wheel_declares_the_projects_dependencies(wheel):
    """The wheel's ``Requires-Dist`` are the dependencies of ``pyproject.toml`` (the
    installed-wheel test below takes them from this environment, where ``make test``
    installed them from the same list)."""
    import tomllib

    path, _ = wheel
    z = zipfile.ZipFile(path)
    (meta,) = [n for n in z.namelist() if n.endswith(".dist-info/METADATA")]
    declared = {line.split(":", 1)[1].strip().replace(" ", "")
                for line in z.read(meta).decode().splitlines()
                if line.startswith("Requires-Dist:") and "extra ==" not in line}
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert declared == {d.replace(" ", "") for d in project["dependencies"]}


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory):
    """Fresh venv, ``pip install --no-deps <wheel>`` with this environment's
    site-packages appended to its path (a ``.pth`` line: the dependencies, not this
    checkout, whose editable hook is not run). Returns (venv, environment, a working
    folder outside the checkout)."""
    import site

    path, _ = wheel
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    tmp = tmp_path_factory.mktemp("iwanfe-venv")
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    (own,) = (venv / "lib").glob("python3*/site-packages")
    (own / "iwanfe-test-dependencies.pth").write_text("\n".join(site.getsitepackages()))
    inst = subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", str(path)],
                          env=env, capture_output=True, text=True, timeout=600)
    assert inst.returncode == 0, (inst.stdout + inst.stderr)[-3000:]
    work = tmp / "work"
    work.mkdir()
    return venv, env, work


def _iwanfe(installed, *args, timeout=300):
    venv, env, work = installed
    return subprocess.run([str(venv / "bin" / "iwanfe"), *args], cwd=work, env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.slow
def test_installed_wheel_runs_joint_command(installed):
    """The installed ``iwanfe joint`` against the closed form; imports resolve to the
    installed copy and the measured data file ships with it."""
    venv, env, work = installed
    chi, K_T, F_S, beta, A = -0.5, 1.1e5, 400.0, 4.0, 1e-3
    where = subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import cases.paper_data as p, fe; "
         "print(fe.__file__); print(p.DATA_FILE.is_file())"],
        cwd=work, env=env, capture_output=True, text=True, timeout=120, check=True)
    fe_file, data_ok = where.stdout.split()
    assert Path(fe_file).is_relative_to(venv), fe_file
    assert data_ok == "True"
    run = _iwanfe(installed, "joint", "--chi", str(chi), "--kt", str(K_T), "--fs", str(F_S),
                  "--beta", str(beta), "--amplitude", str(A), "--json")
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout)
    truth = _iwan_closed_form(chi, K_T, F_S, beta, A)
    for key in ("phi_max", "R", "S"):
        assert out[key] == pytest.approx(truth[key], rel=1e-12), key
    (amp,) = out["amplitudes"]
    assert amp["amplitude"] == A and amp["regime"] == "micro"
    for key in ("dissipation_per_cycle", "stiffness_quadrature"):
        assert amp[key] == pytest.approx(truth[key], rel=1e-12), key
    assert amp["stiffness_in_phase"] == pytest.approx(truth["stiffness_in_phase"], rel=1e-9)


@pytest.mark.slow
def test_installed_wheel_checks_every_shipped_case_and_runs_the_main_job(installed):
    """``iwanfe case check NAME`` on every shipped case file, from the installed copy
    (file and measured table inside the venv), and ``iwanfe loop --case double-beam``.
    Truth for the double beam's mass: two aluminium strips 350 x 50 x 1 mm at 2700
    kg/m^3 plus the point masses its TOML lists (2 g drive mass, three 1 g sensors)."""
    from cases.registry import CASE_FILES

    venv = installed[0]
    for name in CASE_FILES:
        run = _iwanfe(installed, "case", "check", "--json", name)
        assert run.returncode == 0, f"{name}: {run.stderr[-3000:]}"
        out = json.loads(run.stdout)
        assert Path(out["file"]).is_relative_to(venv), out["file"]
        assert Path(out["measured_data"]["file"]).is_relative_to(venv), out["measured_data"]
        if name == "double-beam":
            strips = 2 * 2700.0 * 0.350 * 0.050 * 0.001
            assert out["mass_kg"] == pytest.approx(strips + 0.002 + 3 * 0.001, rel=1e-12)
    run = _iwanfe(installed, "loop", "--case", "double-beam", "--out", "loop", "--json",
                  "--no-progress", timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    work = installed[2]
    assert (work / "loop" / "report.md").is_file() and (work / "loop" / "loop.json").is_file()
    assert json.loads((work / "loop" / "loop.json").read_text()) == json.loads(run.stdout)


PINS = ROOT / "constraints.txt"


def _pins(text: str) -> dict:
    """{canonical name: version} of a constraints file's ``==`` lines; any other
    non-comment line, or a name pinned twice, fails."""
    from packaging.utils import canonicalize_name

    pins, bad = {}, []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        name, sep, version = line.partition("==")
        key = canonicalize_name(name.strip())
        if (not sep or not version.strip() or key in pins
                or any(c in version for c in "<>=!~,;* ")):
            bad.append(line)
            continue
        pins[key] = version.strip()
    assert not bad, f"constraints lines that are not one exact pin each: {bad}"
    return pins


def _project_requirements(text: str):
    """(where, Requirement) of a pyproject.toml: dependencies, every optional extra and
    the build system's requirements."""
    import tomllib
    from packaging.requirements import Requirement

    meta = tomllib.loads(text)
    project = meta["project"]
    out = [("dependencies", Requirement(r)) for r in project["dependencies"]]
    for extra, reqs in project.get("optional-dependencies", {}).items():
        out += [(f"extra {extra}", Requirement(r)) for r in reqs]
    out += [("build-system", Requirement(r)) for r in meta["build-system"]["requires"]]
    return out


def _unpinned(pins, reqs) -> list:
    from packaging.utils import canonicalize_name

    return [f"{r.name} ({where})" for where, r in reqs if canonicalize_name(r.name) not in pins]


def _outside(pins, reqs) -> list:
    """Pins outside their requirement's range (pre-releases count as versions)."""
    from packaging.utils import canonicalize_name
    from packaging.version import Version

    out = []
    for where, r in reqs:
        version = pins.get(canonicalize_name(r.name))
        if version is not None and not r.specifier.contains(Version(version), prereleases=True):
            out.append(f"{r.name}=={version} outside {r} ({where})")
    return out


def _repository():
    return _pins(PINS.read_text()), _project_requirements((ROOT / "pyproject.toml").read_text())


def test_constraints_pin_every_requirement_of_pyproject():
    pins, reqs = _repository()
    assert {where for where, _ in reqs} >= {"dependencies", "extra test", "build-system"}
    assert not _unpinned(pins, reqs), f"not pinned in constraints.txt: {_unpinned(pins, reqs)}"
    assert "pip" in pins, "constraints.txt does not pin pip"


def test_pinned_versions_satisfy_pyproject_ranges():
    pins, reqs = _repository()
    assert not _outside(pins, reqs), "\n".join(_outside(pins, reqs))


def test_pin_checks_find_a_missing_pin_a_pin_outside_its_range_and_a_loose_line():
    """The checks on a made-up pair of files: a name not pinned, a version below its
    range, a name spelled differently (PEP 503: same package), a range instead of a pin."""
    project = """
[build-system]
requires = ["setuptools>=77"]
[project]
dependencies = ["numpy>=1.26", "sdypy-ema>=0.28"]
[project.optional-dependencies]
test = ["pytest>=7.4"]
"""
    reqs = _project_requirements(project)
    pins = _pins("# header\nnumpy==1.25.2\nsdypy_EMA==0.31.0  # comment\nsetuptools==84.2.1\n")
    assert _unpinned(pins, reqs) == ["pytest (extra test)"]
    assert _outside(pins, reqs) == ["numpy==1.25.2 outside numpy>=1.26 (dependencies)"]
    with pytest.raises(AssertionError, match="not one exact pin"):
        _pins("numpy>=1.26\n")
    with pytest.raises(AssertionError, match="not one exact pin"):
        _pins("numpy==2.4.6\nNumPy==2.4.5\n")
