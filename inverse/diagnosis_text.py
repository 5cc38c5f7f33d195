"""Plain-words wording of a diagnosis (the ``summary`` of :func:`inverse.diagnose.diagnose`)."""
from __future__ import annotations

from inverse.diagnosis_models import Observations


def describe_cause(cause: str, params: dict, gain: float, obs: Observations) -> str:
    """One paragraph in plain words naming the cause."""
    chi = params.get("chi", float("nan"))
    if cause == "none":
        return (f"The base model (one micro-slip Iwan joint, slip amplitude proportional "
                f"to the excitation, chi = {chi:.3f}) explains the frequency drop and the "
                f"damping growth together within the noise: no extension earned its "
                f"extra parameters.")
    text = {
        "macro-slip": (
            f"At the top levels the joint leaves micro-slip: the frequency drop and the "
            f"damping growth bend away from the power law, as when the slip amplitude "
            f"passes phi_max (top level at {params.get('x_top', float('nan')):.2f} "
            f"phi_max, Dirac weight beta = {params.get('beta', float('nan')):.2g})."),
        "nonproportional-amplitude": (
            f"The joint amplitude does not grow in proportion to the excitation: the "
            f"frequency drop, the damping growth and the measured response amplitude "
            f"all say that at the top level it is "
            f"{100 * params.get('amplitude_shortfall_top', float('nan')):.1f} % short of "
            f"proportional (exciter force drop-out or damping growth)."),
        "geometric-hardening": (
            f"A hardening stiffness that grows with the amplitude squared lifts the "
            f"natural frequency against the Iwan softening (omega^2 + "
            f"{params.get('h_top', float('nan')):.3g} rad^2/s^2 at the top level); the "
            f"damping is unaffected."),
        "thermal-drift": (
            f"The natural frequency drifts with the order in which the levels were run "
            f"({params.get('d', float('nan')):.3g} rad^2/s^2 per run), not with the "
            f"amplitude; the damping is unaffected."),
        "quadratic-damping": (
            f"The damping grows faster than the Iwan law tied to the frequency drop "
            f"allows: an extra damping proportional to the amplitude (air, "
            f"viscoelastic glue) adds {params.get('q_top', float('nan')):.3g} to zeta at "
            f"the top level."),
    }[cause]
    return (f"{text} Extending the base model this way cuts the cross-validated "
            f"prediction error by a factor {gain:.2f} (chi = {chi:.3f}).")
