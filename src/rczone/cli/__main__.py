"""``python -m rczone.cli``: the same as the ``rczone`` command."""

import sys

from rczone.cli.main import main

sys.exit(main())
