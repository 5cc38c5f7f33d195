"""The guards around the compiled Jenkins kernel (joints/kernel.py).

Fallback: when the hand-written IR kernel cannot be used (its module does not import,
its IR no longer builds, its numbers disagree with the reference loop, all simulated
here), one KernelFallbackWarning is given and the compiled reference loop is used; the
truth is the plain reference loop run as Python, and for the solvers (which compile
the kernel into their own loops, in a fresh process) the numbers the IR kernel gives:
the two implementations sum in the same order, so the results must be the same bits.

numba cache: a cached solver loop must not run a stale kernel after the kernel's source
changes: a copy of the packages is edited (the kernel's force shifted by 1 N) and the
cached caller must be recompiled and give the shifted force.
"""
from __future__ import annotations

import importlib
import json
import os
import pkgutil
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from numba import njit, types
from numba.core.registry import CPUDispatcher
from numba.extending import intrinsic

import joints.kernel as kernel
from fe.aft import aft_joint_force
from fe.harmonic_balance import HBSettings, solve_hb
from fe.newmark import NewmarkSettings, integrate
from fe.reduction import JointBank, JointedSystem, reduced_basis
from joints.iwan import IwanParameters
from joints.jenkins import jenkins_update
from joints.kernel import KernelFallbackWarning
from joints.kernel_reference import KERNEL_STAMP, bank_update_reference

ROOT = Path(__file__).resolve().parents[1]
TESTS = Path(__file__).resolve().parent


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def small_bank(seed=1, n_joints=3, n_sliders=37):
    rng = np.random.default_rng(seed)
    k = rng.uniform(1.0, 2.0, (n_joints, n_sliders)) * 1e4
    phi = np.sort(rng.uniform(0.1, 1.0, (1, n_sliders)), axis=1) * 1e-5
    slip = rng.normal(0.0, 0.6e-5, n_joints)
    anchor = rng.normal(0.0, 0.4e-5, (n_joints, n_sliders))
    return slip, anchor, k, phi


def reference_update(slip, anchor, k, phi):
    """The plain reference loop, run as Python."""
    out = [np.empty_like(anchor), np.empty(slip.size), np.empty(slip.size)]
    bank_update_reference(slip, anchor, k, phi, *out)
    return out[1], out[2], out[0]


# ---------------------------------------------------------------- simulated failures


@intrinsic
def _vanished_ir_op(typingctx, x):
    """An intrinsic whose IR no longer builds (as after an llvmlite API change)."""

    def codegen(context, builder, signature, args):
        raise AttributeError("'IRBuilder' object has no attribute 'shuffle_vector' "
                             "(simulated llvmlite change)")

    return types.float64(x), codegen


