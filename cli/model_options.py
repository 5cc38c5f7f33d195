"""``--model FILE``: the FE commands on the model ``iwanfe update`` fitted
(``DIR/updated_model.json``) instead of the case file's own values
(:mod:`feloop.updated_model`)::

    add_model_argument(parser)
    case = case_of(args)          # resolve_case(args.case, model=args.model)

``uncertainty`` and ``loop`` take the model in the FE-levels parametrization instead
(:mod:`feloop.given_model`: the nominal of the Monte Carlo; the model checked at every
level beside the loop's update), with their own ``help``.
"""
from __future__ import annotations

__all__ = ["add_model_argument", "case_of"]


#: ``--model`` of the FE commands that build the case's FE model from it
FE_MODEL_HELP = ("the model iwanfe update fitted on this case: its joints (chi, F_S, beta, "
                 "K_T), damping and stiffness scale replace the case file's (a case file "
                 "that leaves its joints to be fitted needs it for nonlinear commands)")


def add_model_argument(parser, help: str = FE_MODEL_HELP) -> None:
    """Add ``--model FILE`` (``help``: what the command does with it)."""
    parser.add_argument("--model", metavar="DIR/updated_model.json", default=None,
                        help=help)


def case_of(args):
    """The case of ``args.case``, updated by ``args.model`` when given."""
    from cases.registry import resolve_case

    return resolve_case(args.case, model=getattr(args, "model", None))
