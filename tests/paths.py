"""Where the shared model files live, found without asking git.

In order: ``$BASEPARAMS_SHARED`` (a folder holding ``models/``), ``../shared`` beside the
repository, then every parent folder of the repository for a ``shared/models`` folder.
"""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def shared_models() -> Path:
    """The ``models`` folder of the shared files (the first candidate if none exists)."""
    candidates = [Path(os.environ["BASEPARAMS_SHARED"])] if os.environ.get("BASEPARAMS_SHARED") else []
    candidates.append(REPO.parent / "shared")
    candidates += [p / "shared" for p in REPO.parents]
    for c in candidates:
        if (c / "models").is_dir():
            return c / "models"
    return candidates[0] / "models"


SHARED = shared_models()
