"""Fixtures and test-session settings (helpers live in tests/helpers.py)."""
import pytest
from hypothesis import settings

# property tests: no per-example deadline (the machine may be busy) and the same examples
# on every run (a failure reproduces); `--hypothesis-profile=explore` draws fresh random
# examples, 500 where a test sets no max_examples
settings.register_profile("suite", deadline=None, derandomize=True)
settings.register_profile("explore", deadline=None, max_examples=500)
settings.load_profile("suite")


@pytest.fixture
def tmp_archive(tmp_path):
    return tmp_path / "run.nc"
