"""The ``iwanfe`` command: parse, call, print. No physics lives here."""
