"""Test set-up: the helper modules on ``sys.path``, and tests that need outside resources.

``@pytest.mark.shared`` marks a test that reads the third-party data of the shared folder
(``paths.py``); ``@pytest.mark.chromium`` one that renders pages in a system Chromium;
``@pytest.mark.docs`` one that builds the documentation site (the ``docs`` extra). Where
the resource is missing the test skips with one reason naming it and how to provide it, and
the run ends with a count per resource. ``BASEPARAMS_REQUIRE_ALL=1`` (set by ``.ci/run``,
which has them all) turns those skips into failures: nothing is skipped silently in CI.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))

from paths import CHROMIUM, CHROMIUM_REASON, DOCS_REASON, HAVE_DOCS, HAVE_SHARED, SHARED_REASON, STRICT  # noqa: E402

MISSING = {"shared": (HAVE_SHARED, SHARED_REASON), "chromium": (CHROMIUM is not None, CHROMIUM_REASON),
           "docs": (HAVE_DOCS, DOCS_REASON)}
_skipped: dict[str, int] = {}


def pytest_configure(config):
    config.addinivalue_line("markers", "shared: reads the shared third-party test data (skips without it)")
    config.addinivalue_line("markers", "chromium: renders pages in a system Chromium (skips without it)")
    config.addinivalue_line("markers", "docs: builds the documentation site (skips without the docs extra)")


def pytest_runtest_setup(item):
    for name, (present, reason) in MISSING.items():
        if present or item.get_closest_marker(name) is None:
            continue
        if STRICT:
            pytest.fail(f"BASEPARAMS_REQUIRE_ALL is set but this test {reason}", pytrace=False)
        _skipped[name] = _skipped.get(name, 0) + 1
        pytest.skip(reason)


def pytest_terminal_summary(terminalreporter):
    for name, count in _skipped.items():
        terminalreporter.write_line(f"baseparams: {count} test(s) skipped: {MISSING[name][1]}", yellow=True)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
