"""The pages' ``>>>`` examples (doctests: ``pyproject.toml`` ``testpaths`` and ``--doctest-glob``).

Each page's examples run in a fresh scratch folder, as a user's session would in theirs: the loop
writes files (``result.json``) in the current folder, never into the clone. A page whose examples
take more than a few seconds starts with the MyST comment line ``% doctest: slow`` and is then
marked slow (left out of the default run, run by CI) like any slow test.
"""

import pytest

SLOW = "% doctest: slow"


def _is_page_doctest(item) -> bool:
    return type(item).__name__ == "DoctestItem" and item.path.suffix == ".md"


@pytest.hookimpl(tryfirst=True)  # before ``-m 'not slow'`` deselects
def pytest_collection_modifyitems(items):
    """Mark slow the doctests of the pages that say so on their first line."""
    for item in items:
        if _is_page_doctest(item) and item.path.read_text(encoding="utf-8").startswith(SLOW):
            item.add_marker(pytest.mark.slow)


@pytest.fixture(autouse=True)
def _examples_run_in_a_scratch_folder(request, tmp_path, monkeypatch):
    if _is_page_doctest(request.node):
        monkeypatch.chdir(tmp_path)
