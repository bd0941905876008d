"""Where the shared reference material and real data live: ``../shared`` next to the repository.

They are not part of rczone (their licences keep the data out); tests that need them skip when
the folder is absent. ``RCZONE_SHARED`` points elsewhere.
"""

from __future__ import annotations

import os
from pathlib import Path

SHARED = Path(os.environ.get("RCZONE_SHARED", Path(__file__).resolve().parents[2] / "shared"))
