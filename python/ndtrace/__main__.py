"""``python -m ndtrace``: the ``ndtrace`` command line (see :mod:`ndtrace.cli`)."""

from .cli import main

if __name__ == "__main__":
    main()
