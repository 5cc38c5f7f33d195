"""A virtual stepped-sine test of a case file's jointed model (any joint law of the file,
:mod:`casefile.laws`): the phase resonance of one mode at every force level through the
law's exact describing function
(:func:`fe.hb_resonance.resonance_levels`, first harmonic), written as a measured-data
table labelled as simulated (``x_source = simulated``). SI units.

Run ``python -m cases.virtual_test CASE.toml OUT.csv`` to write a table.
"""
from __future__ import annotations

import sys

import numpy as np

from fe.hb_resonance import resonance_levels
from ident.modal_data import MeasuredData


def campaign(nc, forces=None):
    """:class:`fe.hb_resonance.ResonanceLevels` of mode ``nc.mode`` at ``forces`` (N,
    default ``nc.force``) on the drive point of ``nc`` (:class:`NonlinearCase`)."""
    nc.require_point_drive("the virtual stepped-sine test (cases.virtual_test)")
    forces = nc.force if forces is None else np.asarray(forces, dtype=float)
    return resonance_levels(nc.model, nc.joints, nc.load(), forces, nc.mode - 1)


def simulated_table(nc, forces=None) -> MeasuredData:
    """The campaign as a measured-data table (mode = the case's mode, every row labelled
    ``x_source = simulated``)."""
    forces = nc.force if forces is None else np.asarray(forces, dtype=float)
    res = campaign(nc, forces)
    n = forces.size
    return MeasuredData(level=np.arange(1, n + 1), excitation=forces, omega2=res.omega2,
                        zeta=res.zeta, mode=np.full(n, nc.mode), run_order=np.arange(1, n + 1),
                        extra={"x_source": np.full(n, "simulated")})


def main(argv=None) -> int:
    from cases.registry import resolve_case
    from ident.measured import write_measured

    case_name, out = (argv if argv is not None else sys.argv[1:])[:2]
    try:
        table = simulated_table(resolve_case(case_name).nonlinear_model())
    except ValueError as exc:       # a bad file, a base drive: one line, status 2
        print(f"cases.virtual_test: error: {exc}", file=sys.stderr)
        return 2
    write_measured(out, table)
    print(f"wrote {out} (simulated)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
