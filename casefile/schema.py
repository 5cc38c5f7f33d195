"""A case file (``docs/formats/case-file.md``) read into dataclasses and checked.

:func:`read_case_file` parses the TOML (``tomllib``), reads every table through
:class:`casefile.tables.Table` (one-line errors naming file, table and key; unknown
keys refused, ``x_`` keys ignored), checks the geometry rules of the spec (ranges inside
beams, stacked interfaces) and records the *kind* of every parameter: ``given`` (in the
file), ``default`` (with its source), ``fitted`` (a joint parameter left out: fitted by
``iwanfe update``, every law; a Bouc-Wen ``shape`` left out is assumed there);
``calibrated`` is set by :mod:`casefile.calibrate`.
A joint interface names its law and that law's keys (:mod:`casefile.laws`). SI units.

Beyond the spec: ``[damping] zeta`` (the stuck structure's viscous modal damping ratio,
used by the nonlinear model; default 0: the joints' own dissipation only), and a support's
``beam`` may be a list (one clamp holding several beams, as the double beam's).
"""
from __future__ import annotations

import dataclasses
import glob
import re
import tomllib
from pathlib import Path

from casefile.spec import (Beam, Calibrate, CaseFile, Interface, Material, Measured,
                                 PointMass, Section, Support)
from casefile.drive import read_drive
from casefile.laws import LAW_KEYS, LAWS, law_keys
from casefile.tables import CaseFileError, Table
from ident.units import HINT, suspect

TABLES = ("case", "material", "beam", "support", "interface", "mass", "drive", "sensor",
          "measured", "calibrate", "mesh", "damping")
ARRAYS = ("material", "beam", "support", "interface", "mass", "sensor")
STACK_TOLERANCE = 1e-6      # m, spec: stacked within 1e-6 m
DEFAULT_ELEMENT_SIZE = 0.005


