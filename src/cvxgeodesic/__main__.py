"""``python -m cvxgeodesic``: the ``cvxgeodesic`` command (as ``python -m cvxgeodesic.cli``)."""

import sys

from .cli import main

sys.exit(main())
