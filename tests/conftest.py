"""Shared pytest options (``--update-golden`` regenerates the golden reference renders) and the
guard that fails any test during which the bindings caught a panic (``ndtrace.InternalError``):
a panic is a bug even when a test expects an error."""

import pytest

from ndtrace import _ndtrace


def pytest_addoption(parser):
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/*.png from the current renders (say why in the commit message)",
    )


@pytest.fixture(autouse=True)
def _no_caught_panic():
    before = _ndtrace.internal_errors()
    yield
    caught = _ndtrace.internal_errors() - before
    assert caught == 0, f"the bindings caught {caught} panic(s) during this test (an ndtrace bug)"