@njit
def _kernel_whose_ir_fails(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
    force[0] = _vanished_ir_op(slip[0])


@njit
def _kernel_off_by_one_ulp(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
    kernel.reference_kernel(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent)
    force[-1] = np.nextafter(force[-1], np.inf)


def _module_gone(monkeypatch):
    monkeypatch.setitem(sys.modules, "joints.kernel_ir", None)      # ImportError


def _ir_fails(monkeypatch):
    monkeypatch.setattr(kernel, "_ir_kernel", lambda: _kernel_whose_ir_fails)


def _disagrees(monkeypatch):
    monkeypatch.setattr(kernel, "_ir_kernel", lambda: _kernel_off_by_one_ulp)


@pytest.fixture
def fresh_choice(monkeypatch):
    """The kernel is chosen anew inside the test; this process's choice (the IR
    kernel) is put back afterwards."""
    assert kernel.compiled_kernel() is not kernel.reference_kernel
    monkeypatch.delattr(kernel, "bank_update_kernel")
    return monkeypatch


@pytest.mark.parametrize("failure, reason", [
    (_module_gone, "joints.kernel_ir"),
    (_ir_fails, "shuffle_vector"),
    (_disagrees, "differ from the reference loop"),
])
def test_one_warning_then_the_reference_loop(fresh_choice, failure, reason):
    failure(fresh_choice)
    slip, anchor, k, phi = small_bank()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        chosen = kernel.compiled_kernel()
        F, T, new = jenkins_update(slip, anchor, k, phi)       # through the module attribute
        assert kernel.compiled_kernel() is chosen is kernel.bank_update_kernel
    fallbacks = [w for w in caught if issubclass(w.category, KernelFallbackWarning)]
    assert len(fallbacks) == 1, [str(w.message) for w in caught]
    assert issubclass(KernelFallbackWarning, RuntimeWarning)
    message = str(fallbacks[0].message)
    assert reason in message and "results stay correct" in message and "slower" in message
    assert chosen is kernel.reference_kernel
    for got, ref in zip((F, T, new), reference_update(slip, anchor, k, phi)):
        np.testing.assert_array_equal(bits(got), bits(ref))


def test_no_refcount_switch_is_optional(monkeypatch):
    """Without numba's private ``_nrt`` option (or the module that defines it) the IR
    kernel is compiled without it."""
    import numba.core.cpu

    from joints.kernel_ir import _no_refcount_option
    assert _no_refcount_option() == {"_nrt": False}
    monkeypatch.setattr(numba.core.cpu, "CPUTargetOptions", type("CPUTargetOptions", (), {}))
    assert _no_refcount_option() == {}
    monkeypatch.setitem(sys.modules, "numba.core.cpu", None)
    assert _no_refcount_option() == {}


def solver_outputs() -> dict:
    """Hex digests of a harmonic-balance solve (AFT march with Jacobian), the periodic
    Jenkins force (march without), a Newmark run and a Python-level update."""
    p = IwanParameters(chi=-0.5, K_T=1e6, F_S=100.0, beta=1.0)
    system = JointedSystem(M=np.diag([1.0, 2.0]), K=np.array([[3e5, -1e5], [-1e5, 1e5]]),
                           C=np.diag([20.0, 10.0]), G=np.array([[1.0, 0.0], [-1.0, 1.0]]),
                           K_T=np.array([p.K_T, p.K_T]))
    model = reduced_basis(system)
    bank = JointBank.from_iwan([p, p], 45)
    load = model.load(np.array([60.0, 0.0]))
    w = np.sqrt(p.K_T / 1.5)
    hb = solve_hb(model, bank, load, w, HBSettings(n_harmonics=5, n_time=64))
    theta = 2 * np.pi * np.arange(64) / 64
    slips = np.outer([1.3, 0.4], np.sin(theta)) * p.phi_max
    force, _ = aft_joint_force(slips, bank)
    dt = 2 * np.pi / w / 128
    run = integrate(model, bank, load, np.cos(w * dt * np.arange(400)),
                    NewmarkSettings(dt=dt))
    F, T, new = jenkins_update(*small_bank())
    return {name: bits(a).tobytes().hex() for name, a in (
        ("hb_slip", hb.slip.view(float)), ("aft_force", force), ("newmark_q", run.q),
        ("newmark_anchor", run.state.anchor), ("update", np.concatenate([F, T, new.ravel()])))}


_FALLBACK_SCRIPT = """
import json, sys, warnings
sys.path.insert(0, {tests!r})
import joints.kernel_ir as ir_module

class _IRBuilderGone:                      # llvmlite.ir as after an incompatible upgrade
    def __getattr__(self, name):
        raise AttributeError(f"module 'llvmlite.ir' has no attribute {{name!r}} (simulated)")

ir_module._ir = _IRBuilderGone()
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from test_kernel_fallback import solver_outputs
    out = solver_outputs()
import joints.kernel as kernel
out["kernel_is_reference"] = kernel.bank_update_kernel is kernel.reference_kernel
out["warnings"] = [str(w.message) for w in caught
                   if w.category.__name__ == "KernelFallbackWarning"]
print(json.dumps(out))
"""


def _run(script: str, tmp_path: Path, pythonpath: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(pythonpath), NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_solvers_on_the_fallback_give_the_same_bits(tmp_path):
    """A fresh process (empty numba cache) whose llvmlite IR builder is gone: one
    warning, the solvers' compiled loops run on the reference loop, and every result
    is bitwise what the IR kernel gives in this process."""
    ir_results = solver_outputs()
    assert kernel.bank_update_kernel is not kernel.reference_kernel
    got = _run(_FALLBACK_SCRIPT.format(tests=str(TESTS)), tmp_path, ROOT)
    assert got.pop("kernel_is_reference") is True
    messages = got.pop("warnings")
    assert len(messages) == 1 and "VectorType" in messages[0], messages
    assert got == ir_results


# ---------------------------------------------------------------- stale numba cache


_CALLER_SCRIPT = """
import json
import numpy as np
from fe.aft import _aft_march, aft_joint_force
from fe.reduction import JointBank

rng = np.random.default_rng(3)
bank = JointBank(rng.uniform(1, 2, (2, 29)) * 1e4, np.sort(rng.uniform(0.1, 1, (2, 29))) * 1e-5)
slips = np.outer([1.0, 0.3], np.sin(2 * np.pi * np.arange(32) / 32)) * 1e-5
force, _ = aft_joint_force(slips, bank)
print(json.dumps({"force": force.tolist(), "stamp": __import__("joints.kernel_reference",
                  fromlist=["x"]).KERNEL_STAMP, "hits": sum(_aft_march.stats.cache_hits.values()),
                  "misses": sum(_aft_march.stats.cache_misses.values())}))
"""

# a new version of the kernel, in both its implementations: every force 1 N higher
_KERNEL_EDITS = {
    "kernel_reference.py": ("        force[j] = sums[0] + f_tail\n",
                            "        force[j] = sums[0] + f_tail + 1.0\n"),
    "kernel_ir.py": ("            force[j] = f\n", "            force[j] = f + 1.0\n"),
}


def test_cached_caller_runs_the_edited_kernel(tmp_path):
    """The AFT march (fe/aft.py) compiles the kernel in and is cached on disk. After
    the kernel's files change (and fe/aft.py does not), the next process must not load
    the stale march: it recompiles it, and the forces are the edited kernel's."""
    src = tmp_path / "src"
    for package in ("joints", "fe"):
        shutil.copytree(ROOT / package, src / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    first = _run(_CALLER_SCRIPT, tmp_path, src)
    again = _run(_CALLER_SCRIPT, tmp_path, src)
    assert (first["misses"], again["hits"], again["misses"]) == (1, 1, 0)
    assert again["force"] == first["force"]
    for name, (old, new) in _KERNEL_EDITS.items():
        text = (src / "joints" / name).read_text()
        assert text.count(old) == 1, name
        (src / "joints" / name).write_text(text.replace(old, new))
    edited = _run(_CALLER_SCRIPT, tmp_path, src)
    assert edited["stamp"] != first["stamp"]
    assert (edited["hits"], edited["misses"]) == (0, 1)
    np.testing.assert_array_equal(np.array(edited["force"]), np.array(first["force"]) + 1.0)


def test_every_cached_caller_of_other_files_is_keyed_by_the_stamp():
    """Each compiled function in joints/ and fe/ cached on disk that calls code of
    another project module (the kernel) has KERNEL_STAMP in its closure, numba's cache
    key."""
    keyed = []
    for package in ("joints", "fe"):
        path = importlib.import_module(package).__path__
        for info in pkgutil.iter_modules(path, package + "."):
            module = importlib.import_module(info.name)
            for obj in vars(module).values():
                if not isinstance(obj, CPUDispatcher) or obj.py_func.__module__ != info.name \
                        or type(obj._cache).__name__ == "NullCache":       # not cached
                    continue
                py = obj.py_func
                others = [n for n in py.__code__.co_names if _is_other_project_code(
                    py.__globals__.get(n), info.name)]
                if others:
                    cells = [c.cell_contents for c in py.__closure__ or ()]
                    assert KERNEL_STAMP in cells, f"{info.name}.{py.__name__} calls {others}"
                    keyed.append(f"{info.name}.{py.__name__}")
    assert {"fe.aft._aft_march", "fe.newmark_march.march"} <= set(keyed)


def _is_other_project_code(value, module_name: str) -> bool:
    name = getattr(value, "__name__", "") if isinstance(value, type(np)) else \
        getattr(value, "__module__", "") if callable(value) else ""
    return name.split(".")[0] in ("joints", "fe") and name != module_name
