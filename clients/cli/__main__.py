"""``python -m clients.cli`` is the ``thrustshape`` command."""

import sys

from clients.cli import main

sys.exit(main())
