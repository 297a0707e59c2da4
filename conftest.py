"""README.md's ``>>>`` examples (a doctest: ``pyproject.toml`` ``testpaths``) run in a scratch folder.

The README's loop writes files (``result.json``) in the current folder, as a user's session would;
under the tests that folder is a fresh temporary one, never the clone.
"""

import pytest


@pytest.fixture(autouse=True)
def _readme_runs_in_a_scratch_folder(request, tmp_path, monkeypatch):
    if type(request.node).__name__ == "DoctestItem" and request.node.path.name == "README.md":
        monkeypatch.chdir(tmp_path)
