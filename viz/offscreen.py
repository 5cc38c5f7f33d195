"""Head-less OpenGL for VTK: choosing the off-screen window and probing that it works.

VTK >= 9.4 wheels load libGL/libEGL/libOSMesa at run time; :func:`select_offscreen_backend`
picks EGL or OSMesa before the first window is made when there is no display, and
:func:`probe_offscreen` tries a tiny render in a child process (a machine without working
GL libraries can crash instead of raising).
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

__all__ = ["RenderingUnavailableError", "select_offscreen_backend", "probe_offscreen"]


class RenderingUnavailableError(OSError):
    """No usable OpenGL library for off-screen rendering on this machine."""


def _loadable(*names: str) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def select_offscreen_backend() -> str | None:
    """Choose the VTK OpenGL window class for head-less rendering; returns its name.

    VTK >= 9.4 wheels load libGL/libEGL/libOSMesa at run time and try X first, which
    prints "bad X server connection" without a display. Without ``DISPLAY`` (or
    ``WAYLAND_DISPLAY``) this sets ``VTK_DEFAULT_OPENGL_WINDOW`` to
    ``vtkEGLRenderWindow`` (libEGL.so.1) or ``vtkOSOpenGLRenderWindow`` (libOSMesa), so
    no X attempt is made. A value already in the environment is respected. Returns
    ``None`` when a display is present (VTK's default X window is used).

    Raises
    ------
    RenderingUnavailableError
        No display and neither libEGL nor libOSMesa can be loaded.
    """
    chosen = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW")
    if chosen:
        return chosen
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    if _loadable("libEGL.so.1", "libEGL.so"):
        chosen = "vtkEGLRenderWindow"
    elif _loadable("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"):
        chosen = "vtkOSOpenGLRenderWindow"
    else:
        raise RenderingUnavailableError(
            "no display and no off-screen OpenGL library: install libegl1 libegl-mesa0 "
            "libgl1-mesa-dri (EGL) or libosmesa6 (OSMesa)"
        )
    os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = chosen
    return chosen


_PROBE = """
import sys
sys.path.insert(0, sys.argv[2])
from fe.interface import StripGeometry
from viz.render import render_mode_shape
import numpy as np
x = np.linspace(0.0, 1.0, 5)
r = render_mode_shape([StripGeometry(x, 0.0, 0.05, 0.1)],
                      [dict(u=0 * x, w=x**2, theta=2 * x)], sys.argv[1],
                      window_size=(160, 120), subdivisions=1)
"""


def probe_offscreen(timeout: float = 120.0,
                    env: Mapping[str, str] | None = None) -> tuple[bool, str]:
    """Try a tiny render in a child process; ``(ok, message)``.

    A machine without working GL libraries can crash the process (segmentation fault)
    instead of raising, so the attempt is isolated in ``subprocess.run``.
    """
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        png = Path(tmp) / "probe.png"
        try:
            proc = subprocess.run(
                [sys.executable, "-c", _PROBE, str(png), str(Path(__file__).resolve().parents[1])],
                capture_output=True, text=True,
                timeout=timeout, env=None if env is None else dict(env),
            )
        except subprocess.TimeoutExpired:
            return False, f"off-screen render probe timed out after {timeout:.0f} s"
        if proc.returncode != 0:
            lines = [ln for ln in (proc.stderr or "").strip().splitlines() if ln.strip()]
            tail = lines[-1] if lines else ""
            return False, f"off-screen render probe failed (exit {proc.returncode}) {tail}".strip()
        if not png.is_file() or png.stat().st_size == 0:
            return False, "off-screen render probe wrote no image"
    return True, "off-screen rendering works"
