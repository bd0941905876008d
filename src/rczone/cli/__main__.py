"""``python -m rczone.cli``: the same as the ``rczone`` command."""

import sys

from rczone.cli import run

sys.exit(run())
