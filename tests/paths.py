"""Where the third-party test data live, found without asking git.

The shared folder holds robot files and real logs written by others (``models/``, ``ident/``;
see docs/development/tests-and-data.md). It is never copied into the repository: tests read it where it
is. In order: ``$BASEPARAMS_SHARED`` (when set, only that folder), ``../shared`` beside the
repository, then every parent folder of the repository for a ``shared`` folder holding
``models/``.

Tests that need it are marked ``@pytest.mark.shared`` (and ``@pytest.mark.chromium`` for a
system browser): without it they skip with one reason naming what is missing and how to
provide it; with ``BASEPARAMS_REQUIRE_ALL=1`` (what ``.ci/run`` sets) they fail instead, so
that nothing is skipped silently in CI.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def shared_root() -> Path | None:
    """The shared folder (holding ``models/`` and ``ident/``), or None when there is none."""
    env = os.environ.get("BASEPARAMS_SHARED")
    if env:
        candidates = [Path(env)]
    else:
        candidates = [REPO.parent / "shared"] + [p / "shared" for p in REPO.parents]
    for c in candidates:
        if (c / "models").is_dir():
            return c
    return None


ROOT = shared_root()
HAVE_SHARED = ROOT is not None
#: the shared robot files (a path that does not exist when the folder is absent)
SHARED = (ROOT if ROOT is not None else REPO.parent / "shared") / "models"
#: real identification logs recorded by others
IDENT = SHARED.parent / "ident"

#: ``BASEPARAMS_REQUIRE_ALL=1`` (``.ci/run``): a test that would skip for a missing resource fails instead
STRICT = os.environ.get("BASEPARAMS_REQUIRE_ALL", "") not in ("", "0")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

SHARED_REASON = ("needs the shared test data (../shared beside the repository, or BASEPARAMS_SHARED=DIR "
                 "holding models/ and ident/; see docs/development/tests-and-data.md)")
DOCS_TOOLS = ("sphinx", "myst_parser", "numpydoc", "sphinxarg", "furo")
HAVE_DOCS = all(importlib.util.find_spec(m) is not None for m in DOCS_TOOLS)
DOCS_REASON = ("needs the documentation tools (pip install -e '.[test]', which holds the docs extra: Sphinx, MyST, "
               "numpydoc, sphinx-argparse, furo)")

CHROMIUM_REASON = "needs a system Chromium for the HTML checks (Debian: apt-get install chromium)"
