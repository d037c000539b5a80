"""``python -m hapmotion``: the same as the ``hapmotion`` command."""

import sys

from .console import main

sys.exit(main())
