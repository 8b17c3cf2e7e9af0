"""``python -m cvxgeodesic.cli``: the ``cvxgeodesic`` command."""

import sys

from . import main

sys.exit(main())
