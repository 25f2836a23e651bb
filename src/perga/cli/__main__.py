"""``python -m perga.cli``: the ``perga`` command."""

import sys

from perga.cli import main

sys.exit(main())
