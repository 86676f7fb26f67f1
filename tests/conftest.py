"""Shared pytest options: ``--update-golden`` regenerates the golden reference renders."""


def pytest_addoption(parser):
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/*.png from the current renders (say why in the commit message)",
    )
