"""Any jointed FE model as a function of its parameters: omega^2 and zeta at every level.

:class:`FELevels` maps a parameter set (a dict, :data:`BASE_PARAMETERS` and the extensions
of :mod:`feloop.causes`) to the natural frequency and damping ratio of the measured mode at
every force level of a measured series, by the nonlinear FE simulation: the case's reduced
FE model (:func:`fe.reduction.reduced_basis` with static joint modes) with one continuous
four-parameter Iwan element per joint element, driven at each level's force, solved by
first-harmonic balance with the exact describing function at the phase resonance of the
mode's modal filter (:func:`fe.hb_resonance.resonance_levels`; many parameter sets at once,
:func:`fe.hb_batch.resonance_batch`): a few ms per campaign of 10 levels. A case supplies only :meth:`FELevels._build` (its FE model at a joint stiffness
K_T, calibrated as the case calibrates), e.g. :class:`feloop.case_levels.CaseLevels`.

Parameters (SI units; how each enters):

* ``chi``: the Iwan exponent, the same at every joint element.
* ``ln_dc1``: ln of the joints' modal quadrature stiffness at level 1, ``|kappa1| B~``
  (rad^2/s^2, paper eq. 30-32, 37): the joint strength in the variable the data determine.
  ``R~ = exp(ln_dc1) / ((|kappa1|/R) B~(chi))`` (:func:`inverse.iwan_modal.r_tilde`),
  ``B~`` from the linear-inverse joint slips at level 1 (force ``force_scale *
  excitation_1`` at resonance with the measured ``zeta_1``,
  :func:`inverse.fe_reference.joint_slip_at_resonance`). Node ``m`` carries the share
  ``w_m = k_m / K_T`` of R~ and of S, hence one ``phi_max`` for all (eq. 1 below).
* ``zeta_v``: viscous modal damping ratio of every basis vector (at its frequency after the
  ``f0_hz`` scaling below).
* ``f0_hz``: the stuck-joint natural frequency of the mode (Hz). The case calibrates its
  model for each K_T (:meth:`FELevels._build`); ``f0_hz`` then scales the whole stiffness
  (strips and joints) by ``(2 pi f0)^2 / omega_k^2``: the frequency moves, no mode shape.
* ``log10_kt``: the total stuck joint stiffness K_T (N/m); each value builds and calibrates
  its own model (cached).
* ``ln_phimax`` (optional): ``ln(phi_max / a_ref)``, ``a_ref`` the largest level-1
  linear-inverse joint slip: where macro-slip starts, in units of the slip. Absent, or
  above the largest ``phi_max`` the stuck stiffness allows (``beta = 0``, eq. 1 of
  :func:`phi_max_of`): ``beta = 0``; below it, ``1 + beta = (phi_max(beta=0) /
  phi_max)^(chi+1)`` (the Dirac share of the Iwan density). In this variable the onset
  level barely moves when chi or the joint strength change: the fits stay smooth.

The force is ``force_scale * excitation`` (N/V, an assumption: every omega^2 and zeta is
invariant to it, R~ scales as ``force_scale^-(chi+1)``). Rows whose abscissa is the
response amplitude (free decay, response control) are simulated at that amplitude
(``abscissa = response``: phase resonance with the force found,
:func:`fe.hb_response.response_levels`, the EPMC backbone read there), random rows by the
Rayleigh expectation over their response RMS (``abscissa = random``,
:func:`rayleigh_expectation`); ``ln_dc1`` then refers to the joint slips of the mode at
level 1's response amplitude (or RMS).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fe.hb_batch import resonance_batch
from fe.hb_response import response_levels
from inverse.update import SIMULATION_FAILURES
from inverse.random_amplitude import rayleigh_nodes
from feloop.joint_forms import IwanForm, JointForm, phi_max_of

__all__ = ["BASE_PARAMETERS", "phi_max_of", "LinearPart", "LevelPrediction", "FELevels",
           "Simulator", "abscissa_of", "rayleigh_expectation"]

#: The base model's parameters, in the order the fits use.
BASE_PARAMETERS = ("chi", "ln_dc1", "zeta_v", "f0_hz")
N_MODES = 40
#: How a level is simulated (class docstring).
ABSCISSAE = ("force", "response", "random")
#: Gauss-Laguerre nodes of a random level's Rayleigh expectation (1e-3 relative on the
#: joint's part of omega^2 and zeta in micro slip; :func:`inverse.random_amplitude.
#: rayleigh_nodes`).
RAYLEIGH_NODES = 8
#: Nodes lighter than this are dropped (the two beyond 4.9 RMS: weight 3.4e-6 together).
RAYLEIGH_MIN_WEIGHT = 1e-6


@dataclass
class LinearPart:
    """One calibrated linear jointed model (one K_T) in reduced modal form: ``red``
    (undamped Ritz basis), ``k`` (basis vector of the measured mode), ``omega_k`` (its
    stuck-joint frequency, rad/s), ``load`` (reduced unit drive), ``grip`` (m), ``shares``
    (w_m), ``gphi`` (joint slips of the mass-normalized mode), ``slips1`` (linear-inverse
    slips at level 1, m), ``lambda3`` (``int |phi_w|^3 dx``, kg^-3/2 m), ``phi_drive``
    (the mode at the drive DOF), ``response_row`` (the basis at the response DOF: ``x_resp
    = response_row . q``), ``drive_dof`` (physical), ``fe_mode`` (1-based, full model)."""

    K_T: float
    grip: float
    red: object
    k: int
    omega_k: float
    load: np.ndarray
    shares: np.ndarray
    gphi: np.ndarray
    slips1: np.ndarray
    lambda3: float
    phi_drive: float
    width: float
    response_row: np.ndarray | None = None
    drive_dof: int = -1
    fe_mode: int = 0

    @property
    def a_ref(self) -> float:
        """Largest level-1 linear-inverse joint slip (m): the unit of ``ln_phimax``."""
        return float(self.slips1.max())

    def B(self, chi: float) -> float:
        """B~ (paper eq. 37) at the level-1 linear-inverse slips (m^(chi+1)/kg)."""
        return float(np.sum(self.shares * self.gphi ** 2 * self.slips1 ** (chi + 1.0)))


@dataclass
class LevelPrediction:
    """Per level: ``omega2`` (rad^2/s^2), ``zeta``, ``frequency_hz``, largest joint slip over
    ``phi_max`` (``slip_over_phi_max``), the joint (``R``, ``phi_max``, ``F_S``, ``K_T``)
    the parameters made, the modal amplitude ``|q_k|`` (kg^1/2 m) and ``fallbacks``."""

    omega2: np.ndarray
    zeta: np.ndarray
    slip_over_phi_max: np.ndarray
    joint: dict
    modal_amplitude: np.ndarray | None = None
    fallbacks: list | None = None

    def fallback_lines(self, labels=None) -> list[str]:
        """A line per level (``labels``, default 1, 2, ...) whose steady state needed one."""
        fb = self.fallbacks or []
        return [f"level {lv}: {w}" for lv, w in zip(
            range(1, len(fb) + 1) if labels is None else labels, fb) if w]

    @property
    def frequency_hz(self) -> np.ndarray:
        return np.sqrt(self.omega2) / (2.0 * math.pi)


class FELevels:
    """The measured series' levels simulated by a case's FE model (module docstring); a
    case subclasses it with its :meth:`_build` and :attr:`default_kt`. ``excitation``
    (L,): of each level (V or N; ``force = force_scale * excitation``, N); ``run_order``
    (L,); ``omega2_1``, ``zeta_1``: measured omega^2 (rad^2/s^2) and zeta of the lowest
    level (the reference of ``ln_dc1``); ``force_scale``: N per excitation unit;
    ``abscissa``: ``force`` (each level at its force), ``response`` (at its response
    amplitude: response control, free decay) or ``random`` (the Rayleigh expectation at
    its response RMS), :data:`ABSCISSAE`; ``response_amplitude`` (L,): the held response
    amplitude or RMS at the case's response point, in any unit proportional to
    displacement (omega^2 and zeta are invariant to it; air drag and cubic causes read
    it as metres)."""

    #: K_T (N/m) when a parameter set has no ``log10_kt`` (assumed; set by the case)
    default_kt: float = math.nan
    #: what the model is, in reports
    label = "FE model"
    #: how the joints' law enters (:mod:`feloop.joint_forms`; set by the case)
    form: JointForm = IwanForm()
    #: another mode's model whose joints this one takes (:mod:`feloop.modes`)
    joint_source: "FELevels | None" = None

    def __init__(self, excitation, run_order, omega2_1: float, zeta_1: float,
                 force_scale: float = 1.0, n_modes: int = N_MODES, abscissa: str = "force",
                 response_amplitude=None):
        if abscissa not in ABSCISSAE:
            raise ValueError(f"abscissa must be one of {ABSCISSAE}, got {abscissa!r}")
        self.abscissa = abscissa
        self.response_amplitude = None if response_amplitude is None else \
            np.asarray(response_amplitude, dtype=float)
        if abscissa != "force" and (self.response_amplitude is None or np.any(
                ~(self.response_amplitude > 0)) or np.any(~np.isfinite(self.response_amplitude))):
            raise ValueError(f"the {abscissa} route needs a positive response_amplitude "
                             "at every level")
        self.excitation = np.asarray(excitation, dtype=float)
        self.run_order = np.asarray(run_order, dtype=float)
        self.omega_1 = math.sqrt(float(omega2_1))
        self.zeta_1 = float(zeta_1)
        self.force_scale = float(force_scale)
        self.n_modes = int(n_modes)
        self._linear: dict = {}
        self._warm: dict = {}
        self._joints: dict = {}

    def reset(self) -> None:
        """Forget the warm starts (results then depend on no earlier call)."""
        self._warm = {}
    @classmethod
    def from_data(cls, data, **kw) -> "FELevels":
        """From a one-mode :class:`ident.modal_data.MeasuredData` (levels sorted): the
        route its test calls for (:func:`abscissa_of`)."""
        return cls(data.excitation, data.run_order, data.omega2[0], data.zeta[0],
                   abscissa=abscissa_of(data), response_amplitude=data.response_amplitude,
                   **kw)

    @property
    def n_levels(self) -> int:
        return self.run_order.size

    def linear(self, K_T: float) -> LinearPart:
        """The calibrated reduced model at joint stiffness ``K_T`` (cached)."""
        key = round(math.log10(K_T), 9)
        if key not in self._linear:
            self._linear[key] = self._build(10.0 ** key)
        return self._linear[key]

    def _build(self, K_T: float) -> LinearPart:
        """The case's calibrated model at joint stiffness ``K_T`` (N/m), reduced by
        :func:`feloop.case_levels.linear_part`."""
        raise NotImplementedError

    def structure(self, lin: LinearPart) -> str:
        """How the structure of ``lin`` was calibrated, in reports."""
        return "structure as the case file gives or calibrates it"

    @property
    def base_parameters(self) -> tuple:
        """The base model's parameters, in the order the fits use: the form's joint
        parameters, ``zeta_v``, ``f0_hz`` (:data:`BASE_PARAMETERS` for Iwan joints)."""
        return self.form.names + BASE_PARAMETERS[2:]

    def joint(self, p: dict) -> dict:
        """The joints of parameter set ``p`` (:meth:`feloop.joint_forms.JointForm.joint`:
        ``K_T, F_S, slip_scale``, the law's own figures, ``chi, R, beta, phi_max`` for
        Iwan joints; ``params``, the same objects for the same joint parameters: the last
        256 kept) and ``linear``, the model they sit on (a :attr:`joint_source`'s joints)."""
        if self.joint_source is not None:
            j = self.joint_source.joint(p)
            return {**j, "linear": self.linear(j["K_T"])}
        lin = self.linear(10.0 ** float(p.get("log10_kt", math.log10(self.default_kt))))
        key = (round(math.log10(lin.K_T), 9),) + self.form.key(p)
        if key not in self._joints:
            self._joints = self._joints if len(self._joints) < 256 else {}
            self._joints[key] = {**self.form.joint(p, lin), "linear": lin}
        return dict(self._joints[key])

    def setup(self, p: dict, extension=None):
        """The first-harmonic balance inputs of parameter set ``p``: ``(joint, red,
        scale, forces, elements)`` (module docstring)."""
        j = self.joint(p)
        lin = j["linear"]
        alpha = (2.0 * math.pi * float(p["f0_hz"])) ** 2 / lin.omega_k ** 2
        # modal damping of the scaled basis: zeta_v of every (scaled) basis frequency
        red = replace(lin.red, C=np.diag(2.0 * float(p["zeta_v"]) * math.sqrt(alpha)
                                         * lin.red.omega))
        scale = np.full(self.n_levels, alpha)
        forces = self.force_scale * self.excitation
        elements = ()
        if extension is not None:
            scale, forces, elements = extension.apply(p, self, lin, scale, forces)
        return j, red, scale, forces, elements

    def predict(self, p: dict, extension=None) -> LevelPrediction:
        """omega^2 and zeta at every level for parameter set ``p`` (module docstring),
        from the last solution of the same K_T and ``extension`` (a
        :class:`feloop.causes.Extension`, its parameters in ``p``, or None)."""
        (pred,), (self._warm,) = self.predict_batch([p], extension)
        if isinstance(pred, Exception):
            raise pred
        return pred

    def predict_batch(self, ps, extension=None, warm=None) -> tuple:
        """:meth:`predict` of every set of ``ps`` from its warm starts ``warm[i]`` (dicts
        like the model's own, left as they are; None: the model's own): per set its
        LevelPrediction or the exception :meth:`predict` raises, and its warm starts after
        it; on the force route together, each as alone (:func:`fe.hb_batch.resonance_batch`)."""
        warm = [self._warm if w is None else w for w in (warm or [None] * len(ps))]
        out, new, todo = [None] * len(ps), list(warm), {}
        for i, p in enumerate(ps):
            try:
                s = self.setup(p, extension)
                todo.setdefault((round(math.log10(s[0]["K_T"]), 9),
                                 getattr(extension, "cause", None)), []).append((i, s))
            except SIMULATION_FAILURES as exc:
                out[i] = exc
        for key, items in todo.items():
            guesses = [warm[i].get(key) for i, _ in items]
            if self.abscissa == "force":
                res = resonance_batch([(red, j["params"], j["linear"].load, f, a, el) for
                                       _, (j, red, a, f, el) in items], items[0][1][0]["linear"].k,
                                      guesses)
            else:
                res = [self._response(s, g) for (_, s), g in zip(items, guesses)]
            for n, ((i, s), r) in enumerate(zip(items, res)):
                if isinstance(r, Exception) and key[1] is not None and guesses[n] is None \
                        and self.abscissa == "force":
                    r = self._from_base(ps[i], s, warm[i].get((key[0], None)), r)
                failed = isinstance(r, Exception)
                out[i] = r if failed else self._prediction(ps[i], s[0], r)
                new[i] = warm[i] if failed else {**warm[i], key: r}
        return out, new

    def _from_base(self, p: dict, s, base, error):
        """A cause's balance (set-up ``s`` of parameter set ``p``) that failed from the
        linear guess, again from the base model's solution of the same joints (``base``:
        the last one at that K_T, else solved here from the linear guess), its element
        coordinates ``Z = rows q`` added: the solution, or ``error`` when that fails too
        (the damped Newton of the larger balance can go astray from the linear guess in a
        Jenkins slider's deep slip where the base balance does not)."""
        j, red, a, f, el = s
        k = j["linear"].k
        if base is None:
            bj, bred, ba, bf, _ = self.setup({n: v for n, v in p.items()
                                              if n in self.base_parameters
                                              or n == "log10_kt"})
            base = resonance_batch([(bred, bj["params"], bj["linear"].load, bf, ba, ())], k)[0]
            if isinstance(base, Exception):
                return error
        rows = [np.atleast_2d(e.rows) for e in el]
        Z = base.q @ np.vstack(rows).T if rows else np.zeros((base.q.shape[0], 0), complex)
        guess = replace(base, element_harmonics=Z, element_amplitude=np.abs(Z))
        r = resonance_batch([(red, j["params"], j["linear"].load, f, a, el)], k, [guess])[0]
        return error if isinstance(r, Exception) else r

    def _response(self, s, guess):
        """The response or random route of set-up parameters ``s`` from ``guess``: the
        solution, or the exception it raised."""
        j, red, scale, forces, el = s
        lin, amp = j["linear"], self.response_amplitude
        if self.abscissa == "random":      # each level at the Rayleigh nodes
            factor = rayleigh_nodes(RAYLEIGH_NODES, RAYLEIGH_MIN_WEIGHT)[0]
            amp, scale = np.outer(amp, factor).ravel(), np.repeat(scale, factor.size)
        try:
            return response_levels(red, j["params"], lin.load, amp, lin.response_row, lin.k,
                                   scale=scale, elements=el, guess=guess)
        except SIMULATION_FAILURES as exc:
            return exc

    def _prediction(self, p: dict, j: dict, res) -> LevelPrediction:
        """The LevelPrediction of parameter set ``p`` (joints ``j``) from its solution."""
        lin, omega2, zeta = j["linear"], res.omega2, res.zeta
        slip, modal = res.slip_amplitude.max(axis=1), np.abs(res.q[:, lin.k])
        fallbacks = list(res.fallbacks)
        if self.abscissa == "random":
            weight = rayleigh_nodes(RAYLEIGH_NODES, RAYLEIGH_MIN_WEIGHT)[1]
            n = weight.size
            omega2, zeta = rayleigh_expectation(omega2.reshape(-1, n), zeta.reshape(-1, n),
                                                weight)
            slip, modal = slip.reshape(-1, n).max(axis=1), modal.reshape(-1, n) @ weight
            fallbacks = ["; ".join(f"at Rayleigh node {j + 1}: {w}" for j, w in
                                   enumerate(fallbacks[i:i + n]) if w)
                         for i in range(0, len(fallbacks), n)]
        joint = {k: v for k, v in j.items() if k not in ("params", "linear")}
        joint.update(grip=lin.grip, structure=self.structure(lin), fe_mode=lin.fe_mode,
                     stiffness_scale=(2 * math.pi * float(p["f0_hz"]) / lin.omega_k) ** 2)
        return LevelPrediction(omega2=omega2, zeta=zeta, slip_over_phi_max=slip / j["slip_scale"],
                               joint=joint, modal_amplitude=modal, fallbacks=fallbacks)


def abscissa_of(data) -> str:
    """The route of :class:`FELevels` a one-mode series calls for: ``random``
    for ``test = random``, ``response`` for a free decay or response control, else
    ``force``. One line (ValueError) for what no route models."""
    test = set(map(str, data.test))
    if len(test) > 1:
        raise ValueError(f"{data.source}: one test type per series, got {sorted(test)}")
    if test == {"random"}:
        return "random"
    if test == {"free-decay"} or data.response_controlled:
        return "response"
    if test == {"stepped-sine"} and np.all(data.control == "force"):
        return "force"
    raise ValueError(f"{data.source}: levels with mixed control "
                     f"({sorted(set(map(str, data.control)))}) have no FE route")


def rayleigh_expectation(omega2, zeta, weight):
    """The H1 (statistical-linearization) omega^2 and zeta of a random level from the
    sine values at its Rayleigh nodes (``(L, n)`` each, weights ``(n,)`` of
    :func:`inverse.random_amplitude.rayleigh_nodes`): the energy-weighted expectations
    of the modal in-phase stiffness ``omega^2`` and quadrature stiffness ``2 zeta
    omega^2`` (eq. 1 of :mod:`inverse.random_amplitude`)."""
    o2 = omega2 @ weight
    return o2, ((2.0 * zeta * omega2) @ weight) / (2.0 * o2)


@dataclass
class Simulator:
    """``simulate(values) -> (omega2, zeta)`` of :mod:`inverse.update` for an FE-levels
    model with an optional extension (picklable, for worker processes)."""

    fe: FELevels
    extension: object = None

    def __call__(self, values: dict):
        pred = self.fe.predict(values, self.extension)
        return pred.omega2, pred.zeta

    def batch(self, values: list, warm=None) -> tuple:
        """The batch of :mod:`inverse.update` (:meth:`FELevels.predict_batch`): per set
        ``(omega2, zeta)`` or the exception, and its warm starts after it."""
        preds, after = self.fe.predict_batch(values, self.extension, warm)
        return [p if isinstance(p, Exception) else (p.omega2, p.zeta) for p in preds], after

    def reset(self) -> None:
        self.fe.reset()
