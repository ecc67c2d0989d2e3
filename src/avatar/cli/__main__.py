"""``python -m avatar.cli``: the ``avatar`` command."""

import sys

from avatar.cli import main

sys.exit(main())
