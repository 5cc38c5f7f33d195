"""One module per ``iwanfe`` sub-command. Each defines ``register(subparsers)``, which
adds its parser and sets ``func`` to a callable ``run(args) -> int``."""