def read_case_file(path) -> CaseFile:
    """Read and check a case file (module docstring); CaseFileError on any fault."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CaseFileError(f"{path}: no such case file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseFileError(f"{path}: cannot read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseFileError(f"{path}: not valid TOML: {exc}") from None
    return _Reader(path, doc).read()


class _Reader:
    def __init__(self, path: Path, doc: dict):
        self.path, self.doc, self.kinds, self.extra = path, doc, {}, {}
        for key, value in doc.items():
            if key.startswith("x_"):
                continue
            if key not in TABLES:
                raise CaseFileError(f"{path}: [{key}]: unknown table (known: {', '.join(TABLES)})")
            if key in ARRAYS and not isinstance(value, list):
                raise CaseFileError(f"{path}: [{key}]: must be an array of tables [[{key}]]")

    # -------------------------------------------------------------- helpers
    def tables(self, name: str) -> list[Table]:
        return [Table(self.path, name, d, i) for i, d in enumerate(self.doc.get(name, []))]

    def table(self, name: str) -> Table | None:
        return Table(self.path, name, self.doc[name]) if name in self.doc else None

    def given(self, t: Table, *keys, default_sources: dict | None = None):
        for key in keys:
            if t.has(key):
                self.kinds[f"{t.label}.{key}"] = ("given", "")
            elif default_sources and key in default_sources:
                self.kinds[f"{t.label}.{key}"] = ("default", default_sources[key])

    @staticmethod
    def _plausible(t: Table, key: str, value: float, quantity: str):
        """One line naming table and key when ``value`` looks like another unit
        (:mod:`ident.units`)."""
        why = suspect(quantity, value)
        if why:
            t.fail(key, f"{why} {HINT}")

    def close(self, t: Table):
        t.finish()
        if t.extra:
            self.extra[t.label] = t.extra

    # -------------------------------------------------------------- tables
    def read(self) -> CaseFile:
        case = self.table("case")
        if case is None:
            raise CaseFileError(f"{self.path}: [case]: missing (required)")
        name = case.text("name")
        if not re.fullmatch(r"[a-z0-9-]+", name):
            case.fail("name", f"must be made of a-z, 0-9 and '-', got {name!r}")
        description = case.text("description", required=False, default="")
        self.close(case)
        materials = self.materials()
        beams = self.beams({m.name for m in materials})
        by_name = {b.name: b for b in beams}
        supports = tuple(self.support(t, by_name) for t in self.tables("support"))
        interfaces = tuple(self.interface(t, by_name) for t in self.tables("interface"))
        masses = tuple(self.point(t, by_name, "mass") for t in self.tables("mass"))
        sensors = tuple(self.point(t, by_name, "sensor") for t in self.tables("sensor"))
        t = self.table("drive")
        drive = read_drive(self, t, by_name, supports) if t is not None else None
        element_size = self.mesh()
        zeta = self.damping()
        measured = self.measured()
        cf = CaseFile(path=self.path, name=name, description=description, materials=materials,
                      beams=beams, supports=supports, interfaces=interfaces, masses=masses,
                      sensors=sensors, drive=drive, measured=measured, calibrate=None,
                      element_size=element_size, zeta=zeta, kinds=self.kinds, extra=self.extra)
        return dataclasses.replace(cf, calibrate=self.calibrate(cf))

    def materials(self) -> tuple:
        out = []
        for t in self.tables("material"):
            m = Material(t.text("name"), t.number("E", lo=0, lo_open=True),
                         t.number("rho", lo=0, lo_open=True))
            if m.name in {o.name for o in out}:
                t.fail("name", f"material {m.name!r} defined twice")
            self.given(t, "E", "rho")
            self._plausible(t, "E", m.E, "E")
            self._plausible(t, "rho", m.rho, "rho")
            self.close(t)
            out.append(m)
        if not out:
            raise CaseFileError(f"{self.path}: [[material]]: missing (at least one)")
        return tuple(out)

    def beams(self, material_names: set) -> tuple:
        out = []
        for t in self.tables("beam"):
            name = t.text("name")
            if name in {b.name for b in out}:
                t.fail("name", f"beam {name!r} defined twice")
            material = t.text("material")
            if material not in material_names:
                t.fail("material", f"no [[material]] named {material!r}")
            x = t.span("x", point_ok=False)
            width = t.number("width", lo=0, lo_open=True)
            thickness = t.number("thickness", lo=0, lo_open=True)
            z = t.number("z", required=False, default=0.0)
            self.given(t, "x", "width", "thickness", "z",
                       default_sources={"z": "spec: centroid height 0 when left out"})
            self._plausible(t, "x", x[1] - x[0], "length")
            self._plausible(t, "width", width, "section")
            self._plausible(t, "thickness", thickness, "section")
            sections = []
            raw = t.raw("section", required=False) or []
            if not isinstance(raw, list):
                t.fail("section", "must be an array of tables [[beam.section]]")
            for j, d in enumerate(raw):
                s = Table(self.path, f"beam.{t.index}.section", d, j)
                sx = s.span("x", point_ok=False)
                if not (x[0] <= sx[0] and sx[1] <= x[1]):
                    s.fail("x", f"{list(sx)} lies outside beam {name!r} {list(x)}")
                sections.append(Section(sx, s.number("thickness", lo=0, lo_open=True),
                                        s.number("z", required=False, default=z),
                                        s.number("width", required=False, default=width,
                                                 lo=0, lo_open=True)))
                self.given(s, "x", "thickness", "z", "width", default_sources={
                    "z": "the beam's z", "width": "the beam's width"})
                self.close(s)
            self.close(t)
            out.append(Beam(name, material, x, width, thickness, z, tuple(sections)))
        if not out:
            raise CaseFileError(f"{self.path}: [[beam]]: missing (at least one)")
        return tuple(out)

    def on_beam(self, t: Table, by_name: dict, key: str = "beam") -> "Beam":
        name = t.text(key)
        if name not in by_name:
            t.fail(key, f"no [[beam]] named {name!r} (beams: {', '.join(by_name)})")
        return by_name[name]

    def inside(self, t: Table, beam: Beam, x: tuple, key: str = "x"):
        if not (beam.x[0] - 1e-12 <= x[0] and x[1] <= beam.x[1] + 1e-12):
            t.fail(key, f"{x[0]:g}..{x[1]:g} lies outside beam {beam.name!r} "
                        f"({beam.x[0]:g}..{beam.x[1]:g} m)")

    def support(self, t: Table, by_name: dict) -> Support:
        names = t.data.get("beam")
        if isinstance(names, list):      # one support holding several beams (a clamp)
            t.strings("beam")
            if not names or any(n not in by_name for n in names):
                t.fail("beam", f"must name beams among {', '.join(by_name)}, got {names!r}")
            beams = [by_name[n] for n in names]
        else:
            beams = [self.on_beam(t, by_name)]
        kind = t.text("kind", required=False, choices=("clamp", "pin", "spring", "free"),
                      default="free")
        x = t.span("x")
        for b in beams:
            self.inside(t, b, x)
        ks = {k: t.number(k, required=False, default=0.0, lo=0) for k in ("k_u", "k_w", "k_theta")}
        if kind != "spring" and any(t.has(k) for k in ks):
            t.fail(next(k for k in ks if t.has(k)), f"only a spring support has stiffnesses "
                                                     f"(kind is {kind!r})")
        if kind == "spring" and not any(ks.values()):
            t.fail("k_w", "a spring support needs k_u, k_w or k_theta > 0")
        if kind in ("pin", "spring") and x[0] != x[1]:
            t.fail("x", f"a {kind} acts at one point: x = [x0, x0], got {list(x)}")
        self.given(t, "x", "k_u", "k_w", "k_theta", "kind",
                   default_sources={"kind": "spec: free when left out"})
        self.close(t)
        return Support(tuple(b.name for b in beams), kind, x, **ks)

    def interface(self, t: Table, by_name: dict) -> Interface:
        names = t.strings("beams", length=2)
        if names[0] == names[1]:
            t.fail("beams", "must name two different beams (bottom, top)")
        for n in names:
            if n not in by_name:
                t.fail("beams", f"no [[beam]] named {n!r}")
        lo, up = by_name[names[0]], by_name[names[1]]
        x = t.span("x", point_ok=False)
        self.inside(t, lo, x)
        self.inside(t, up, x)
        xm = 0.5 * (x[0] + x[1])
        h_lo, z_lo, _ = lo.section_at(xm)
        h_up, z_up, _ = up.section_at(xm)
        top, bottom = z_lo + 0.5 * h_lo, z_up - 0.5 * h_up
        if abs(top - bottom) > STACK_TOLERANCE:
            t.fail("beams", f"{up.name!r} does not lie on {lo.name!r} at x = {xm:g} m: top of "
                            f"{lo.name!r} at z = {top:g}, bottom of {up.name!r} at z = "
                            f"{bottom:g} (stacked within {STACK_TOLERANCE:g} m)")
        normal = t.text("normal", choices=("tied", "open"))
        tangential = t.text("tangential", choices=("joint", "tied", "free"))
        joints_at = joint_elements = law = kt = None
        params = {}
        if tangential == "joint":
            if t.has("joints_at") == t.has("joint_elements"):
                t.fail("joints_at", "a joint interface needs joints_at or joint_elements "
                                    "(one of them)")
            if t.has("joints_at"):
                joints_at = tuple(sorted(t.numbers("joints_at")))
                if any(not (x[0] <= v <= x[1]) for v in joints_at):
                    t.fail("joints_at", f"joints must lie in x = {list(x)}")
                if len(set(joints_at)) != len(joints_at):
                    t.fail("joints_at", "two joints at the same x")
            else:
                joint_elements = t.integer("joint_elements", lo=2)
            law, kt, params = self.joint_law(t)
        else:
            for k in ("joints_at", "joint_elements", "law", "kt", *LAW_KEYS):
                if t.has(k):
                    t.fail(k, f"only a joint interface (tangential = 'joint') has {k}")
        self.given(t, "x")
        self.close(t)
        return Interface((lo.name, up.name), x, normal, tangential, joints_at, joint_elements,
                         law, kt, **params)

    def joint_law(self, t: Table) -> tuple[str, float, dict]:
        """``(law, kt, its own keys)`` of a joint interface (:mod:`casefile.laws`): a key
        of another law is one line naming it; a key left out is ``fitted``."""
        law = t.text("law", choices=tuple(LAWS))
        own = law_keys(law)
        for k in LAW_KEYS:
            if k not in own and t.has(k):
                others = ", ".join(n for n in LAWS if k in law_keys(n))
                t.fail(k, f"not a key of law {law!r} (its keys: kt, {', '.join(own)}; "
                          f"{k} belongs to {others})")
        kt = t.number("kt", lo=0, lo_open=True)
        params = {k.name: k.read(t) for k in LAWS[law]}
        self.given(t, "kt", "joints_at", "joint_elements")
        for k in own:      # a Bouc-Wen shape left out: update assumes it (joint_forms)
            left = ("assumed", "0.5 by iwanfe update (fitted nowhere)") \
                if (law, k) == ("bouc-wen", "shape") else ("fitted", "by iwanfe update")
            self.kinds[f"{t.label}.{k}"] = ("given", "") if t.has(k) else left
        return law, kt, params

    def point(self, t: Table, by_name: dict, kind: str) -> PointMass:
        beam = self.on_beam(t, by_name)
        x = t.number("x")
        self.inside(t, beam, (x, x))
        if kind == "drive":
            mass, label = 0.0, "drive"
        else:
            label = t.text("label", required=False, default=f"{kind} {t.index}")
            mass = t.number("mass", required=(kind == "mass"), default=0.0, lo=0)
        self.given(t, "x", "mass", default_sources={
            "mass": "spec: 0.0, a non-contact sensor"} if kind == "sensor" else None)
        self.close(t)
        return PointMass(beam.name, x, mass, label)

    def mesh(self) -> float:
        t = self.table("mesh")
        if t is None:
            self.kinds["mesh.element_size"] = ("default", f"spec: {DEFAULT_ELEMENT_SIZE} m")
            return DEFAULT_ELEMENT_SIZE
        h = t.number("element_size", required=False, default=DEFAULT_ELEMENT_SIZE,
                     lo=0, lo_open=True)
        self.given(t, "element_size",
                   default_sources={"element_size": f"spec: {DEFAULT_ELEMENT_SIZE} m"})
        self.close(t)
        return h

    def damping(self) -> float:
        t = self.table("damping")
        if t is None:
            self.kinds["damping.zeta"] = ("default", "0: the joints' dissipation only")
            return 0.0
        zeta = t.number("zeta", lo=0, hi=1, hi_open=True)
        self.given(t, "zeta")
        self.close(t)
        return zeta

    def measured(self) -> Measured | None:
        t = self.table("measured")
        if t is None:
            return None
        raw = t.raw("file", False)
        names = [raw] if isinstance(raw, str) else raw if raw is not None else []
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            t.fail("file", f"must be a path, a glob pattern or a list of paths, got {raw!r}")
        files = []
        for name in names:     # relative to this file; a pattern such as level_*.csv
            found = sorted(self.path.parent.glob(name)) if glob.has_magic(name) else \
                [self.path.parent / name]
            if not found or not found[0].exists():
                t.fail("file", f"no such file: {(self.path.parent / name).resolve()}")
            files += [f.resolve() for f in found]
        mode = t.integer("mode", required=False, lo=1)
        f = t.number("frequency_hz", required=False, lo=0, lo_open=True)
        if mode is None and f is None:
            t.fail("mode", "give mode (bending-mode order) or frequency_hz")
        self.given(t, "mode", "frequency_hz")
        self.close(t)
        return Measured(tuple(files), mode, f)

    def calibrate(self, cf: CaseFile) -> Calibrate | None:
        t = self.table("calibrate")
        if t is None:
            return None
        params = t.strings("parameters")
        freqs = t.numbers("frequencies_hz", lo=1e-300)
        if not params:
            t.fail("parameters", "must name at least one parameter")
        if len(freqs) < len(params):
            t.fail("frequencies_hz", f"{len(params)} parameters need at least as many "
                                     f"frequencies, got {len(freqs)}")
        from casefile.parameters import check_parameter

        for p in params:
            reason = check_parameter(cf, p)
            if reason:
                t.fail("parameters", f"{p!r}: {reason}")
            self.kinds[p] = ("calibrated", "to " + ", ".join(f"{f:g}" for f in freqs) + " Hz")
        self.close(t)
        return Calibrate(tuple(params), tuple(freqs))
