"""The test tiers stay honest: every test marked slow by name (tests/conftest.py ``SLOW``) exists,
so a renamed test cannot silently move into the fast tier's list of exceptions and rot there."""

import re
from pathlib import Path

from tests.conftest import SLOW

HERE = Path(__file__).resolve().parent


def test_every_slow_entry_names_a_test_function():
    missing = []
    for file, names in SLOW.items():
        path = HERE / file
        text = path.read_text() if path.exists() else ""
        missing += [f"{file}::{name}" for name in names
                    if not re.search(rf"^def {re.escape(name)}\(", text, re.M)]
    assert not missing, f"tests/conftest.py SLOW names tests that do not exist: {missing}"


def test_the_slow_marker_is_registered():
    text = (HERE.parent / "pyproject.toml").read_text()
    assert re.search(r'^\s*"slow: ', text, re.M)
