"""Optional dependencies: one helper that imports one and, when it is missing, names the extra
of ``pyproject.toml`` that installs it::

    meshio = need("meshio", extra="mesh", what="reading .obj mesh files")
    # ImportError: reading .obj mesh files needs meshio: pip install "ndtrace[mesh]"

Callers that report errors as another type (the CLI's usage errors, the ValueError of
``animate``'s output checks) catch the ImportError and re-raise its message.
"""

from __future__ import annotations

import sys
from types import ModuleType

__all__ = ["need", "install"]


def install(extra: str) -> str:
    """The command that installs ndtrace's ``extra``: ``pip install "ndtrace[extra]"``."""
    return f'pip install "ndtrace[{extra}]"'


def need(module: str, *, extra: str, what: str, package: str | None = None) -> ModuleType:
    """``module`` imported, or ImportError ``{what} needs {package}: pip install
    "ndtrace[{extra}]"`` (``package``: the name to show, default ``module``)."""
    try:
        # Through builtins.__import__, which tests replace to hide an installed package.
        __import__(module)
    except ImportError:
        raise ImportError(f"{what} needs {package or module}: {install(extra)}") from None
    return sys.modules[module]
