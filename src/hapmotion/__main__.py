"""``python -m hapmotion``: the same as the ``hapmotion`` command."""

import sys

from .cli import main

sys.exit(main())
