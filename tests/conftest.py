"""Fixtures and test-session settings (helpers live in tests/helpers.py)."""
import os

import pytest
from hypothesis import settings

# property tests: no per-example deadline (the machine may be busy) and the same examples
# on every run (a failure reproduces); `--hypothesis-profile=explore` draws fresh random
# examples, 500 where a test sets no max_examples
settings.register_profile("suite", deadline=None, derandomize=True)
settings.register_profile("explore", deadline=None, max_examples=500)
settings.load_profile("suite")

# the suite keeps no FFTW wisdom in the user's cache (tests/test_wisdom.py sets its own file);
# a wisdom file named by the caller is respected. Worker processes inherit the setting.
os.environ.setdefault("CONTACTPIPE_FFTW_WISDOM", "off")


@pytest.fixture
def tmp_archive(tmp_path):
    return tmp_path / "run.nc"
